"""The controller languages' front ends: grammars, parsers, checkers and declarations.

One sub-package per language (``lang/<key>/``), each declaring its
:class:`~wirecal.lang.base.Language`; :mod:`wirecal.lang.registry` finds them. Both the
generators (``gen/``) and the digital twin (``twin/``) import the front ends from here. This
layer imports only the standard library, lark and the solver core.
"""
