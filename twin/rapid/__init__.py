"""RAPID (ABB IRC5) in the twin: the interpreter of the subset wirecal generates.

The front end (grammar, parser, checker) is :mod:`wirecal.lang.rapid`; what the program
does to the robot, the encoder, files and the FlexPendant goes through a
:class:`wirecal.twin.rapid.interp.RapidController`.

``ADAPTER`` (:mod:`wirecal.twin.rapid.adapter`) is what ``wirecal.twin.adapters.adapter("rapid")``
finds: it runs the generated module on the twin's World.
"""

from wirecal.twin.rapid.adapter import ADAPTER

__all__ = ["ADAPTER"]
