"""URScript controller of the twin: the interpreter with the UR controller's 32-bit numbers.

The grammar, parser and checker it runs are the front end in :mod:`wirecal.lang.urscript`.
"""
