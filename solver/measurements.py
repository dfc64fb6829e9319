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

import itertools
import math
from dataclasses import dataclass, field

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan import Plan
from wirecal.solver.readings import REFERENCE_STEP, Log, Reading
from wirecal.solver.robot import Encoder, Robot
from wirecal.solver.run_parameters import RunParameters, run_timeline
from wirecal.solver.scale import find_slips, reference_problems


@dataclass(frozen=True)
class Tolerances:
    """What the reader accepts; each is a CLI option of ``wirecal solve``."""

    joint_deg: float = 0.05  # logged joints vs the plan
    spread_mm: float = 0.1  # max − min of a point's samples: the robot was still moving
    zero_mm: float = 0.1  # a step change of the zero readings: the wire slipped


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
    tol: Tolerances = Tolerances(),
    accept_foreign: bool = False,
) -> Measurements:
    """Validate a log against the plan and robot; wire lengths for every plan point.

    Raises :class:`WirecalError` listing every ``file:line: problem``. A fingerprint,
    robot-name or encoder-scale mismatch is refused unless ``accept_foreign``. Missing
    points are not an error here: they are listed in the result (a run that stopped is
    still readable).
    """
    if not accept_foreign:
        _check_origin(log, plan, robot)
    src = log.source
    problems: list[str] = []
    rows = _read_rows(log, plan, robot, tol, problems)
    zeros, n_steps, mpc = rows.zeros, len(plan.steps), log.mm_per_count
    first_zero = zeros[min(zeros)] if zeros else None
    if first_zero is None and log.readings:
        problems.append(f"{src}: no zero reading: the log must start with the zero reading at θ0")
    drift: dict[int, float] = {}
    if first_zero is not None:
        drift = _zero_drift(zeros, first_zero.counts, n_steps, robot, tol, mpc, src, problems)
        for s in sorted({int(x) for x in rows.step_no[~np.isnan(rows.counts)]}):
            if s not in zeros:
                problems.append(
                    f"{src}: step {s} has points but no zero reading; the zero "
                    "check at θ0 guards against a slipped wire"
                )
        distance = _lengths(rows, first_zero.counts, n_steps, robot, tol, mpc, src, problems)
    else:
        distance = rows.counts
    reference_mm = _reference_pairs(rows, robot.encoder, mpc, src, problems)
    if not problems:  # a duplicated or foreign row explains a timer going backwards
        problems += _timer_problems(log, rows.zeros, plan, robot)
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


def _times(rows: _Rows, drift: dict[int, float], n_steps: int) -> dict:
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


FASTEST_RUN = RunParameters(speed_pct=100.0, settle_s=0.0, readings=1)
"""The quickest run a generated program makes: full speed, no fixed settle, one reading."""

TIMER_RATIO_BOUNDS = (0.5, 500.0)
"""The run's time between its zero readings over the time model's fastest run
(:func:`~wirecal.solver.run_parameters.run_timeline`): below 0.5 the robot would have moved
faster than it can (a timer at zero, or in minutes); above 500 slower than at 1 % speed
with 60 s settling (about 100 times, pauses included): a timer in milliseconds."""


def _timer_problems(log: Log, zeros: dict[int, Reading], plan: Plan, robot: Robot) -> list[str]:
    """Check the controller's timer ``t_s``: never backwards, and in seconds.

    In seconds: the time between the first and the last zero reading compared with the
    robot time of the same moves (:data:`TIMER_RATIO_BOUNDS`).
    """
    src = log.source
    timed = [(r.line, r.t_s) for r in log.readings if r.t_s is not None]
    for (line_before, before), (line, t) in itertools.pairwise(timed):
        if t < before:
            return [
                f"{src}:{line}: t_s {t:g} s is before the previous reading's "
                f"{before:g} s (line {line_before}): the controller's timer never runs "
                "backwards; keep one run per log, its lines in the order written"
            ]
    zero_t = {s: (r.line, r.t_s) for s, r in sorted(zeros.items()) if r.t_s is not None}
    if len(zero_t) < 2:
        return []
    (s0, (line0, t0)), (s1, (line1, t1)) = list(zero_t.items())[:: len(zero_t) - 1]
    model = run_timeline(robot, plan, FASTEST_RUN).reading_s
    at_zero = np.cumsum([0] + [1 + len(st.points_deg) for st in plan.steps])
    fastest_s = float(model[at_zero[s1 - 1]] - model[at_zero[s0 - 1]])
    lo, hi = TIMER_RATIO_BOUNDS
    if lo <= (t1 - t0) / fastest_s <= hi:
        return []
    unit = "at zero or in minutes" if (t1 - t0) / fastest_s < lo else "in milliseconds"
    return [
        f"{src}:{line0}-{line1}: t_s says steps {s0}–{s1} took {t1 - t0:g} s; the robot "
        f"needs {fastest_s:.0f} s at full speed, and well under {hi * fastest_s:.0f} s even "
        f"at 1 % speed: is the controller's timer {unit}? t_s is in seconds since the "
        "start of the run"
    ]


def _check_origin(log: Log, plan: Plan, robot: Robot) -> None:
    """Refuse a log of another plan, robot or encoder scale, before any row is read."""
    src = log.source
    problems: list[str] = []
    if log.plan != plan.fingerprint():
        problems.append(
            f"{src}: plan fingerprint {log.plan[:16]}… differs from {plan.source} "
            f"({plan.fingerprint()[:16]}…): the log was taken with another plan; "
            "use that plan, or --accept-foreign if you are sure"
        )
    if log.robot != robot.name:
        problems.append(
            f"{src}: robot {log.robot!r} differs from {robot.source} "
            f"({robot.name!r}); use the matching robot file, or --accept-foreign"
        )
    if not math.isclose(abs(log.mm_per_count), abs(robot.encoder.mm_per_count), rel_tol=1e-6):
        problems.append(
            f"{src}: mm_per_count {log.mm_per_count!r} differs from the robot "
            f"file's encoder.mm_per_count {robot.encoder.mm_per_count!r}; use the matching "
            "robot file, or --accept-foreign"
        )
    if problems:  # a log of another plan or robot: row-by-row complaints would be noise
        raise WirecalError(problems)


@dataclass
class _Rows:
    """The accepted readings of a log, in plan order (NaN counts where a point is missing)."""

    step_no: np.ndarray  # (N,) 1-based, plan order
    index_no: np.ndarray  # (N,)
    counts: np.ndarray  # (N,) NaN where missing
    joints_deg: np.ndarray  # (N, n) as logged (plan values where missing)
    zeros: dict[int, Reading]  # per step with a zero reading
    seen: dict[tuple[str, int, int], int]  # (kind, step, index) → line
    unsettled: list[tuple[int, int]]  # (step, index) of the unsettled readings
    t_s: np.ndarray  # (N,) NaN where missing or untimed
    references: dict[int, Reading] = field(default_factory=dict)  # index → reference row


class _BadRow(Exception):
    """One reading refused; its message is reported at the reading's line."""


def _read_rows(log: Log, plan: Plan, robot: Robot, tol: Tolerances, problems: list[str]) -> _Rows:
    """Check each reading against the plan; keep the good ones, report the others."""
    q_plan, step_no, index_no = plan.all_points()
    position = {(int(s), int(i)): k for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    rows = _Rows(
        step_no,
        index_no,
        np.full(len(q_plan), np.nan),
        q_plan.copy(),
        {},
        {},
        [],
        np.full(len(q_plan), np.nan),
    )
    for r in log.readings:
        if r.kind == "unsettled":  # for the record only: the program measured it again
            rows.unsettled.append((r.step, r.index))
            continue
        key = (r.kind, r.step, r.index)
        try:
            if key in rows.seen:
                raise _BadRow(
                    f"duplicate {r.kind} reading of step {r.step}"
                    + (f" point {r.index}" if r.kind == "point" else "")
                    + f" (first on line {rows.seen[key]}); keep one run per log"
                )
            rows.seen[key] = r.line
            if r.kind == "reference":
                _check_reference(r)
                rows.references[r.index] = r
                continue
            k = _check_reading(r, plan, robot, tol, q_plan, position, abs(log.mm_per_count))
        except _BadRow as e:
            problems.append(f"{log.source}:{r.line}: {e}")
            continue
        if k is None:
            rows.zeros[r.step] = r
        else:
            rows.counts[k] = r.counts
            rows.joints_deg[k] = r.joints_deg
            rows.t_s[k] = np.nan if r.t_s is None else r.t_s
    return rows


def _check_reference(r: Reading) -> None:
    """Raise :class:`_BadRow` for a reference row off its step (0) or index (≥ 1)."""
    if r.step != REFERENCE_STEP or r.index < 1:
        raise _BadRow(
            f"a reference row has step {REFERENCE_STEP} and index 1, 2, … (nest A odd, "
            f"nest B even), not step {r.step} index {r.index}"
        )


def _reference_pairs(
    rows: _Rows, enc: Encoder, mpc: float, src: str, problems: list[str]
) -> np.ndarray:
    """Return each reference pair's nest B − nest A length (mm, nominal scale).

    The pairs are checked against the gauge (:func:`~wirecal.solver.scale.reference_problems`)
    when the robot file gives one.
    """
    refs, counter = rows.references, enc.counter
    out: list[float] = []
    lines: list[tuple[int, int]] = []
    for i in sorted(refs):
        if i % 2 == 0:
            continue
        if i + 1 not in refs:
            problems.append(
                f"{src}:{refs[i].line}: the reference reading in nest A (index {i}) has no "
                f"nest B reading (index {i + 1}); repeat the reference step"
            )
            continue
        out.append(float(counter.difference(refs[i + 1].counts, refs[i].counts)) * mpc)
        lines.append((refs[i].line, refs[i + 1].line))
    for i in sorted(refs):
        if i % 2 == 0 and i - 1 not in refs:
            problems.append(
                f"{src}:{refs[i].line}: the reference reading in nest B (index {i}) has no "
                f"nest A reading (index {i - 1}); repeat the reference step"
            )
    if out and enc.reference_length_mm is not None:
        problems += [
            f"{src}:{p}"
            for p in reference_problems(
                np.array(out), lines, enc.reference_length_mm, enc.scale_tolerance_ppm
            )
        ]
    return np.array(out)


def _check_reading(
    r: Reading,
    plan: Plan,
    robot: Robot,
    tol: Tolerances,
    q_plan: np.ndarray,
    position: dict[tuple[int, int], int],
    mm_per_count: float,
) -> int | None:
    """Raise :class:`_BadRow` for a reading the plan refuses; its plan row (None: a zero)."""
    counter = robot.encoder.counter
    n_steps = len(plan.steps)
    # The mean of samples unwrapped from the first lies within a spread of the range.
    if abs(r.counts) > counter.half + r.spread:
        raise _BadRow(
            f"counts {r.counts:.4f} exceed the {robot.encoder.counter_bits}-bit counter "
            f"(±{counter.half}): not a count of this encoder; check counter_bits in "
            f"{robot.source} and that the log column holds the raw counter value"
        )
    if not 1 <= r.step <= n_steps + (r.kind == "zero"):
        raise _BadRow(
            f"step {r.step} is not in the plan (it has {n_steps} steps; the closing "
            f"zero reading is logged as step {n_steps + 1})"
        )
    k, expected = _planned_joints(r, plan, q_plan, position)
    if r.joints_deg.shape != expected.shape:
        raise _BadRow("joint count differs from the robot's")
    off = np.abs(r.joints_deg - expected)
    if np.any(off > tol.joint_deg):
        j = int(np.argmax(off))
        raise _BadRow(
            f"joint {j + 1} is {r.joints_deg[j]:.4f} deg; the plan says "
            f"{expected[j]:g} (tolerance {tol.joint_deg:g}): the robot was not where the "
            "plan puts it"
        )
    if r.spread > tol.spread_mm / mm_per_count:
        raise _BadRow(
            f"spread of {r.samples} samples is {r.spread:g} counts "
            f"({r.spread * mm_per_count:.3f} mm > {tol.spread_mm:g} mm): the robot was "
            f"still moving; lengthen the settle time and repeat step {r.step}"
        )
    return k


def _planned_joints(
    r: Reading, plan: Plan, q_plan: np.ndarray, position: dict[tuple[int, int], int]
) -> tuple[int | None, np.ndarray]:
    """Return a reading's plan row (None for a zero reading) and the joints planned there."""
    if r.kind == "zero":
        if r.index != 0:
            raise _BadRow(f"a zero reading has index 0, not {r.index}")
        return None, plan.theta0_deg
    k = position.get((r.step, r.index))
    if k is None:
        raise _BadRow(
            f"step {r.step} has {len(plan.steps[r.step - 1].points_deg)} points; "
            f"point {r.index} is not in the plan"
        )
    return k, q_plan[k]


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
    rows: _Rows,
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
    for k in np.flatnonzero(~np.isnan(distance)):
        line = rows.seen[("point", int(rows.step_no[k]), int(rows.index_no[k]))]
        if distance[k] > robot.encoder.range_mm:
            problems.append(
                f"{src}:{line}: wire length {distance[k]:.1f} mm is beyond "
                f"the encoder's range {robot.encoder.range_mm:g} mm"
            )
        elif distance[k] < -tol.zero_mm:
            problems.append(
                f"{src}:{line}: wire length {distance[k]:.3f} mm is "
                "negative: is the sign of mm_per_count right?"
            )
    return distance
