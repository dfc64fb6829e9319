"""The URScript backend (Universal Robots controllers).

The language facts it relies on, each with the manual page it was confirmed on
(:mod:`wirecal.gen.urscript.facts`).
"""

from wirecal.gen.urscript.backend import GENERATOR

__all__ = ["GENERATOR"]
