"""The cell before motion: a plan's moves checked against the arm's body and the cell.

Before a program is written (``wirecal gen``) or a plan is passed (``psi --strict``), every
target and every joint-interpolated move of the measurement run (θ0 → via points → points
→ θ0, :func:`~wirecal.solver.wire_range.run_moves`), sampled as the planner samples moves
(:func:`~wirecal.solver.plan.moves.move_samples`), must keep the arm out of itself, the floor
and the keep-out volumes of ``[cell]`` (:mod:`~wirecal.solver.cell.model`), and every target
within the body limits.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.cell.model import SURE_GAP_MM
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.moves import move_samples
from wirecal.solver.robot import Robot
from wirecal.solver.wire_range import RunSamples, run_samples


def _joints(q: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.1f}" for x in q) + ") deg"


def move_sweep(
    robot: Robot,
    model: Model,
    p0: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    contact: bool = False,
    exact_below_mm: float = np.inf,
) -> tuple[str | None, np.ndarray, float]:
    """Return the first collision along the joint-interpolated move a → b (deg), or None.

    In words: what collides (the pair, or a link and the floor or a volume) and where.
    A collision is a gap under the cell's margin, or with ``contact`` (the twin's arm as
    built) capsules that touch: the margin is the planner's, not the robot's. With it, the
    move's last sample (deg) and that sample's smallest gap (mm): with ``exact_below_mm``
    (:func:`~wirecal.solver.cell.model.cell_gaps`) a lower bound of it where it exceeds
    that, the same answer and words otherwise.
    """
    q, _ = move_samples(np.asarray(a)[None], np.asarray(b)[None])
    gaps = robot.cell_gaps(q, p0, model, exact_below_mm=exact_below_mm)
    smallest = gaps.smallest()
    hit = np.flatnonzero(smallest < collision_below_mm(gaps.margin_mm, contact))
    if not hit.size:
        return None, q[-1], float(smallest[-1])
    k = int(hit[0])
    return f"{gaps.cause(k)} at joints {_joints(q[k])}", q[-1], float(smallest[-1])


def collision_below_mm(margin_mm: float, contact: bool) -> float:
    """Return the smallest gap under which a configuration collides (:func:`move_sweep`)."""
    return -margin_mm if contact else 0.0


def body_problem(robot: Robot, q_deg: np.ndarray) -> str | None:
    """Return why a target is beyond the body limits (``[cell]``), or None."""
    lo, hi = robot.limits_deg()
    for j in np.flatnonzero((q_deg < lo) | (q_deg > hi)):
        return (
            f"joint {j + 1} = {q_deg[j]:g} deg is beyond its body limits [{lo[j]:g}, "
            f"{hi[j]:g}] ([cell] body_min_deg/body_max_deg: the arm would fold into itself)"
        )
    return None


def check_cell(robot: Robot, plan: Plan, samples: RunSamples | None = None) -> None:
    """Raise naming every target or move of the run where the arm meets itself or the cell.

    Each problem names the step and point, the colliding pair and the joints where it
    happens first. ``samples``: the plan's
    :func:`~wirecal.solver.wire_range.run_samples` when the caller has them. The capsule
    pairs' gaps beyond :data:`~wirecal.solver.cell.model.SURE_GAP_MM` are taken as their
    lower bounds: every answer and word the same, the pairs far apart not measured.
    """
    model = robot.nominal
    p0 = tool_position(model, np.radians(plan.theta0_deg)[None])[0]
    samples = run_samples(robot, plan) if samples is None else samples
    moves, q, first = samples.moves, samples.q_deg, samples.first
    problems = []
    body = body_problem(robot, np.asarray(plan.theta0_deg, float))
    if body:
        problems.append(f"{plan.source}: theta0_deg: {body}")
    gaps = robot.cell_gaps(q, p0, model, samples.frames, SURE_GAP_MM)  # the same answers
    smallest = gaps.smallest()
    worst = np.minimum.reduceat(smallest, first)
    ends = np.r_[first[1:], len(q)]
    for k, (where, _, target, home) in enumerate(moves):
        body = None if home else body_problem(robot, target)
        if body:
            problems.append(f"{plan.source}: {where}: {body}")
        if worst[k] < 0:
            hit = first[k] + int(np.flatnonzero(smallest[first[k] : ends[k]] < 0)[0])
            problems.append(
                f"{plan.source}: {where}: the arm collides on the move there: "
                f"{gaps.cause(hit)} at joints {_joints(q[hit])}; move the point or add a via "
                "point ('wirecal plan' plans around it), or correct [cell] in the robot file"
            )
    if problems:
        raise WirecalError(problems)
