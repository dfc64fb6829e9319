"""V+/eV+ controller of the twin: the interpreter with V+ semantics.

The grammar, parser and checker it runs are the front end in :mod:`wirecal.lang.vplus`.
"""
