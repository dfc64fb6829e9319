"""The ABB RAPID backend (IRC5 / RobotWare): one module, ``WIRECAL.mod``.

``GENERATOR`` is what ``wirecal.gen.backends.generator("rapid")`` finds
(:mod:`wirecal.gen.rapid.backend`).
"""

from wirecal.gen.rapid.backend import GENERATOR

__all__ = ["GENERATOR"]
