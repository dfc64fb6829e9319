"""What the twin's interpreters share, whatever the controller language.

The single-precision rounding both controllers apply to their 32-bit floats (V+ REAL,
URScript float), the run-time error a program stops with and how a run ended (the
parsers' nesting bounds are in :mod:`wirecal.lang.syntax`).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

_S = struct.Struct("f")
_PACK, _UNPACK = _S.pack, _S.unpack


class RunError(Exception):
    """A run-time error of a controller program: it stops with this code and message."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code, self.message = code, message


def f32(x: float) -> float:
    """Round to IEEE single precision (a V+ REAL, a URScript float).

    A finite ``x`` beyond the single range is the overflow error: Python's ``struct``
    packs it as infinity on some versions and raises on others.
    """
    try:
        r = _UNPACK(_PACK(x))[0]
    except OverflowError:
        raise RunError(-405, "*Floating-point overflow*") from None
    if r - r != 0.0 and x - x == 0.0:  # r infinite (or NaN) from a finite x
        raise RunError(-405, "*Floating-point overflow*")
    return r


def rounded(op: Callable[[Any, Any], Any]) -> Callable[[Any, Any], float]:
    """Return ``op`` with its result rounded by :func:`f32`, in one call (a hot path's).

    A finite result is rounded here; any other goes through :func:`f32` (its overflow
    error), so the numbers and errors are :func:`f32`'s.
    """

    def single(x: Any, y: Any) -> float:
        v = op(x, y)
        try:
            r = _UNPACK(_PACK(v))[0]
        except OverflowError:
            return f32(v)
        return r if r - r == 0.0 else f32(v)

    return single


ROUNDING_NAMES: dict[str, Any] = {"_pack": _PACK, "_unpack": _UNPACK, "_f32": f32}
"""What the lines of :func:`rounding_source` name (bound in a generated function's globals)."""


def rounding_source(value: str, result: str) -> list[str]:
    """Return Python lines setting ``result`` to ``value`` rounded as :func:`rounded` does.

    Generated code's form of :func:`rounded` (no call): a finite result rounded here, any
    other through :func:`f32` (its overflow error). ``value`` is a variable's name.
    """
    return [
        "try:",
        f"    {result} = _unpack(_pack({value}))[0]",
        "except OverflowError:",
        f"    {result} = _f32({value})",
        f"if {result} - {result} != 0.0:",
        f"    {result} = _f32({value})",
    ]


class Kept:
    """Values kept for objects that do not change once made (a kept parse, its nodes).

    Found by the objects' identity (each held, so that its ``id`` is not reused while
    kept); beyond ``size`` values the oldest is dropped.
    """

    def __init__(self, size: int):
        self.size = size
        self._kept: dict[tuple[int, ...], tuple[tuple[object, ...], Any]] = {}

    def get(self, make: Callable[[], Any], *owners: object) -> Any:
        """Return the value kept for ``owners``, or ``make()``'s, then kept."""
        key = tuple(map(id, owners))
        kept = self._kept.get(key)
        if kept is not None and all(a is b for a, b in zip(kept[0], owners, strict=True)):
            return kept[1]
        value = make()
        if len(self._kept) >= self.size:
            del self._kept[next(iter(self._kept))]
        self._kept[key] = (owners, value)
        return value


class Halt(Exception):
    """HALT (V+) or halt (URScript): the program stops."""


class Stopped(Exception):
    """The operator stopped the program (URScript: at a blocking warning popup)."""


@dataclass
class Outcome:
    """How a program ended: "completed", "halted", "paused", "stopped" or "error"."""

    status: str
    program: str = ""
    line: int = 0
    message: str = ""
    console: list[str] = field(default_factory=list)
