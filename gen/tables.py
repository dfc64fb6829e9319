"""The constant tables of the controller solver, computed once on the PC.

Configuration c = 0 is θ0, c = 1..N the plan's calibration points in plan order. For
every configuration and joint the tables hold cos and sin of the nominal joint angle
(plan angle + DH θ offset), so the controller never evaluates a trigonometric function:
a perturbed angle θ + ε uses the angle-addition formula with short polynomials for ε
(the ``sincos`` macro of ``templates/vplus/macros.j2``). For every point they also hold
the nominal wire vector ν_n and length d_n, so the controller works with small
differences from nominal only; with a guide pulley, d_n is arc plus span, and the tables
add each point's nominal coordinates w (along the swivel axis), s (across it) and t (the
free span) of :mod:`~wirecal.solver.exit_geometry`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.exit_geometry import Pulley, bend_coordinates, wire_path
from wirecal.solver.identify import omega_vector
from wirecal.solver.kinematics import tool_position
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot

KIND_CODE = {"th": 1, "d": 2, "a": 3, "al": 4, "tool": 5}
"""Parameter kinds as the controller numbers them (array ``pk``)."""

STEP_ITERATIONS = 5
"""Gauss–Newton iterations per step (fixed: 5 agree with the converged reference to
2e-8 for errors up to ±4.5 deg/mm on the Viper plan; 4 with the polish at 2 give 3e-7)."""

JOINT_ITERATIONS = 3
"""Gauss–Newton iterations of the joint polish (fixed)."""


@dataclass(frozen=True)
class Tables:
    """Everything the controller solver reads besides the measurements (internal units)."""

    n: int  # joints
    ca: np.ndarray  # (n,) cos α_{k-1}
    sa: np.ndarray  # (n,) sin α_{k-1}
    la: np.ndarray  # (n,) a_{k-1} (mm)
    ld: np.ndarray  # (n,) d_k (mm)
    tool: np.ndarray  # (3,)
    ct: np.ndarray  # (N+1, n) cos of nominal angle, c = 0 is θ0
    st: np.ndarray  # (N+1, n)
    qp: np.ndarray  # (N+1, n) plan angles (deg)
    vn: np.ndarray  # (N+1, 3) nominal ν (row 0 unused, zeros)
    dn: np.ndarray  # (N+1,)   nominal length (row 0 unused)
    dni: np.ndarray  # (N+1,)   nominal length in counts: integer part
    dnf: np.ndarray  # (N+1,)   and fraction, so d̃ − d_n needs no big numbers
    mpc: float  # mm per count (the robot file's, with its sign)
    first: np.ndarray  # (S,) first point (1-based) of each step
    count: np.ndarray  # (S,) points of each step
    spar: np.ndarray  # (S,) parameter index (1-based) of each step
    omega: np.ndarray  # (S,) bound Ω (rad or mm)
    pk: np.ndarray  # (m,) kind code
    pr: np.ndarray  # (m,) row k (1-based) or tool axis
    errors: ErrorSet  # parameters, identification order, and their units
    nominal: np.ndarray  # (m,) nominal values in boundary units (deg, mm)
    pulley: Pulley | None = None  # the guide pulley the wire runs over, if any
    bend: np.ndarray | None = None  # (N+1, 3) with a pulley: nominal w, s, t of each point

    @property
    def n_points(self) -> int:
        """Return the number of plan points (θ0's row not counted)."""
        return len(self.dn) - 1

    @property
    def names(self) -> tuple[str, ...]:
        """Return the parameters in identification order."""
        return self.errors.names


def build_tables(robot: Robot, plan: Plan) -> Tables:
    """Compute the controller solver's tables for the robot's nominal model and the plan."""
    names = plan.order
    q, _, _ = plan.all_points()
    conf = np.vstack([plan.theta0_deg, q])
    angle = np.radians(conf) + robot.dh[:, 2]
    model = robot.nominal
    p = tool_position(model, np.radians(conf))
    nu = p - p[0]
    nu[0] = 0.0
    first = np.cumsum([1] + [len(s.points_deg) for s in plan.steps[:-1]])
    dn = wire_path(model.pulley, nu)[0]
    bend = None
    if model.pulley is not None:
        w, s, _, t = bend_coordinates(nu, model.pulley.axis, model.pulley.radius_mm)
        bend = np.stack([w, s, t], axis=1)
    mpc = robot.encoder.mm_per_count
    dni = np.round(dn / mpc)
    rows = []
    for name in names:
        par = P.parse(name, robot.n_joints)
        rows.append(par.row + 1)
    return Tables(
        n=robot.n_joints,
        ca=np.cos(robot.dh[:, 0]),
        sa=np.sin(robot.dh[:, 0]),
        la=robot.dh[:, 1].copy(),
        ld=robot.dh[:, 3].copy(),
        tool=robot.tool_point.copy(),
        ct=np.cos(angle),
        st=np.sin(angle),
        qp=conf,
        vn=nu,
        dn=dn,
        dni=dni,
        dnf=dn / mpc - dni,
        mpc=mpc,
        first=first,
        count=np.array([len(s.points_deg) for s in plan.steps]),
        spar=np.arange(1, len(names) + 1),
        omega=omega_vector(names, robot.n_joints, plan),
        pk=np.array([KIND_CODE[P.parse(n, robot.n_joints).kind] for n in names]),
        pr=np.array(rows),
        errors=robot.errors(names),
        nominal=np.array([robot.nominal_value(n) for n in names]),
        pulley=model.pulley,
        bend=bend,
    )
