"""The URScript twin's values and their operations (:mod:`wirecal.twin.urscript.interp`).

What the node-by-node closures and the fused statements
(:mod:`wirecal.twin.urscript.fused`) both do to values: their checks, errors, 32-bit
int wrap and single-precision results (the interpreter's module docstring says what is
confirmed).
"""

from __future__ import annotations

import math
import operator
from collections import Counter
from collections.abc import Callable
from typing import Any

from wirecal.twin.machine import RunError, f32, rounded

INT_MIN = -(2**31)


class URError(RunError):
    """A URScript run-time error: the program stops with this message."""

    def __init__(self, message: str, code: int = -1):
        super().__init__(code, message)


def i32(v: int) -> int:
    """Wrap an int result to 32 bits, two's complement (unconfirmed: see the interpreter)."""
    return (v - INT_MIN) % 2**32 + INT_MIN


def number(v, what: str = "a number") -> float | int:
    """Return ``v`` if it is an int or a float (not a boolean), else stop."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise URError(f"{what}: expected a number, got {to_str(v)!r}")
    return v


def to_float(v) -> float:
    """Return a number as a URScript float (single precision)."""
    return f32(float(number(v)))


def truth(v) -> bool:
    """Return a condition's value; only booleans are conditions."""
    if not isinstance(v, bool):
        raise URError(f"a condition must be True or False, got {to_str(v)!r}")
    return v


def to_str(v) -> str:
    """Write a value as ``str_cat`` does in the twin (the interpreter's module docstring)."""
    if isinstance(v, bool):
        return "True" if v else "False"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f"{v:.6f}"
    if isinstance(v, list):
        return "[" + ", ".join(to_str(x) for x in v) + "]"
    if isinstance(v, dict):
        return "struct(" + ", ".join(f"{k}={to_str(x)}" for k, x in v.items()) + ")"
    if v is None:
        return "nil"
    return str(v)


def copy_value(v):
    """Return a copy of a list or struct (assigned and passed by value); else ``v``."""
    if isinstance(v, list):
        return [copy_value(x) for x in v]
    return dict(v) if isinstance(v, dict) else v


def element(container, index):
    """Return ``container[index]``, or stop where that is no list element."""
    return container[position(container, index)]


def position(container, index) -> int:
    """Return ``index`` if it is a position in the list ``container``, else stop."""
    if not isinstance(container, list):
        raise URError(f"only a list can be indexed, not {to_str(container)!r}")
    if isinstance(index, bool) or not isinstance(index, int):
        raise URError(f"a list index must be an int, got {to_str(index)!r}")
    if not 0 <= index < len(container):
        raise URError(f"index {index} out of bounds (the list has {len(container)} elements)")
    return index


def negative(v):
    """Return ``-v`` of a number (an int wrapped to 32 bits), else stop."""
    v = number(v, "unary minus")
    return i32(-v) if isinstance(v, int) else -v


def fmod(x: float, y: float) -> float:
    """Return ``x % y`` as :func:`math.fmod` does; an infinite ``x`` stops the run.

    Python's fmod raises ``ValueError`` there, which would end the twin in a traceback;
    what the controller does with it is unconfirmed.
    """
    if math.isinf(x):
        raise URError(f"{x} % {y}: no remainder of an infinite number (unconfirmed)")
    return math.fmod(x, y)


COUNTED = {"+": "add", "-": "add", "*": "mul", "/": "div", "%": "div"}
"""The kind each arithmetic operator is counted as (the interpreter's ``ops``)."""
INT_OPS: dict[str, Callable[[int, int], int]] = {
    "+": lambda x, y: x + y,
    "-": lambda x, y: x - y,
    "*": lambda x, y: x * y,
    "%": lambda x, y: int(fmod(x, y)),
}
FLOAT_OPS: dict[str, Callable[[float, float], float]] = {
    "+": operator.add,
    "-": operator.sub,
    "*": operator.mul,
    "/": operator.truediv,
    "%": fmod,
}


def mixed(op: str, ops: Counter[str]) -> Callable[[Any, Any], Any]:
    """Return ``x op y`` on any two values, counted in ``ops`` (not two floats: a fast path).

    Each operand must be a number; int op int is an int (wrapped) for ``+ - * %``, else the
    operands are floats and the result is rounded to single precision.
    """
    kind, divides = COUNTED[op], op in "/%"
    int_op, single = INT_OPS.get(op), rounded(FLOAT_OPS[op])

    def any_values(x, y):
        x, y = number(x, op), number(y, op)
        ops[kind] += 1
        if divides and y == 0:
            raise URError("division by zero")
        if int_op is not None and isinstance(x, int) and isinstance(y, int):
            return i32(int_op(x, y))
        return single(float(x), float(y))

    return any_values
