"""A log's checks as a whole: its origin (plan, robot, encoder scale) and its timer.

A log of another plan, robot or encoder scale is refused before any row is read
(:func:`check_origin`); the controller's timer ``t_s`` must never run backwards and must count
seconds (:func:`timer_problems`, :data:`TIMER_RATIO_BOUNDS`).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.log.readings import Log, Reading
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import RunParameters, run_timeline

FASTEST_RUN = RunParameters(speed_pct=100.0, settle_s=0.0, readings=1)
"""The quickest run a generated program makes: full speed, no fixed settle, one reading."""


TIMER_RATIO_BOUNDS = (0.5, 500.0)
"""The run's time between its zero readings over the time model's fastest run
(:func:`~wirecal.solver.run_parameters.run_timeline`): below 0.5 the robot would have moved
faster than it can (a timer at zero, or in minutes); above 500 slower than at 1 % speed
with 60 s settling (about 100 times, pauses included): a timer in milliseconds."""


def timer_problems(log: Log, zeros: dict[int, Reading], plan: Plan, robot: Robot) -> list[str]:
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


def check_origin(log: Log, plan: Plan, robot: Robot) -> None:
    """Refuse a log of another plan, robot or encoder scale, before any row is read."""
    src = log.source
    problems: list[str] = []
    if log.plan != plan.fingerprint():
        problems.append(
            f"{src}: plan fingerprint {log.plan[:16]}… differs from {plan.source} "
            f"({plan.fingerprint()[:16]}…): the log was taken with another plan; "
            "use that plan, or --accept-foreign if you are sure"
        )
    problems += robot_problems(src, log.robot, log.mm_per_count, robot, ", or --accept-foreign")
    if problems:  # a log of another plan or robot: row-by-row complaints would be noise
        raise WirecalError(problems)


def robot_problems(
    src: str, name: str, mm_per_count: float | None, robot: Robot, other: str = ""
) -> list[str]:
    """Return the problems of a log (a measurement or validation log) of another robot.

    ``name`` and ``mm_per_count`` (None: the log has none) are its header's; ``other``
    ends each problem's advice (", or --accept-foreign" where that option exists).
    """
    problems = []
    if name != robot.name:
        problems.append(
            f"{src}: robot {name!r} differs from {robot.source} "
            f"({robot.name!r}); use the matching robot file{other}"
        )
    enc = robot.encoder.mm_per_count
    if mm_per_count is not None and not math.isclose(abs(mm_per_count), abs(enc), rel_tol=1e-6):
        problems.append(
            f"{src}: mm_per_count {mm_per_count!r} differs from the robot "
            f"file's encoder.mm_per_count {enc!r}; use the matching robot file{other}"
        )
    return problems


def payload_problems(log: Log, plan: Plan) -> list[str]:
    """Check the log's ``payload_kg`` marker against the plan's payload step.

    A plan with a payload step needs a log that says its points were measured with the
    mass at the flange, and that mass; a log that says so needs such a plan.
    """
    step = plan.payload_step
    number = len(plan.steps)
    if step is None and log.payload_kg is not None:
        return [
            f"{log.source}: the log says a {log.payload_kg:g} kg payload was mounted "
            "(payload_kg) but the plan has no payload step; use the plan it was taken with"
        ]
    if step is None:
        return []
    if log.payload_kg is None:
        return [
            f"{log.source}: the plan's step {number} is a payload step ({step.payload_kg:g} kg "
            "at the flange) but the log has no '# payload_kg' line saying the mass was "
            "mounted: take the log with the programs generated for this plan"
        ]
    if not math.isclose(log.payload_kg, step.payload_kg, rel_tol=1e-6, abs_tol=1e-9):
        return [
            f"{log.source}: the log's payload_kg {log.payload_kg:g} kg is not the plan's "
            f"payload step's {step.payload_kg:g} kg; use the plan it was taken with"
        ]
    return []
