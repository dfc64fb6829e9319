"""A log's readings placed against the plan: each row checked, the good ones kept in plan order.

Each reading's kind, step and index must name a zero or a point of the plan, its joints be
where the plan puts them (``Tolerances.joint_deg``) and its samples' spread small
(``Tolerances.spread_mm``); a refused row is reported at its line. The reference rows (step
:data:`~wirecal.solver.log.readings.REFERENCE_STEP`) come in pairs, nest A then nest B, whose
difference is the gauge's length (:func:`reference_pairs`). What the rows mean together —
the zero reference, slips, drift and the wire lengths — is :mod:`~wirecal.solver.log.measurements`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wirecal.solver.log.readings import REFERENCE_STEP, Log, Reading
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Encoder, Robot
from wirecal.solver.scale import reference_problems


@dataclass(frozen=True)
class Tolerances:
    """What the reader accepts; each is a CLI option of ``wirecal solve``."""

    joint_deg: float = 0.05  # logged joints vs the plan
    spread_mm: float = 0.1  # max − min of a point's samples: the robot was still moving
    zero_mm: float = 0.1  # a step change of the zero readings: the wire slipped


DEFAULT_TOLERANCES = Tolerances()
"""The reader's tolerances when ``wirecal solve`` is given none."""


@dataclass
class LogRows:
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


def read_rows(log: Log, plan: Plan, robot: Robot, tol: Tolerances, problems: list[str]) -> LogRows:
    """Check each reading against the plan; keep the good ones, report the others."""
    q_plan, step_no, index_no = plan.all_points()
    position = {(int(s), int(i)): k for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    rows = LogRows(
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
                _check_spread(r, tol, abs(log.mm_per_count), _REFERENCE_MOVED)
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


def reference_pairs(
    rows: LogRows, enc: Encoder, mpc: float, src: str, problems: list[str]
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
    _check_spread(
        r,
        tol,
        mm_per_count,
        f"the robot was still moving; lengthen the settle time and repeat step {r.step}",
    )
    return k


_REFERENCE_MOVED = "the wire tip moved in its nest; seat it again and repeat the reference step"


def _check_spread(r: Reading, tol: Tolerances, mm_per_count: float, cause: str) -> None:
    """Raise :class:`_BadRow` when the reading's samples spread beyond ``tol.spread_mm``."""
    if r.spread > tol.spread_mm / mm_per_count:
        raise _BadRow(
            f"spread of {r.samples} samples is {r.spread:g} counts "
            f"({r.spread * mm_per_count:.3f} mm > {tol.spread_mm:g} mm): {cause}"
        )


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
