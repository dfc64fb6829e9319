"""The analyses of the paper's two validation procedures (§3.6).

The analyses of the paper's two validation procedures (§3.6): per pose the largest
wire-length discrepancy among the four configurations (§3.6.1), and the residuals of the
least-squares plane through the probed points (§3.6.2, eq. 21–25).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.checks import robot_problems
from wirecal.solver.robot import Robot


@dataclass(frozen=True)
class ValidationLog:
    """A validation log's header and its readings.

    Read by :mod:`~wirecal.formats.validation_files`, analysed here.
    """

    kind: str  # "configuration" or "plane"
    source: str
    robot: str
    setup: str
    mm_per_count: float
    rows: np.ndarray  # numbers, one row per reading, columns as its file format's COLUMNS[kind]


@dataclass(frozen=True)
class Stats:
    """Mean, sample standard deviation and maximum of some values."""

    values: np.ndarray
    mean: float
    std: float
    max: float

    @classmethod
    def of(cls, values) -> Stats:
        """Return the statistics of ``values``."""
        v = np.asarray(values, dtype=float)
        return cls(v, float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0, float(v.max()))


def reduction(before: Stats, after: Stats) -> dict[str, float | None]:
    """Return 1 − after/before of the mean, std and max.

    None where the before figure is 0 (nothing to reduce).
    """
    out: dict[str, float | None] = {}
    for k in ("mean", "std", "max"):
        b = getattr(before, k)
        out[k] = 1 - getattr(after, k) / b if b > 0 else None
    return out


MIN_TRAVEL_MM = 1.0
"""Least spread of the wire lengths over a configuration log's poses (mm): the poses lie
across the workspace, hundreds of millimetres apart, so a smaller spread means the
encoder did not count."""


def config_discrepancy(log: ValidationLog, counter: Counter) -> Stats:
    """Return, per pose, the largest wire-length difference among its configurations.

    Per pose, the largest difference among the wire lengths of its four configurations
    (mm); the counts are compared modulo the width of the robot's ``counter``. A log whose
    lengths do not change from pose to pose is refused (:data:`MIN_TRAVEL_MM`): its
    discrepancies would all be zero, a perfect score from a dead encoder.
    """
    rows = log.rows
    _check_counted(log, counter)
    poses, first, group, size = np.unique(
        rows[:, 0], return_index=True, return_inverse=True, return_counts=True
    )
    if np.any(size != 4):
        incomplete = [int(p) for p in poses[size != 4]]
        raise WirecalError(
            f"{log.source}: poses {incomplete[:10]} lack one of the four "
            "configurations; finish the run"
        )
    c = rows[:, 8]
    rel = counter.difference(c, c[first][group])  # each pose's counts from its first
    hi = np.full(len(poses), -np.inf)
    lo = np.full(len(poses), np.inf)
    np.maximum.at(hi, group, rel)
    np.minimum.at(lo, group, rel)
    return Stats.of((hi - lo) * abs(log.mm_per_count))


def _check_counted(log: ValidationLog, counter: Counter) -> None:
    """Raise :class:`WirecalError` when the encoder did not count over the log's poses."""
    c = log.rows[:, 8]
    if len(np.unique(log.rows[:, 0])) < 2:
        return
    travel_mm = float(np.ptp(counter.difference(c, c[0]))) * abs(log.mm_per_count)
    if travel_mm < MIN_TRAVEL_MM:
        raise WirecalError(
            f"{log.source}: the wire length changes by {travel_mm:.4f} mm over "
            f"{len(c)} readings at poses across the workspace (all counts near "
            f"{c[0]:.0f}; less than {MIN_TRAVEL_MM:g} mm): the encoder did not count. "
            "Check its cable, the counter (encoder.channel in the robot file) and that "
            "the wire is attached, then repeat the run"
        )


def plane_residuals(log: ValidationLog) -> tuple[Stats, np.ndarray]:
    """Fit the least-squares plane through the probed points (paper eq. 21–25).

    |Δ_i| of the least-squares plane z = a·x + b·y + c through the probed points, and
    (a, b, c) (paper eq. 21–25).
    """
    x, y, z = log.rows[:, 2], log.rows[:, 3], log.rows[:, 4]
    U = np.column_stack([x, y, np.ones_like(x)])
    xy = np.column_stack([x, y])
    sv = np.linalg.svd(xy - xy.mean(axis=0), compute_uv=False) if len(xy) >= 3 else [0.0, 0.0]
    if not sv[1] > 1e-9 * max(1.0, float(np.abs(xy).max())):
        raise WirecalError(
            f"{log.source}: the plane fit needs at least three probed points not on one "
            f"line; the log has {len(xy)} ({len(np.unique(xy, axis=0))} distinct)"
            + ("" if len(np.unique(xy, axis=0)) < 3 else ", all on one line")
            + "; probe the whole grid"
        )
    coef, *_ = np.linalg.lstsq(U, z, rcond=None)
    return Stats.of(np.abs(U @ coef - z)), coef


def check_logs(logs: list[ValidationLog], robot: Robot | None) -> None:
    """Refuse logs of another robot, and a BEFORE and AFTER not of one setup or the same.

    ``logs``: BEFORE, then AFTER if given; ``robot``: the robot file (None: not given).
    """
    problems = []
    for log in logs:
        mpc = log.mm_per_count if math.isfinite(log.mm_per_count) else None
        if robot is not None:
            problems += robot_problems(log.source, log.robot, mpc, robot)
    if len(logs) == 2:
        before, after = logs
        if before.setup != after.setup:
            problems.append(
                f"{after.source}: setup {after.setup[:16]}… differs from {before.source}'s "
                f"({before.setup[:16]}…): BEFORE and AFTER compare only when taken with one "
                "validation setup; generate both programs from the same one"
            )
        elif np.array_equal(before.rows, after.rows):
            problems.append(
                f"{after.source}: holds the readings of {before.source}, the same run: give "
                "the log taken after calibration as AFTER"
            )
    if problems:
        raise WirecalError(problems)
