"""URScript front end of the twin.

The lark grammar, the parser and checker (the same one ``wirecal lint`` runs on ``.script``
files) and the interpreter with the UR controller's 32-bit numbers.
"""
