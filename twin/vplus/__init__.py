"""V+/eV+ front end of the twin.

The lark grammar, the parser and checker (the same one the generator runs on its own
output), and the interpreter with V+ semantics.
"""
