"""Range before motion: the nominal wire length along everything ``wc.run`` does.

The draw-wire encoder counts only within its measuring range, and a wire pulled to the
end of its drum, or wound back to zero, can break the encoder or lose its zero. So the
plan is checked before any program is generated or any Ψ table is trusted: at θ0, every
point and via point, and along every joint-interpolated move between them (sampled as the
planner samples moves, :func:`~wirecal.solver.plan.moves.move_samples`), the nominal wire
length must stay within ``range_mm`` less a margin and above a few millimetres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.kinematics import Frames, frames, tool_position
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.moves import move_samples
from wirecal.solver.robot import Robot

RANGE_MARGIN_MM = 20.0  # default: the wire stays this far inside the encoder's range
MIN_WIRE_MM = 5.0  # and at least this long away from θ0 (the wire tip must not touch)


def run_moves(plan: Plan) -> list[tuple[str, np.ndarray, np.ndarray, bool]]:
    """Return the moves of ``wc.run`` in order.

    Each (where, from, to, back to θ0) in deg: per step θ0 → via points → points in the
    plan's order → the next step's θ0 (the last: the closing zero at θ0).
    """
    moves = []
    here = plan.theta0_deg
    for j, s in enumerate(plan.steps, 1):
        targets = [
            (f"step {j} ({s.parameter}) via point {i}", v, False)
            for i, v in enumerate(s.via_deg, 1)
        ]
        targets += [
            (f"step {j} ({s.parameter}) point {i}", p, False) for i, p in enumerate(s.points_deg, 1)
        ]
        targets.append((f"step {j} ({s.parameter}): back to theta0", plan.theta0_deg, True))
        for where, q, home in targets:
            moves.append((where, np.asarray(here, float), np.asarray(q, float), home))
            here = q
    return moves


@dataclass(frozen=True)
class RunSamples:
    """The moves of ``wc.run`` sampled, and the nominal frames at the samples.

    What the checks before motion (the wire's range, the cell) share: each computes them
    alike, so a caller running both computes them once (:func:`run_samples`).
    """

    moves: list[tuple[str, np.ndarray, np.ndarray, bool]]  # :func:`run_moves`
    q_deg: np.ndarray  # (K, n) every move's samples, in order
    first: np.ndarray  # (M,) each move's first sample
    frames: Frames  # the nominal model's frames of ``q_deg``


def run_samples(robot: Robot, plan: Plan) -> RunSamples:
    """Return the moves of ``wc.run``, sampled as the planner samples moves, and their frames."""
    moves = run_moves(plan)
    q, first = move_samples(np.array([m[1] for m in moves]), np.array([m[2] for m in moves]))
    return RunSamples(moves, q, first, frames(robot.nominal, np.radians(q)))


def nominal_wire_mm(robot: Robot, theta0_deg, q_deg, f: Frames | None = None) -> np.ndarray:
    """Return the nominal model's wire length (mm) at each configuration of ``q_deg`` (n×6).

    Measured from the tool position at θ0; over a pulley, arc plus span (a tip inside the
    pulley counts as 0). ``f``: the nominal frames of ``q_deg`` when the caller has them.
    """
    model = robot.nominal
    p0 = tool_position(model, np.radians(np.asarray(theta0_deg, float))[None])[0]
    tips = tool_position(model, np.radians(np.asarray(q_deg, float)), f)
    return np.nan_to_num(wire_path(model.pulley, tips - p0)[0])


def check_wire_range(
    robot: Robot,
    plan: Plan,
    margin_mm: float = RANGE_MARGIN_MM,
    min_mm: float = MIN_WIRE_MM,
    samples: RunSamples | None = None,
) -> None:
    """Raise when a target's nominal wire length is out of the encoder's range.

    Raise :class:`WirecalError` naming every target (and the move to it) where the
    nominal wire length exceeds ``range_mm − margin_mm`` or comes within ``min_mm`` of
    zero (the moves back to θ0, where the wire is zero by construction, excepted).
    ``samples``: the plan's :func:`run_samples` when the caller has them.
    """
    if not margin_mm >= 0:
        raise WirecalError(f"--range-margin {margin_mm:g}: give a margin of 0 mm or more")
    samples = run_samples(robot, plan) if samples is None else samples
    moves, q, first = samples.moves, samples.q_deg, samples.first
    d = nominal_wire_mm(robot, plan.theta0_deg, q, samples.frames)
    longest = np.maximum.reduceat(d, first)
    # the wire is short near θ0 by construction: only the targets must stay above min_mm
    last = np.r_[first[1:], len(d)] - 1
    at_target = d[last]
    limit = robot.encoder.range_mm - margin_mm
    problems = []
    for k, (where, _, _, home) in enumerate(moves):
        if longest[k] > limit:
            on_move = longest[k] > at_target[k] + 1e-9
            problems.append(
                f"{plan.source}: {where}: the nominal wire is {longest[k]:.1f} mm long"
                + (" on the move there" if on_move else "")
                + f", beyond the encoder's range_mm {robot.encoder.range_mm:g} less the "
                f"{margin_mm:g} mm margin; move the point, or use an encoder with a longer "
                "range"
            )
        if not home and at_target[k] < min_mm:
            problems.append(
                f"{plan.source}: {where}: the nominal wire is {at_target[k]:.1f} mm long, "
                f"within {min_mm:g} mm of zero; move the point away from theta0"
            )
    if problems:
        raise WirecalError(problems)
