"""Names of the kinematic error parameters (DESIGN.md conventions).

Craig's modified DH row i (1-based) holds α_{i-1}, a_{i-1}, θ_i, d_i, so:

* ``th<i>`` — offset of θ_i, row i;      ``d<i>``  — offset of d_i, row i;
* ``a<k>``  — offset of a_k, row k+1;    ``al<k>`` — offset of α_k, row k+1;
* ``tool_x``/``tool_y``/``tool_z`` — the wire attachment point in the last frame
  (used by the identifiability analysis to show its redundancy with th6/d6).

Angular parameters are degrees at the boundary, radians inside.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache

_PATTERN = re.compile(r"^(th|d|al|a)(\d+)$")
TOOL_NAMES = ("tool_x", "tool_y", "tool_z")


@dataclass(frozen=True)
class Param:
    """One error parameter: its name, kind (th, d, a, al, tool) and 0-based row or axis."""

    name: str
    kind: str
    row: int

    @property
    def angular(self) -> bool:
        return self.kind in ("th", "al")

    @property
    def unit(self) -> str:
        return "deg" if self.angular else "mm"


@cache
def parse(name: str, n_joints: int) -> Param:
    """Parse a parameter name; raise ``ValueError`` with the valid range if it is unknown."""
    if name in TOOL_NAMES:
        return Param(name, "tool", TOOL_NAMES.index(name))
    m = _PATTERN.match(name)
    if m:
        kind, idx = m.group(1), int(m.group(2))
        if kind in ("th", "d") and 1 <= idx <= n_joints:
            return Param(name, kind, idx - 1)
        if kind in ("a", "al") and 0 <= idx <= n_joints - 1:
            return Param(name, kind, idx)
    raise ValueError(
        f"unknown parameter {name!r}; use th1..th{n_joints}, d1..d{n_joints}, "
        f"a0..a{n_joints - 1}, al0..al{n_joints - 1} or {', '.join(TOOL_NAMES)}"
    )


def all_names(n_joints: int, with_tool: bool = False) -> tuple[str, ...]:
    """Every DH error parameter of an n-joint arm, row by row (and the tool point)."""
    names: list[str] = []
    for i in range(n_joints):
        names += [f"al{i}", f"a{i}", f"th{i + 1}", f"d{i + 1}"]
    return tuple(names) + (TOOL_NAMES if with_tool else ())


def angular_mask(names: tuple[str, ...] | list[str], n_joints: int):
    """Boolean list: True where the parameter is an angle (th*, al*)."""
    return [parse(n, n_joints).angular for n in names]
