"""RAPID's num arithmetic, strings and array elements, as the twin runs them.

What the node-by-node closures (:mod:`wirecal.twin.rapid.interp`) and the fused statements
(:mod:`wirecal.twin.rapid.fused`) both do: the run-time errors, DIV and MOD, the string
bound, the 1-based positions of array elements (the interpreter's module docstring says
what is confirmed).
"""

from __future__ import annotations

import math
import operator
from collections.abc import Callable
from typing import Any

from wirecal.lang.rapid import tables as T
from wirecal.twin.machine import RunError


class RapidError(RunError):
    """A RAPID run-time error: the program stops with this message.

    ``errno``: the predefined error name an ERROR handler sees in ERRNO (``err_divzero`` …,
    :data:`~wirecal.lang.rapid.tables.SUBSET_ERRORS`); None: no handler runs for it.
    """

    def __init__(self, message: str, errno: str | None = None):
        super().__init__(-1, message)
        self.errno = errno


def string(text: str) -> str:
    """Return ``text`` if RAPID holds a string that long, else stop."""
    if len(text) > T.STRING_MAX:
        raise RapidError(f"a string of {len(text)} characters: RAPID holds {T.STRING_MAX}")
    return text


def integer(x: float, what: str) -> int:
    """Return ``x`` as an int if it is one (an operand of DIV, MOD), else stop."""
    if not math.isfinite(x) or x != int(x):
        raise RapidError(f"{what} of {x:g}: DIV and MOD take integers")
    return int(x)


def arith(op: str, a: float, b: float) -> float:
    """Return ``a op b`` for an arithmetic operator (``/`` by zero, DIV and MOD checked)."""
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if b == 0:
        raise RapidError("division by zero", "err_divzero")
    if op == "/":
        return a / b
    x, y = integer(a, op), integer(b, op)
    q = abs(x) // abs(y) * (1 if (x >= 0) == (y >= 0) else -1)
    return float(q if op == "DIV" else x - q * y)


FAST: dict[str, Callable[[float, float], float]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
}

COUNTED = {"+": "add", "-": "add", "*": "mul", "/": "div", "DIV": "div", "MOD": "div"}
"""The kind each arithmetic operator is counted as (the interpreter's ``ops``)."""


def position(array: list[Any], i: float) -> int:
    """Return the position in ``array`` of its element ``i`` (from 1)."""
    if not 1 <= i <= len(array) or i != int(i):  # NaN fails the first comparison
        raise RapidError(f"index {i:g} outside 1..{len(array)}")
    return int(i) - 1


def element_holder(array: list[Any], indices: list[float]) -> tuple[list[Any], int]:
    """Return the list holding the element ``indices`` (from 1) and its position."""
    holder = array
    for i in indices[:-1]:
        holder = holder[position(holder, i)]
    return holder, position(holder, indices[-1])
