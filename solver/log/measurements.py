"""A measurement log checked against its plan and robot: one wire length per plan point.

The reference of every length is the mean of the steps' zero readings at θ0, each checked
against the first: a step change beyond the tolerance means the wire slipped, a slope in
time is a drift, left to the solver (:func:`~wirecal.solver.scale.find_slips`); counts are
compared modulo the counter width. A run ends with a closing zero reading at θ0 after
the last step, logged as the zero of step N+1: it checks the last step for a slip like
every later zero checks the step before it, and is not part of the reference (the
controller solver uses the same readings).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.log.checks import check_origin, payload_problems, timer_problems
from wirecal.solver.log.readings import Log, Reading
from wirecal.solver.log.rows import (
    DEFAULT_TOLERANCES,
    LogRows,
    Tolerances,
    read_rows,
    reference_pairs,
)
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.scale import find_slips
from wirecal.solver.zero_reading import expected_zero_mm, slip_tolerance_mm


@dataclass(frozen=True)
class Measurements:
    """A log checked against its plan: one wire length per plan point (NaN where missing)."""

    source: str
    sha256: str
    mm_per_count: float
    theta0_deg: np.ndarray  # joints of the reference zero reading
    step: np.ndarray  # (N,) 1-based, plan order
    index: np.ndarray  # (N,)
    joints_deg: np.ndarray  # (N, n) as logged (plan values where missing)
    distance_mm: np.ndarray  # (N,) NaN where missing
    zero_drift_mm: dict[int, float]  # per step with a zero reading (N+1: the closing zero)
    log: Log  # the parsed log these were checked from, so nothing reads it twice
    notes: tuple[str, ...] = ()
    missing: tuple[tuple[int, int], ...] = field(default=())
    unsettled: tuple[tuple[int, int], ...] = field(default=())  # (step, index) not settled
    closed: bool = True  # the closing zero reading after the last step is there
    t_s: np.ndarray | None = None  # (N,) each point's time (version 2; NaN where missing)
    zero_t_s: np.ndarray | None = None  # every zero reading's time, closing one included
    zero_mm: np.ndarray | None = None  # every zero reading's drift from the first (mm)
    reference_t_s: float | None = None  # mean time of the zeros the lengths are read from
    reference_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))  # gauge pairs B − A

    @property
    def timed(self) -> bool:
        """Every reading carries the controller's time (log format version 2)."""
        return self.zero_t_s is not None

    @property
    def present(self) -> np.ndarray:
        """Return a mask of the plan points that have a wire length."""
        return ~np.isnan(self.distance_mm)

    @property
    def complete(self) -> bool:
        """Every point and the closing zero reading are in the log.

        A version 1 log is complete without the closing zero reading (wirecal 0.1 took
        none); its last step is then :attr:`unchecked`.
        """
        return not self.missing and (self.closed or self.log.version < 2)

    @property
    def unchecked(self) -> tuple[int, ...]:
        """Steps with points but no zero reading after them: a wire slip there is unseen."""
        steps = sorted({int(s) for s in self.step[self.present]})
        return tuple(s for s in steps if s + 1 not in self.zero_drift_mm)

    def missing_text(self) -> str:
        """Describe what is missing in words, including the closing zero reading.

        E.g. 'step 5 points 3–6; steps 6–10 (all points)'.
        """
        parts = [describe_missing(self.missing, self.step, self.index)] if self.missing else []
        if not self.closed and not self.missing:  # a stopped run: its points say more
            last = int(self.step.max())
            parts.append(
                f"the closing zero reading at θ0 after step {last} (without it a wire "
                f"slip during step {last} goes unseen: repeat step {last})"
            )
        return "; ".join(parts) or "none"


def describe_missing(missing, step: np.ndarray, index: np.ndarray) -> str:
    """Name missing ``(step, index)`` points in words, whole steps as step ranges."""
    if not missing:
        return "none"
    parts: list[str] = []
    by_step: dict[int, list[int]] = {}
    for s, i in missing:
        by_step.setdefault(s, []).append(i)
    whole = [s for s, idx in by_step.items() if len(idx) == int(np.sum(step == s))]
    for s, idx in sorted(by_step.items()):
        if s in whole:
            continue
        parts.append(f"step {s} point{'s' if len(idx) > 1 else ''} {_ranges(idx)}")
    if whole:
        parts.append(f"step{'s' if len(whole) > 1 else ''} {_ranges(whole)} (all points)")
    return "; ".join(parts)


def _ranges(values: list[int]) -> str:
    values = sorted(values)
    out: list[str] = []
    start = values[0]
    for a, b in zip(values, [*values[1:], None], strict=True):
        if b != a + 1:
            out.append(str(start) if start == a else f"{start}–{a}")
            if b is not None:
                start = b
    return ", ".join(out)


def check_log(
    log: Log,
    plan: Plan,
    robot: Robot,
    tol: Tolerances = DEFAULT_TOLERANCES,
    accept_foreign: bool = False,
) -> Measurements:
    """Validate a log against the plan and robot; wire lengths for every plan point.

    Raises :class:`WirecalError` listing every ``file:line: problem``. A fingerprint,
    robot-name or encoder-scale mismatch is refused unless ``accept_foreign``. Missing
    points are not an error here: they are listed in the result (a run that stopped is
    still readable). The zero readings' slip tolerance ``tol.zero_mm`` is the floor of
    :func:`~wirecal.solver.zero_reading.slip_tolerance_mm` (the generated programs' check).
    """
    zero_mm = slip_tolerance_mm(robot.nominal, plan.theta0_deg, robot.repeatability_mm, tol.zero_mm)
    tol = replace(tol, zero_mm=zero_mm)
    if not accept_foreign:
        check_origin(log, plan, robot)
    src = log.source
    problems = payload_problems(log, plan)  # a new list: the checks below add to it
    rows = read_rows(log, plan, robot, tol, problems)
    zeros, n_steps, mpc = rows.zeros, len(plan.steps), log.mm_per_count
    first_zero = zeros[min(zeros)] if zeros else None
    if first_zero is None and log.readings:
        problems.append(f"{src}: no zero reading: the log must start with the zero reading at θ0")
    drift: dict[int, float] = {}
    distance = rows.counts
    if first_zero is not None:
        drift = _zero_drift(zeros, first_zero.counts, n_steps, robot, tol, mpc, src, problems)
        problems += _steps_without_zero(rows, src)
        distance = _lengths(rows, first_zero.counts, n_steps, robot, tol, mpc, src, problems)
        distance = distance + _zero_offset_mm(robot, first_zero.joints_deg)
    reference_mm = reference_pairs(rows, robot.encoder, mpc, src, problems)
    if not problems:  # a duplicated or foreign row explains a timer going backwards
        problems += timer_problems(log, rows.zeros, plan, robot)
    if problems:
        raise WirecalError(problems)
    missing = tuple(
        (int(rows.step_no[k]), int(rows.index_no[k])) for k in np.flatnonzero(np.isnan(distance))
    )
    theta0 = first_zero.joints_deg if first_zero is not None else plan.theta0_deg
    return Measurements(
        source=src,
        sha256=log.sha256,
        mm_per_count=mpc,
        theta0_deg=theta0,
        step=rows.step_no,
        index=rows.index_no,
        joints_deg=rows.joints_deg,
        distance_mm=distance,
        zero_drift_mm=drift,
        notes=log.notes,
        missing=missing,
        unsettled=tuple(rows.unsettled),
        closed=n_steps + 1 in zeros,
        log=log,
        reference_mm=reference_mm,
        **_times(rows, drift, n_steps),
    )


def _steps_without_zero(rows: LogRows, src: str) -> list[str]:
    """Return a problem for each step with points but no zero reading."""
    return [
        f"{src}: step {s} has points but no zero reading; the zero "
        "check at θ0 guards against a slipped wire"
        for s in sorted({int(x) for x in rows.step_no[~np.isnan(rows.counts)]})
        if s not in rows.zeros
    ]


def _times(rows: LogRows, drift: dict[int, float], n_steps: int) -> dict:
    """Return the readings' times for the drift fit; none without ``t_s`` (version 1)."""
    zeros = [rows.zeros[s] for s in sorted(drift)]
    if not zeros or any(r.t_s is None for r in zeros):
        return {}
    t_zero = np.array([r.t_s for r in zeros], dtype=float)
    in_ref = np.array([s <= n_steps for s in sorted(drift)])
    return {
        "t_s": rows.t_s,
        "zero_t_s": t_zero,
        "zero_mm": np.array([drift[s] for s in sorted(drift)]),
        "reference_t_s": float(t_zero[in_ref].mean()) if in_ref.any() else None,
    }


def _zero_drift(
    zeros: dict[int, Reading],
    first: float,
    n_steps: int,
    robot: Robot,
    tol: Tolerances,
    mpc: float,
    src: str,
    problems: list[str],
) -> dict[int, float]:
    """Each zero reading's drift from the first in mm; a slip blamed on the step it hit.

    A slip is a step change of the zero readings, a drift a slope in time: with the
    controller's times (and enough zeros), each step change beyond the tolerance on top
    of a fitted slope is a slip (:func:`~wirecal.solver.scale.find_slips`) and the slope is
    left to the solver's drift fit; without times, any zero beyond the tolerance is one.
    """
    counter = robot.encoder.counter
    steps = sorted(zeros)
    drift = {s: float(counter.difference(zeros[s].counts, first) * mpc) for s in steps}
    t = np.array([np.nan if zeros[s].t_s is None else zeros[s].t_s for s in steps])
    z = np.array([drift[s] for s in steps])
    slips = find_slips(t, z, tol.zero_mm)
    if slips is None:
        slips = _untimed_slips(z, tol.zero_mm)
    for k, jump in slips:
        s = steps[k]
        prev = max(s - 1, 1)
        which = "the closing zero reading" if s > n_steps else f"zero reading at step {s}"
        problems.append(
            f"{src}:{zeros[s].line}: {which} is {drift[s]:+.3f} mm from the first, a step "
            f"of {jump:+.3f} mm (tolerance {tol.zero_mm:g} mm): the wire slipped or the "
            f"encoder moved after the zero of step {prev}; remount at θ0 and repeat from "
            f"step {prev}"
        )
    return drift


def _untimed_slips(z: np.ndarray, tol_mm: float) -> list[tuple[int, float]]:
    """Return the slips of zero readings without times, as (index, jump).

    Where the zeros first leave the tolerance, and where they jump again (a slip moves
    every later zero too).
    """
    out = []
    for k in range(1, len(z)):
        jumped = abs(z[k] - z[k - 1]) > tol_mm
        if jumped or abs(z[k]) > tol_mm >= abs(z[k - 1]):
            out.append((k, float(z[k] - z[k - 1])))
    return out


def _lengths(
    rows: LogRows,
    first: float,
    n_steps: int,
    robot: Robot,
    tol: Tolerances,
    mpc: float,
    src: str,
    problems: list[str],
) -> np.ndarray:
    """Wire lengths from the mean zero reading in mm; beyond the range or negative reported."""
    counter = robot.encoder.counter
    # The reference is the mean of all zero readings: every length is measured from
    # it, so its error is common to all points; averaging the steps' zeros shrinks it.
    zero_diffs = [
        float(counter.difference(r.counts, first)) for s, r in rows.zeros.items() if s <= n_steps
    ]
    ref = first + float(np.mean(zero_diffs or [0.0]))
    distance = counter.difference(rows.counts, ref) * mpc
    negative = []
    for k in np.flatnonzero(~np.isnan(distance)):
        line = rows.seen[("point", int(rows.step_no[k]), int(rows.index_no[k]))]
        if distance[k] > robot.encoder.range_mm:
            problems.append(
                f"{src}:{line}: wire length {distance[k]:.1f} mm is beyond "
                f"the encoder's range {robot.encoder.range_mm:g} mm"
            )
        elif distance[k] < -tol.zero_mm:
            negative.append((line, distance[k]))
    problems += _negative_lengths(negative, src, robot.encoder.counter_bits)
    return distance


def _negative_lengths(negative: list[tuple[int, float]], src: str, bits: int) -> list[str]:
    """One problem per negative wire length, or one for them all when there are many."""
    if len(negative) < 3:
        return [
            f"{src}:{line}: wire length {d:.3f} mm is negative: is the sign of mm_per_count right?"
            for line, d in negative
        ]
    line, d = negative[0]
    return [
        f"{src}:{line}: {len(negative)} points read negative wire lengths (the first "
        f"{d:.3f} mm): the sign of mm_per_count is wrong, or the logged counts wrap sooner "
        f"than the {bits}-bit counter of the robot file (a filtered 16-bit count wraps at "
        "±32768: give counter_bits the width the controller logs)"
    ]


def _zero_offset_mm(robot: Robot, theta0_deg: np.ndarray) -> float:
    """Return what the zero readings read at θ0: E‖δ‖ with a declared repeatability, else 0.

    An arm back at θ0 within its repeatability reads a length ‖δ‖ ≥ 0, the reference of every
    other length (:mod:`~wirecal.solver.zero_reading`).
    """
    if robot.repeatability_mm is None:
        return 0.0
    return float(expected_zero_mm(robot.nominal, theta0_deg, robot.repeatability_mm))
