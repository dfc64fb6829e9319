"""The V+ twin's run-time error and the errors of its variables and arithmetic.

Raised alike by the node-by-node closures (:mod:`wirecal.twin.vplus.interp`) and the
statements written out (:mod:`wirecal.twin.vplus.fused`); the codes and messages are the
V+ Language Reference's (see :mod:`wirecal.twin.vplus.interp`).
"""

from __future__ import annotations

import math
from typing import NoReturn

from wirecal.twin.machine import RunError


class VError(RunError):
    """A V+ run-time error: the program stops with this code and message."""


def undefined(name: str) -> NoReturn:
    """Raise the error of a variable read before it has a value (-406)."""
    raise VError(-406, f"*Undefined value* {name}")


def illegal_index(k: int) -> NoReturn:
    """Raise the error of a negative array index (-407)."""
    raise VError(-407, f"*Illegal array index* {k}")


def array_index(x: float) -> int:
    """Return the element an index ``x`` names: the nearest integer, halves up.

    An infinite or NaN index names none: the -407 error (the manual's code for an index
    out of bounds; that a controller gives it here is unconfirmed), where Python's rounding
    would end the twin in a traceback.
    """
    if not math.isfinite(x):
        raise VError(-407, f"*Illegal array index* {x}")
    return math.floor(x + 0.5)


def division_by_zero() -> NoReturn:
    """Raise the error of a zero divisor of / or MOD (-409)."""
    raise VError(-409, "*Division by zero*")
