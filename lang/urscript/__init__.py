"""Universal Robots URScript: the front end (grammar, parser, checker, function table)."""
