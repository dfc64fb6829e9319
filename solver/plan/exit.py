"""The wire's exit over a plan's points: the eyelet's cone and the length it leaves out.

Plan-level checks of :mod:`~wirecal.solver.exit_geometry` (pure geometry of one exit):
the wire vectors p_i − p_0 of a plan's points on a robot's model, the exit angle of each,
and the eyelet's unmodelled edge wrap (the exit term of the error budget).
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.distance import wire_vectors
from wirecal.solver.exit_geometry import (
    Eyelet,
    edge_wrap_mm,
    exit_angle_deg,
    far_field_edge_wrap_mm,
)
from wirecal.solver.kinematics import Model
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot


def plan_wires(robot: Robot, plan: Plan, model: Model | None = None) -> np.ndarray:
    """Return p_i − p_0 (mm) of every plan point, plan order, on ``model`` (default nominal)."""
    q, _, _ = plan.all_points()
    model = robot.nominal if model is None else model
    return wire_vectors(model, np.radians(q), np.radians(plan.theta0_deg))


def unmodelled_exit_mm(robot: Robot, plan: Plan, model: Model | None = None) -> np.ndarray:
    """Return, per plan point (plan order), the wire length the model leaves out (mm).

    The eyelet's edge wrap (:func:`edge_wrap_mm`) at the points of ``plan`` on ``model``
    (default: the robot's nominal model); zero for a point exit or a pulley, which the
    model carries. This is the exit term of the error budget.
    """
    exit_ = robot.encoder.exit
    if not isinstance(exit_, Eyelet):
        return np.zeros(plan.n_points)
    return edge_wrap_mm(plan_wires(robot, plan, model), exit_)


def cone_problems(robot: Robot, plan: Plan) -> list[str]:
    """Return a line per plan point whose wire leaves an eyelet beyond its cone (nominal).

    Plans designed for this robot never do; an older plan (the paper's) may, and is then
    still measurable: the edge wrap it adds is what simulate measures.
    """
    exit_ = robot.encoder.exit
    if not isinstance(exit_, Eyelet):
        return []
    angle = exit_angle_deg(plan_wires(robot, plan), exit_.axis)
    _, step, index = plan.all_points()
    wrap_mm = far_field_edge_wrap_mm(angle, exit_.edge_radius_mm)
    return [
        f"{plan.source}: step {step[k]} point {index[k]}: the wire leaves the eyelet "
        f"{angle[k]:.1f} deg off its axis, beyond max_exit_deg {exit_.max_exit_deg:g} of "
        f"{robot.source}; its edge adds about {wrap_mm[k]:.3f} mm the model leaves out "
        "(plan again with 'wirecal plan', or fit a guide pulley)"
        for k in np.flatnonzero(angle > exit_.max_exit_deg)
    ]


def largest_exit_deg(robot: Robot, plan: Plan) -> float | None:
    """Return the largest angle (deg) between a plan point's wire and the exit's axis.

    None for the ideal point exit, which has no axis.
    """
    exit_ = robot.encoder.exit
    if exit_ is None:
        return None
    return float(exit_angle_deg(plan_wires(robot, plan), exit_.axis).max())
