"""The V+/eV+ backend of the generator.

The module's context for the templates in ``templates/vplus`` and V+ literals written
exactly.
"""

from wirecal.gen.vplus.backend import GENERATOR

__all__ = ["GENERATOR"]
