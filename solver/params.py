"""Names of the kinematic error parameters (DESIGN.md conventions).

Craig's modified DH row i (1-based) holds α_{i-1}, a_{i-1}, θ_i, d_i, so:

* ``th<i>`` — offset of θ_i, row i;      ``d<i>``  — offset of d_i, row i;
* ``a<k>``  — offset of a_k, row k+1;    ``al<k>`` — offset of α_k, row k+1;
* ``tool_x``/``tool_y``/``tool_z`` — the wire attachment point in the last frame
  (used by the identifiability analysis to show its redundancy with th6/d6);
* ``c<j>`` — compliance of joint j under its gravity torque (:mod:`~wirecal.solver.gravity`),
  µrad/(N·m) at the boundary, rad/(N·m) inside; not a DH offset.

Angular parameters are degrees at the boundary, radians inside: the one unit rule is
:data:`UNIT` with :data:`INTERNAL_PER_BOUNDARY`, and every module asks it (:func:`unit_of`,
:attr:`Param.unit`, :class:`ErrorSet`) rather than the names' letters.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cache

import numpy as np

_PATTERN = re.compile(r"^(th|d|al|a|c)(\d+)$")
TOOL_NAMES = ("tool_x", "tool_y", "tool_z")
DH_COLUMN = {"al": 0, "a": 1, "th": 2, "d": 3}
"""Column of the DH table (α_{i-1}, a_{i-1}, θ offset, d_i) each kind of parameter offsets."""

UNIT = {"th": "deg", "al": "deg", "a": "mm", "d": "mm", "tool": "mm", "c": "urad/Nm"}
"""Each kind of parameter's boundary unit (files, command line, logs, controller): angles
(θ, α) in degrees, lengths (a, d, the tool point) in mm (DESIGN.md); compliances in
µrad/(N·m), written ``urad/Nm``."""

INTERNAL_PER_BOUNDARY = {"deg": math.pi / 180.0, "mm": 1.0, "urad/Nm": 1e-6}
"""Internal units (rad, mm, rad/(N·m): the mathematics) per boundary unit."""

BOUNDARY_PER_INTERNAL = {u: 1.0 / f for u, f in INTERNAL_PER_BOUNDARY.items()}
"""Boundary units per internal unit: 180/π deg per rad, 1 for mm."""

UNIT_KINDS = {u: ", ".join(k for k, v in UNIT.items() if v == u) for u in ("deg", "mm")}
"""Each offset unit's kinds of parameter, in words: ``{"deg": "th, al", "mm": "a, d, tool"}``
(a patch's ``[parameters]``; compliances have their own table)."""


@dataclass(frozen=True)
class Param:
    """One error parameter: its name, kind (th, d, a, al, tool) and 0-based row or axis."""

    name: str
    kind: str
    row: int

    @property
    def angular(self) -> bool:
        """Return whether the parameter is an angle (θ or α)."""
        return self.unit == "deg"

    @property
    def unit(self) -> str:
        """Return the parameter's boundary unit, ``deg``, ``mm`` or ``urad/Nm`` (:data:`UNIT`)."""
        return UNIT[self.kind]


def unit_of(name: str) -> str:
    """Return the boundary unit of the parameter ``name`` without parsing it against an arm.

    ``deg`` for th*, al*; ``urad/Nm`` for c*; ``mm`` for a*, d* and any other name
    (tool_x, tool_y, tool_z).
    """
    m = _PATTERN.match(name)
    return UNIT[m.group(1) if m else "tool"]


@cache
def parse(name: str, n_joints: int) -> Param:
    """Parse a parameter name; raise ``ValueError`` with the valid range if it is unknown."""
    if name in TOOL_NAMES:
        return Param(name, "tool", TOOL_NAMES.index(name))
    m = _PATTERN.match(name)
    if m:
        kind, idx = m.group(1), int(m.group(2))
        if kind in ("th", "d", "c") and 1 <= idx <= n_joints:
            return Param(name, kind, idx - 1)
        if kind in ("a", "al") and 0 <= idx <= n_joints - 1:
            return Param(name, kind, idx)
    raise ValueError(
        f"unknown parameter {name!r}; use th1..th{n_joints}, d1..d{n_joints}, "
        f"a0..a{n_joints - 1}, al0..al{n_joints - 1}, {', '.join(TOOL_NAMES)} "
        f"or the compliances c1..c{n_joints}"
    )


def all_names(n_joints: int, with_tool: bool = False) -> tuple[str, ...]:
    """Every DH error parameter of an n-joint arm, row by row (and the tool point)."""
    names: list[str] = []
    for i in range(n_joints):
        names += [f"al{i}", f"a{i}", f"th{i + 1}", f"d{i + 1}"]
    return tuple(names) + (TOOL_NAMES if with_tool else ())


@dataclass(frozen=True)
class ErrorSet:
    """An ordered set of error parameters of an n-joint arm and their units.

    Offsets are degrees (angles) and mm (lengths) at every boundary, radians and mm inside
    the mathematics: :meth:`to_internal` and :meth:`to_boundary` convert values,
    :meth:`per_boundary` and :meth:`per_internal` convert derivatives (Jacobian or Ψ
    columns, the last axis). ``rows`` and ``columns`` place each parameter in the DH table
    (column −1: a tool-point axis, ``rows`` then the axis).
    """

    names: tuple[str, ...]
    n_joints: int
    params: tuple[Param, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        """Store the names as a tuple and parse each into its parameter."""
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "params", tuple(parse(n, self.n_joints) for n in self.names))

    def __len__(self) -> int:
        """Return the number of parameters."""
        return len(self.names)

    @property
    def angular(self) -> np.ndarray:
        """(m,) True where the parameter is an angle (th*, al*)."""
        return np.array([p.angular for p in self.params], dtype=bool)

    @property
    def units(self) -> tuple[str, ...]:
        """Boundary unit of each parameter: "deg" or "mm"."""
        return tuple(p.unit for p in self.params)

    @property
    def rows(self) -> np.ndarray:
        """(m,) 0-based DH row of each parameter (the axis for a tool-point component)."""
        return np.array([p.row for p in self.params], dtype=int)

    @property
    def columns(self) -> np.ndarray:
        """(m,) DH column each parameter offsets; −1 for a tool-point component."""
        return np.array([DH_COLUMN.get(p.kind, -1) for p in self.params], dtype=int)

    @property
    def internal_per_boundary(self) -> np.ndarray:
        """(m,) internal units per boundary unit: π/180 rad/deg for angles, 1 for lengths."""
        return np.array([INTERNAL_PER_BOUNDARY[u] for u in self.units], dtype=float)

    @property
    def boundary_per_internal(self) -> np.ndarray:
        """(m,) boundary units per internal unit: 180/π deg/rad for angles, 1 for lengths."""
        return 1.0 / self.internal_per_boundary

    def to_internal(self, values_boundary: np.ndarray | Sequence[float]) -> np.ndarray:
        """Offsets (…, m) in deg/mm → rad/mm."""
        return np.asarray(values_boundary, dtype=float) * self.internal_per_boundary

    def to_boundary(self, values_internal: np.ndarray | Sequence[float]) -> np.ndarray:
        """Offsets (…, m) in rad/mm → deg/mm."""
        return np.asarray(values_internal, dtype=float) * self.boundary_per_internal

    def per_boundary(self, columns_internal: np.ndarray) -> np.ndarray:
        """Return derivatives (…, m) per rad/mm → per deg/mm (e.g. ∂p/∂e in mm/rad → mm/deg)."""
        return np.asarray(columns_internal, dtype=float) * self.internal_per_boundary

    def per_internal(self, columns_boundary: np.ndarray) -> np.ndarray:
        """Return derivatives (…, m) per deg/mm → per rad/mm (e.g. Ψ in mm/deg → mm/rad)."""
        return np.asarray(columns_boundary, dtype=float) / self.internal_per_boundary
