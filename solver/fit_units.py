"""Plausibility of a cable-length table's units before ``wirecal fit`` (degrees and mm).

A table's columns carry no units. Joints in radians, lengths in metres (or in counts) fit
numbers to nonsense, so each is checked against what the robot file's geometry allows at
the table's own joints, and refused with which column looks like which unit:

* **joints** — every joint column within ±2π over the whole table: radians (a table that
  calibrates an arm moves some joint further than 6.3°);
* **length** — its span (2nd to 98th percentile, so that a few typos do not count) is at
  most the largest distance between the nominal tool points (a triangle inequality, with a
  margin of :data:`SPAN_MARGIN` for offsets between sessions); below 1/:data:`METRES_RATIO`
  of that distance the values are metres;
* **x, y, z** — their span against the nominal tool points' span: 1/1000 of it is metres.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.cable_data import CableTable
from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.kinematics import Model, tool_position

METRES_RATIO = 50.0
SPAN_MARGIN = 1.5
MAX_JOINT_DEG = 3600.0
MAX_LENGTH_MM = 100_000.0
"""Beyond these a value is no joint angle (ten turns) or cell length (100 m): a typo that
no fit should see."""


def _span(values: np.ndarray) -> float:
    lo, hi = np.percentile(values, [2, 98])
    return float(hi - lo)


def check_units(base: Model, table: CableTable) -> None:
    """Raise, naming the column and the unit it looks like, unless degrees and mm."""
    problems = Problems(table.source)
    _check_magnitudes(table)
    q = table.q_deg
    if len(q) and np.all(np.abs(q) <= 2 * np.pi + 1e-6):
        cols = ", ".join(repr(c) for c in table.columns.joints)
        problems.add(
            "joints",
            f"columns {cols} all stay within ±2π (largest |value| {np.max(np.abs(q)):.4g}): "
            "they look like radians; give degrees",
        )
        problems.raise_if_any()
    p = tool_position(base, np.radians(q))
    reach = float(np.linalg.norm(np.ptp(p, axis=0)))
    span = _span(table.length_mm)
    col = repr(table.columns.length)
    if span < reach / METRES_RATIO:
        problems.add(
            col,
            f"the lengths span {span:.4g} while the robot file's tool point moves over "
            f"{reach:.0f} mm at these joints: they look like metres; give mm",
        )
    elif span > SPAN_MARGIN * reach:
        problems.add(
            col,
            f"the lengths span {span:.4g}, more than any two tool points are apart "
            f"({reach:.0f} mm at these joints): counts or µm? give mm (or check --map)",
        )
    if table.xyz_mm is not None:
        xyz_span = float(np.linalg.norm([_span(c) for c in table.xyz_mm.T]))
        if xyz_span < reach / 1000 * 10:
            problems.add(
                ", ".join(repr(c) for c in table.columns.xyz or ()),
                f"x, y, z span {xyz_span:.4g} where the tool point moves over {reach:.0f} mm: "
                "they look like metres; give mm",
            )
    problems.raise_if_any()


def _check_magnitudes(table: CableTable) -> None:
    """Raise, naming the lines, for joints beyond ten turns or lengths beyond 100 m."""
    huge = np.abs(table.q_deg).max(axis=1) > MAX_JOINT_DEG
    huge |= np.abs(table.length_mm) > MAX_LENGTH_MM
    if table.xyz_mm is not None:
        huge |= np.abs(table.xyz_mm).max(axis=1) > MAX_LENGTH_MM
    rows = np.flatnonzero(huge)
    if rows.size:
        lines = ", ".join(str(int(table.lines[r])) for r in rows[:10])
        raise WirecalError(
            f"{table.source}: line(s) {lines}: a joint beyond ±{MAX_JOINT_DEG:g} deg or a "
            f"length beyond ±{MAX_LENGTH_MM:g} mm: fix or delete the row(s)"
        )
