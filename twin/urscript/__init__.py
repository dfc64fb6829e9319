"""URScript in the twin.

The lark grammar, the parser and checker (the same one ``wirecal lint`` runs on ``.script``
files), the interpreter with the UR controller's 32-bit numbers, the UR controller over
the twin's world (``controller``), and ``ADAPTER``, URScript's twin adapter (``runs``;
loaded when first asked for).
"""

from typing import Any


def __getattr__(name: str) -> Any:
    """Load ``ADAPTER`` on first use: the parser alone needs none of the twin."""
    if name == "ADAPTER":
        from wirecal.twin.urscript.runs import ADAPTER

        return ADAPTER
    raise AttributeError(name)
