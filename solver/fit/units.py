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

Before those, per column (:func:`check_columns`): a length column holding one value, or
negative lengths (a cable's length is not negative), every row at the same joints, and
joints beyond the robot file's limits (another robot's table, or another joint
convention), each named with its column and lines. Then each joint column is tried in
radians on its own (:func:`radian_columns`): a column within ±2π that, read as radians,
makes the nominal model fit the lengths :data:`RADIANS_BETTER` times better is radians —
one joint column in radians among degrees passes every range test.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.angle_units import within_a_turn
from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.fit.cable_data import CableTable
from wirecal.solver.fit.model import multilaterate
from wirecal.solver.fit.sessions import robust_sigma
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.robot import Robot

METRES_RATIO = 50.0
SPAN_MARGIN = 1.5
MAX_JOINT_DEG = 3600.0
MAX_LENGTH_MM = 100_000.0
"""Beyond these a value is no joint angle (ten turns) or cell length (100 m): a typo that
no fit should see."""


RADIANS_BETTER = 2.0
"""A joint column is radians when the nominal model, with it read so, fits the lengths this
many times better (robust σ of the residual; :func:`radian_columns`)."""

LIMIT_MARGIN_DEG = 1.0
"""Joints beyond the robot file's limits by more than this are another robot's (or
another convention's)."""


def _span(values: np.ndarray) -> float:
    lo, hi = np.percentile(values, [2, 98])
    return float(hi - lo)


def _lines(table: CableTable, rows: np.ndarray, shown: int = 10) -> str:
    """Return the file lines of ``rows`` (the first ``shown``, then how many more)."""
    text = ", ".join(str(int(table.lines[r])) for r in rows[:shown])
    return text + (f" … and {len(rows) - shown} more" if len(rows) > shown else "")


def check_columns(robot: Robot, table: CableTable) -> None:
    """Raise, naming columns and lines, for what no unit makes a cable table (docstring)."""
    problems = Problems(table.source)
    col, length = repr(table.columns.length), table.length_mm
    if np.ptp(length) == 0:
        problems.add(
            col,
            f"every row holds {length[0]:g}: not a cable length that changes as the arm "
            "moves; check --map (which column holds the length)",
        )
    negative = np.flatnonzero(length < 0)
    if negative.size:
        problems.add(
            col,
            f"{negative.size} negative length(s) (line(s) {_lines(table, negative)}): a cable's "
            "length is not negative: check --map (which column holds the length), or give "
            "the absolute length in mm (readings from another zero: add a constant; the fit "
            "finds the offset)",
        )
    if np.all(np.ptp(table.q_deg, axis=0) == 0):
        problems.add(
            "joints",
            "every row has the same joints: a fit needs rows where the arm has moved",
        )
    lo = robot.joint_min_deg - LIMIT_MARGIN_DEG
    hi = robot.joint_max_deg + LIMIT_MARGIN_DEG
    for j, name in enumerate(table.columns.joints):
        out = np.flatnonzero((table.q_deg[:, j] < lo[j]) | (table.q_deg[:, j] > hi[j]))
        if out.size:
            problems.add(
                repr(name),
                f"{out.size} row(s) beyond joint {j + 1}'s limits "
                f"[{robot.joint_min_deg[j]:g}, {robot.joint_max_deg[j]:g}] deg of "
                f"{robot.name} (line(s) {_lines(table, out)}): a table of another robot, or "
                "joints in another convention? give this robot's joints in degrees",
            )
    problems.raise_if_any()


def _misfit_mm(base: Model, q_deg: np.ndarray, length_mm: np.ndarray) -> float:
    """Return the robust σ of the lengths about the nominal model, anchor by multilateration."""
    p = tool_position(base, np.radians(q_deg))
    n = len(length_mm)
    sol = multilaterate(p, length_mm, np.zeros(n, dtype=int), 1)
    return robust_sigma(np.linalg.norm(p - sol[:3], axis=1) + sol[3] - length_mm)


def radian_columns(base: Model, table: CableTable) -> list[tuple[int, float, float]]:
    """Return (joint, misfit as given, misfit in radians) of each column that is radians.

    A moving column within ±2π is read as radians; when the nominal model then fits the
    lengths :data:`RADIANS_BETTER` times better, it is radians (module docstring).
    """
    q = table.q_deg
    given = _misfit_mm(base, q, table.length_mm)
    found = []
    for j in range(q.shape[1]):
        if np.ptp(q[:, j]) == 0 or not within_a_turn(q[:, j]):
            continue
        trial = q.copy()
        trial[:, j] = np.degrees(q[:, j])
        misfit = _misfit_mm(base, trial, table.length_mm)
        if RADIANS_BETTER * misfit < given:
            found.append((j, given, misfit))
    return found


def check_units(base: Model, table: CableTable) -> None:
    """Raise, naming the column and the unit it looks like, unless degrees and mm."""
    problems = Problems(table.source)
    _check_magnitudes(table)
    q = table.q_deg
    if len(q) and within_a_turn(q):
        cols = ", ".join(repr(c) for c in table.columns.joints)
        problems.add(
            "joints",
            f"columns {cols} all stay within ±2π (largest |value| {np.max(np.abs(q)):.4g}): "
            "they look like radians; give degrees",
        )
        problems.raise_if_any()
    for j, given, misfit in radian_columns(base, table):
        problems.add(
            repr(table.columns.joints[j]),
            f"stays within ±2π (largest |value| {np.max(np.abs(q[:, j])):.4g}) and, read as "
            f"radians, the robot file's model fits the lengths {given / misfit:.0f} times "
            f"better (σ {misfit:.3g} mm, not {given:.3g} mm): it looks like radians; give "
            "degrees",
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
            f"{reach:.0f} mm at these joints: they look like metres (or inches: under "
            f"1/{METRES_RATIO:g} of it); give mm",
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
