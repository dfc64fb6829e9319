"""Typed fields of a TOML input file: one set of rules for every wirecal file.

Each reader (robot, plan, truth, validation setup, patch) walks its parsed TOML through a
:class:`Table`: the table declares its allowed keys, and typed accessors return the
converted value, or ``None`` when it is missing or wrong. Every problem is collected in the
shared :class:`~wirecal.solver.errors.Problems` as ``file: key: problem`` and reported at
once. The rules are the same in every file:

* a TOML boolean is never a number (``true`` is not 1) and a number is finite;
* an integer is a TOML integer (``24``, not ``24.0`` or ``24.5``);
* a bound is stated in the message (``is 1e+300; give a number within ±10000``);
* a key the table does not know is reported, with the closest known key
  (``unknown key (did you mean 'range_mm'?)``); a required key that is absent is
  ``is missing``; an optional one takes its default;
* a missing or malformed table is reported once, and the keys under it are not.

A document that is recognisably another wirecal file (a truth file given where a patch is
needed, a plan given as a robot file) is refused by :func:`document` in one line.
"""

from __future__ import annotations

import datetime
import difflib
import itertools
import math
from collections.abc import Iterable, Sequence
from typing import Any, TypeVar

import numpy as np

from wirecal.solver.errors import Problems, WirecalError

MISSING: Any = object()
"""Default of a required key."""

T = TypeVar("T")

KINDS: dict[str, tuple[str, tuple[str, ...]]] = {
    "robot file": ("a robot file (DH table, limits, encoder)", ("kinematics", "encoder")),
    "plan file": ("a plan file (θ0 and point sets)", ("theta0_deg", "step")),
    "truth file": ("a truth file (true offsets of a simulated robot)", ("errors",)),
    "patch file": ("a patch written by wirecal solve", ("parameters", "log_sha256")),
    "validation setup": ("a validation setup", ("configuration", "plate")),
    "patch companion": ("a patch's companion (UR standard-DH deltas)", ("mounting",)),
}
"""Each wirecal TOML document: what it is, and the top-level keys that identify it."""


def document(data: dict[str, Any], source: str, kind: str, keys: Sequence[str]) -> Table:
    """Return the root table of a parsed document of ``kind`` (a key of :data:`KINDS`).

    Raise at once when the document is recognisably another kind: its other problems would
    only hide that.
    """
    own = set(KINDS[kind][1])
    for other, (what, signature) in KINDS.items():
        if other != kind and set(signature) <= data.keys() and not own <= data.keys():
            raise WirecalError(f"{source}: is {what}, not {KINDS[kind][0]}")
    return Table(data, Problems(source), "", keys)


def valid(value: T | None) -> T:
    """Return a field that passed: call after :meth:`Table.raise_if_any`, which raised otherwise."""
    if value is None:
        raise AssertionError("a field with a problem was used after raise_if_any()")
    return value


def show(value: Any) -> str:
    """Return a value as TOML spells it, for messages (``true``, ``"text"``, ``1e+300``)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, datetime.date | datetime.time):
        return value.isoformat()
    if isinstance(value, list):
        text = "[" + ", ".join(show(v) for v in value[:4]) + (", …]" if len(value) > 4 else "]")
        return text if len(text) <= 60 else "a list"
    return repr(value)


def _expectation(
    lo: float | None = None,
    hi: float | None = None,
    *,
    integer: bool = False,
    above: float | None = None,
    unit: str = "",
) -> str:
    """Return what a number must be, in words: ``a whole number between 8 and 64``."""
    kind = "a whole number" if integer else "a number"
    if lo is not None and hi is not None:
        text = f"{kind} within ±{hi:g}" if lo == -hi else f"{kind} between {lo:g} and {hi:g}"
    elif above is not None:
        text = f"{kind} > {above:g}" + (f" and ≤ {hi:g}" if hi is not None else "")
    elif lo is not None:
        text = f"{kind} ≥ {lo:g}"
    elif hi is not None:
        text = f"{kind} ≤ {hi:g}"
    else:
        text = kind if integer else "a finite number"
    return f"{text} {unit}".rstrip()


def _is_number(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _number_problem(
    x: Any,
    lo: float | None = None,
    hi: float | None = None,
    *,
    integer: bool = False,
    above: float | None = None,
    unit: str = "",
) -> str | None:
    """Why ``x`` is not an acceptable number (the one rule of every file), or ``None``."""
    ok = (
        _is_number(x)
        and (not integer or isinstance(x, int))
        and math.isfinite(x)
        and (lo is None or x >= lo)
        and (hi is None or x <= hi)
        and (above is None or x > above)
    )
    if ok:
        return None
    hint = " (no decimal point)" if integer and isinstance(x, float) and x.is_integer() else ""
    return (
        f"is {show(x)}; give {_expectation(lo, hi, integer=integer, above=above, unit=unit)}{hint}"
    )


def _all_within(
    x: list, lo: float | Sequence[float] | None, hi: float | Sequence[float] | None
) -> bool:
    """Whether every value of ``x`` is a finite number within its bounds, told fast.

    ``True`` only for finite floats and ints (never booleans) within the bounds, the values
    :func:`_number_problem` has nothing to say about; ``False`` says only that the values
    need that per-value check, which names each problem (a plan's row passes here in a
    tenth of its time).
    """
    if any(isinstance(b, Sequence) and len(b) < len(x) for b in (lo, hi)):
        return False
    los = lo if isinstance(lo, Sequence) else itertools.repeat(lo)
    his = hi if isinstance(hi, Sequence) else itertools.repeat(hi)
    for v, low, high in zip(x, los, his, strict=False):
        kind = type(v)
        if kind is not int and (kind is not float or not math.isfinite(v)):
            return False
        if (low is not None and v < low) or (high is not None and v > high):
            return False
    return True


def _bound(b: float | Sequence[float] | None, k: int) -> float | None:
    return b[k] if isinstance(b, Sequence) else b


def _unit(unit: str | Sequence[str], k: int) -> str:
    return unit if isinstance(unit, str) else unit[k]


class Table:
    """One TOML table under validation (``where`` is its dotted name, "" for the root).

    ``keys`` lists the allowed keys (``None``: any key, for tables of names such as a truth
    file's ``[errors]``). A table built from ``None`` is absent: its accessors return their
    defaults (or ``None``) without reporting anything, since the table's own problem has
    been reported already.
    """

    def __init__(
        self,
        data: dict[str, Any] | None,
        problems: Problems,
        where: str = "",
        keys: Sequence[str] | None = None,
    ):
        self.data = data
        self.problems = problems
        self.where = where
        if data is not None and keys is not None:
            for key in data:
                if key not in keys:
                    hint = difflib.get_close_matches(key, keys, n=1)
                    extra = f" (did you mean {hint[0]!r}?)" if hint else ""
                    self.add(key, f"unknown key{extra}")

    # -- bookkeeping ----------------------------------------------------------------------
    def name(self, key: str) -> str:
        """Return the dotted name of ``key`` in messages."""
        return f"{self.where}.{key}" if self.where and key else self.where or key

    def add(self, key: str, message: str) -> None:
        """Record a problem about ``key`` of this table ("" for the table itself)."""
        self.problems.add(self.name(key), message)

    def raise_if_any(self) -> None:
        """Raise one :class:`WirecalError` listing every problem recorded so far."""
        self.problems.raise_if_any()

    @property
    def present(self) -> bool:
        """Whether the table exists (an absent table's problem is reported already)."""
        return self.data is not None

    def keys(self) -> list[str]:
        """Return the table's keys, in file order (none when absent)."""
        return list(self.data) if self.data is not None else []

    def _value(self, key: str, default: Any) -> tuple[bool, Any]:
        """(found, value); a required key that is absent is reported here."""
        if self.data is None:
            return False, None if default is MISSING else default
        if key not in self.data:
            if default is MISSING:
                self.add(key, "is missing")
                return False, None
            return False, default
        return True, self.data[key]

    # -- scalars --------------------------------------------------------------------------
    def number(
        self,
        key: str,
        default: Any = MISSING,
        *,
        lo: float | None = None,
        hi: float | None = None,
        above: float | None = None,
        unit: str = "",
    ) -> float | None:
        """Return a finite number within the bounds (``above``: strictly greater)."""
        found, x = self._value(key, default)
        if not found:
            return x
        problem = _number_problem(x, lo, hi, above=above, unit=unit)
        if problem:
            self.add(key, problem)
            return None
        return float(x)

    def integer(
        self, key: str, default: Any = MISSING, *, lo: int | None = None, hi: int | None = None
    ) -> int | None:
        """Return a TOML integer within the bounds."""
        found, x = self._value(key, default)
        if not found:
            return x
        problem = _number_problem(x, lo, hi, integer=True)
        if problem:
            self.add(key, problem)
            return None
        return int(x)

    def string(
        self, key: str, default: Any = MISSING, *, choices: dict[str, str] | None = None
    ) -> str | None:
        """Return a non-blank string; with ``choices`` (value → what it means), one of them."""
        found, x = self._value(key, default)
        if not found:
            return x
        if not isinstance(x, str) or not x.strip() or (choices is not None and x not in choices):
            expected = "a non-empty string"
            if choices is not None:
                expected = " or ".join(
                    show(c) + (f" ({note})" if note else "") for c, note in choices.items()
                )
            self.add(key, f"is {show(x)}; give {expected}")
            return None
        return x

    def boolean(self, key: str, default: Any = MISSING) -> bool | None:
        """Return a TOML boolean (``true`` or ``false``)."""
        found, x = self._value(key, default)
        if not found:
            return x
        if not isinstance(x, bool):
            self.add(key, f"is {show(x)}; give true or false")
            return None
        return x

    def strings(self, key: str, default: Any = MISSING, *, what: str = "names") -> list[str] | None:
        """Return a list of non-blank strings (``what`` they are, for the message)."""
        found, x = self._value(key, default)
        if not found:
            return x
        if not isinstance(x, list) or not all(isinstance(v, str) and v.strip() for v in x):
            self.add(key, f"is {show(x)}; give a list of {what}")
            return None
        return list(x)

    # -- arrays ---------------------------------------------------------------------------
    def vector(
        self,
        key: str,
        default: Any = MISSING,
        *,
        length: int | None = None,
        labels: str = "",
        lo: float | Sequence[float] | None = None,
        hi: float | Sequence[float] | None = None,
        above: float | None = None,
        integer: bool = False,
        unit: str = "",
    ) -> np.ndarray | None:
        """Return a list of ``length`` numbers as an array.

        ``labels`` names them in a message, e.g. "(x, y, z)"; per-element bounds may be
        sequences.
        """
        found, x = self._value(key, default)
        if not found:
            return None if x is None else np.asarray(x, dtype=float)
        return self._row(x, key, length, labels, lo, hi, above, integer, unit)

    def _row(
        self,
        x: Any,
        key: str,
        length: int | None,
        labels: str,
        lo: float | Sequence[float] | None,
        hi: float | Sequence[float] | None,
        above: float | None,
        integer: bool,
        unit: str | Sequence[str],
    ) -> np.ndarray | None:
        things = f"{length} numbers" if length is not None else "numbers"
        if not isinstance(x, list):
            self.add(key, f"is {show(x)}; give a list of {things} {labels}".rstrip())
            return None
        if length is not None and len(x) != length:
            self.add(key, f"has {len(x)} values; expected {length} {labels}".rstrip())
            return None
        if not integer and above is None and _all_within(x, lo, hi):
            return np.asarray(x, dtype=float)
        ok = True
        for k, v in enumerate(x):
            problem = _number_problem(
                v, _bound(lo, k), _bound(hi, k), integer=integer, above=above, unit=_unit(unit, k)
            )
            if problem:
                self.add(key, f"value {k + 1} {problem}")
                ok = False
        return np.asarray(x, dtype=float) if ok else None

    def matrix(
        self,
        key: str,
        default: Any = MISSING,
        *,
        cols: int,
        labels: str = "",
        lo: float | Sequence[float] | None = None,
        hi: float | Sequence[float] | None = None,
        nonempty: bool = True,
        unit: str | Sequence[str] = "",
        max_rows: int | None = None,
    ) -> np.ndarray | None:
        """Return a list of rows of ``cols`` numbers (at most ``max_rows``).

        A bad row is reported as ``key[i]`` (1-based).
        """
        found, x = self._value(key, default)
        if not found:
            return None if x is None else np.asarray(x, dtype=float).reshape(-1, cols)
        rows = f"rows of {cols} numbers {labels}".rstrip()
        if not isinstance(x, list) or (nonempty and not x):
            self.add(key, f"is {show(x)}; give a {'non-empty ' if nonempty else ''}list of {rows}")
            return None
        if max_rows is not None and len(x) > max_rows:
            self.add(key, f"has {len(x)} rows; give at most {max_rows}")
            return None
        out = [
            self._row(r, f"{key}[{i}]", cols, labels, lo, hi, None, False, unit)
            for i, r in enumerate(x, 1)
        ]
        if any(r is None for r in out):
            return None
        return np.asarray(out, dtype=float).reshape(-1, cols)

    # -- nested tables --------------------------------------------------------------------
    def table(self, key: str, keys: Sequence[str] | None, *, required: bool = True) -> Table:
        """Return the sub-table ``[key]`` (absent when missing or not a table)."""
        if required and self.data is not None and key not in self.data:
            self.add(key, f"is missing; add the table [{self.name(key)}]")
            return Table(None, self.problems, self.name(key))
        found, x = self._value(key, None)
        if not found:
            return Table(None, self.problems, self.name(key))
        if not isinstance(x, dict):
            self.add(key, f"is {show(x)}; give a table [{self.name(key)}]")
            return Table(None, self.problems, self.name(key))
        return Table(x, self.problems, self.name(key), keys)

    def tables(self, key: str, keys: Sequence[str], *, required: bool = True) -> list[Table]:
        """Return the array of tables ``[[key]]``; a bad element is an absent table."""
        found, x = self._value(key, MISSING if required else [])
        if not found:
            return []
        if not isinstance(x, list):
            self.add(key, f"is {show(x)}; give an array of tables [[{self.name(key)}]]")
            return []
        out = []
        for i, t in enumerate(x, 1):
            where = f"{self.name(key)}[{i}]"
            if not isinstance(t, dict):
                self.problems.add(where, f"is {show(t)}; give a table")
                out.append(Table(None, self.problems, where))
            else:
                out.append(Table(t, self.problems, where, keys))
        return out


def duplicates(names: Iterable[str]) -> list[str]:
    """Names listed more than once, in order of their second appearance."""
    seen: set[str] = set()
    twice = []
    for n in names:
        if n in seen:
            twice.append(n)
        seen.add(n)
    return twice
