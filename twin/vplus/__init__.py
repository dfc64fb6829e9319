"""V+/eV+ in the twin.

The lark grammar, the parser and checker (the same one the generator runs on its own
output), the interpreter with V+ semantics, the V+ controller over the twin's world
(``controller``), and ``ADAPTER``, V+'s twin adapter (``runs``; loaded when first asked for).
"""

from typing import Any


def __getattr__(name: str) -> Any:
    """Load ``ADAPTER`` on first use: the parser alone needs none of the twin."""
    if name == "ADAPTER":
        from wirecal.twin.vplus.runs import ADAPTER

        return ADAPTER
    raise AttributeError(name)
