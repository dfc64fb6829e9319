"""Adept/Omron V+ and eV+: the front end (grammar, parser, checker, keyword table)."""
