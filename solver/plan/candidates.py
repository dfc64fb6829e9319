"""The planner's candidate configurations around θ0 and their screening.

Candidates are configurations that move one to three joints away from θ0 (as the paper's
points do) or all of them (:func:`candidates`); each is screened at once (vectorised,
:func:`screen`) for the joint limits with a margin, the wire length (above a minimum,
within the encoder's range), the exit angle (a wire leaving an eyelet stays within its
cone, :mod:`~wirecal.solver.exit_geometry`), the wrist singularity, the arm clear of its
own body and the cell (floor, keep-out volumes, body limits: :mod:`~wirecal.solver.cell.model`)
and the wire's clearance from the links along the joint-interpolated move from θ0
(:mod:`~wirecal.solver.plan.moves`). :func:`blocked` says what blocked them.
"""

from __future__ import annotations

import itertools

import numpy as np

from wirecal.solver.cell.model import SURE_GAP_MM
from wirecal.solver.exit_geometry import wire_path, within_cone
from wirecal.solver.ik import solutions as ik
from wirecal.solver.kinematics import frames, tool_position
from wirecal.solver.plan.moves import move_clearance, move_ok, reach_ok
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot


def _subsets(n: int):
    for size in (1, 2, 3):
        yield from itertools.combinations(range(n), size)
    yield tuple(range(n))


def candidates(robot: Robot, theta0: np.ndarray, opt: PlanOptions, rng) -> np.ndarray:
    """Return configurations (deg) moving a few joints away from θ0.

    Within the margin of the body limits (the joint limits narrowed by ``[cell]``).
    """
    lo, hi = robot.limits_deg(opt.margin_deg)
    out = []
    for subset in _subsets(robot.n_joints):
        q = np.tile(theta0, (opt.samples, 1))
        idx = list(subset)
        q[:, idx] = rng.uniform(lo[idx], hi[idx], (opt.samples, len(idx)))
        out.append(q)
        # the mirror image about θ0: a pair θ0 ± Δ cancels the odd part of a leak, as the
        # paper's symmetric points do
        mirror = 2 * theta0 - q
        inside = np.all((mirror >= lo) & (mirror <= hi), axis=1)
        out.append(mirror[inside])
    return np.round(np.concatenate(out), 2)


def screen(
    robot: Robot, model, p0: np.ndarray, theta0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> tuple[np.ndarray, np.ndarray]:
    """Return which candidates are usable, and their via points.

    Which candidates are usable (wire length, an eyelet's exit cone, wrist singularity,
    the arm clear of itself and the cell, a clear move from θ0)
    and, for those whose direct move is not clear, a via point that makes it clear (the
    arm joints first, or the wrist first); NaN rows where the direct move is clear. The
    moves are sampled coarsely here; ``reach_ok`` checks the points chosen from finely.
    """
    coarse = 10.0

    def length_ok(x):
        d = wire_path(model.pulley, tool_position(model, np.radians(x)) - p0)[0]
        return (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm)

    ok = point_checks(robot, model, p0, q, opt)
    via = np.full(q.shape, np.nan)
    direct = np.zeros(len(q), bool)
    direct[ok] = move_ok(robot, model, p0, theta0, q[ok], opt, coarse)
    arm = slice(0, 3)
    for first in ("arm", "wrist"):
        need = np.flatnonzero(ok & ~direct & np.isnan(via[:, 0]))
        if not len(need):
            break
        v = np.tile(theta0, (len(need), 1))
        if first == "arm":
            v[:, arm] = q[need, arm]
        else:
            v[:, 3:] = q[need, 3:]
        good = length_ok(v)
        good[good] = reach_ok(robot, model, p0, theta0, q[need[good]], v[good], opt, coarse)
        via[need[good]] = v[good]
    return ok & (direct | ~np.isnan(via[:, 0])), via


def point_checks(
    robot: Robot, model, p0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> np.ndarray:
    """Return which candidate points pass every check of their own (:data:`BLOCKED_WHY`)."""
    return np.all(list(_point_failures(robot, model, p0, q, opt).values()), axis=0)


def _point_failures(
    robot: Robot, model, p0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> dict[str, np.ndarray]:
    """Return, per check of :data:`BLOCKED_WHY`, which candidate points pass it.

    The wire length (above ``min_wire_mm``, within the encoder's range less the margin),
    an eyelet's exit cone (the points read the encoder), the wrist singularity of an
    analytic wrist (|sin θ5| ≥ sin 8°) and the arm clear of itself and the cell.
    """
    f = frames(model, np.radians(q))  # one evaluation of the chain for the tool and the cell
    p = tool_position(model, np.radians(q), f)
    d = wire_path(model.pulley, p - p0)[0]
    wrist = np.ones(len(q), bool)
    if ik.analytic_structure(model):
        wrist = np.abs(np.sin(np.radians(q[:, 4]) + model.dh[4, 2])) >= np.sin(np.radians(8))
    return {
        "range": (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm),
        "cone": within_cone(robot.encoder.exit, p - p0),
        "wrist": wrist,
        "cell": robot.cell_gaps(q, p0, model, f, SURE_GAP_MM).smallest() >= 0,
    }


BLOCKED_WHY = {
    "range": "the wire's length out of the encoder range",
    "cone": "the wire outside the exit's cone",
    "wrist": "at the wrist singularity",
    "cell": "the arm in itself or the cell",
}
"""The checks of a candidate point itself (:func:`_point_failures`) and what each
blocks, in words (:func:`blocked`)."""


def blocked(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> str:
    """Say which constraints blocked the candidates around θ0, with counts.

    Per check of the points themselves (a candidate may fail several), then the moves
    from θ0 of the candidates that pass them: through the arm or the cell (where the wire
    is clear), or with the wire closer than ``clearance_mm`` to a link.
    """
    model = robot.nominal
    q = candidates(robot, theta0, opt, np.random.default_rng(opt.seed))
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    fails = _point_failures(robot, model, p0, q, opt)
    counts = [f"{int(np.sum(~v))} {k} ({BLOCKED_WHY[k]})" for k, v in fails.items() if not v.all()]
    left = q[np.all(list(fails.values()), axis=0)]
    if len(left):
        sweep = move_clearance(robot, model, p0, theta0, left, 10.0, 1, np.inf)
        counts.append(f"{int(np.sum(sweep == -np.inf))} cell on the move from theta0")
        counts.append(
            f"{int(np.sum((sweep > -np.inf) & (sweep < opt.clearance_mm)))} clearance (the "
            "wire too close to a link on the move from theta0)"
        )
    return f"of {len(q)} candidates, blocked: " + ", ".join(counts)
