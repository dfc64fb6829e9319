"""Replay a laser tracker's data through one simulated wire (``bench/bench_tracker_replay.py``).

One replay of a :class:`~wirecal.solver.tracker_data.TrackerTable`: its rows split at
random into halves; from the training half the pool planner
(:func:`~wirecal.solver.plan_pool.plan_pool`) chooses θ0 and at most N poses. On those N
poses, four models:

* **nominal** — the robot file's DH, with the tool point and base frame fitted to the x, y, z
  (:func:`~wirecal.solver.tracker_fit.calibrate` on the tool point alone);
* **tracker** — the 3-D calibration of the same poses (the tool point, the base frame and the
  identifiable DH errors);
* **wire** — the wire's fixed end at the point the tracker measured at θ0; each pose's
  reading is the distance from it to the measured point, rounded to the encoder's count,
  with a zero the fit does not know; identified by ``wirecal fit``'s model and estimator
  (:func:`~wirecal.solver.fit.fit_core`, one session);
* **wire + compliance** — the same readings refitted with the joint compliances they
  identify among the robot file's ``[calibration] compliances`` (issue 30's model
  δθ_j = c_j·τ_j(q), :mod:`~wirecal.solver.gravity`; the file's masses, else the assumed
  ones); the poses are the rigid plan's;
* each judged on the held-out half: its tool points rigidly registered onto the measured
  ones (:func:`~wirecal.solver.tracker_fit.registered_rms_mm`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.compliance import compliance_observability
from wirecal.solver.fit import Core, Data, fit_core, nominal_floor, point_model, solve
from wirecal.solver.fit_model import model_of
from wirecal.solver.gravity import default_masses
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.params import TOOL_NAMES
from wirecal.solver.plan_options import PlanOptions
from wirecal.solver.plan_pool import plan_pool
from wirecal.solver.robot import Robot
from wirecal.solver.tracker_data import TrackerTable
from wirecal.solver.tracker_fit import calibrate, registered_rms_mm

ZERO_MM = -123.456
"""The reading at zero distance: any value; the fit is not told it (an unknown zero)."""


@dataclass(frozen=True)
class Replay:
    """One replay's held-out figures (3-D RMS after rigid registration, mm) and its plan."""

    nominal_mm: float
    tracker_mm: float
    wire_mm: float
    wire_compliance_mm: float | None  # None: the robot file asks no compliances
    anchor_mm: np.ndarray  # (3,) the anchor the planner chose: the nominal tool point at θ0
    anchor_tracker_mm: np.ndarray  # (3,) the point the tracker measured at θ0, its frame
    theta0_deg: np.ndarray  # (n,)
    points: int  # poses used (θ0 not counted)
    wire_parameters: tuple[str, ...]  # the geometry the wire fit identified
    compliances: tuple[str, ...]  # the compliances the wire identified with it


def readings_mm(xyz_mm: np.ndarray, anchor_mm: np.ndarray, mm_per_count: float) -> np.ndarray:
    """Return the wire's readings: ‖x − anchor‖ rounded to whole counts, plus the zero."""
    counts = np.round(np.linalg.norm(xyz_mm - anchor_mm, axis=1) / mm_per_count)
    return counts * mm_per_count + ZERO_MM


@dataclass(frozen=True)
class WireFit:
    """One wire's fit: the model, the geometry chosen, and what a refit needs."""

    model: Model
    core: Core
    data: Data


def wire_fit(base: Model, q_deg: np.ndarray, length_mm: np.ndarray, mm_per_count: float) -> WireFit:
    """Return the model ``wirecal fit``'s estimator identifies from one wire's readings."""
    q_rad = np.radians(q_deg)
    session = np.zeros(len(q_rad), dtype=int)
    floor = nominal_floor(base, Data(q_rad, length_mm, session, 0.0), 1e-6, mm_per_count)
    data = Data(q_rad, length_mm, session, floor)
    core = fit_core(base, data, single_session=True)
    return WireFit(model_of(base, core.layout, core.x), core, data)


def bending(robot: Robot) -> Model:
    """Return the point model with the arm's masses and no compliance yet (to identify).

    The robot file's ``[gravity]`` masses, else the assumed ones
    (:func:`~wirecal.solver.gravity.default_masses`).
    """
    base = point_model(robot)
    masses = robot.masses if robot.masses is not None else default_masses(base.dh)
    return replace(base, masses=masses, compliance=np.zeros(base.n_joints))


def wire_compliance_fit(
    robot: Robot, wire: WireFit, theta0_deg: np.ndarray
) -> tuple[Model, tuple[str, ...]]:
    """Refit one wire's readings with the compliances they identify (issue 30's model).

    The candidates, the robot file's ``[calibration] compliances``, are judged with the
    fit's geometry at the reading noise, the readings' quantisation floor
    (:func:`~wirecal.solver.compliance.compliance_observability`: σ at the reading noise);
    the fit is then solved again with them, from the rigid fit's values.
    """
    base = bending(robot)
    core = wire.core
    q_deg = np.degrees(wire.data.q_rad)
    dh = tuple(n for n in core.layout.geometry if n not in TOOL_NAMES)
    floor = wire.data.floor_mm
    seen = compliance_observability(base, q_deg, theta0_deg, dh, robot.compliances, floor)
    layout = replace(core.layout, geometry=(*core.layout.geometry, *seen.identified))
    start = dict(zip(core.layout.names, core.x, strict=True))
    x0 = np.array([start.get(n, 0.0) for n in layout.names])
    x = solve(base, layout, x0, wire.data, np.arange(len(q_deg)))
    return model_of(base, layout, x), seen.identified


def split(n_rows: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the training and held-out rows of a random 50/50 split."""
    order = np.random.default_rng(seed).permutation(n_rows)
    return np.sort(order[: n_rows // 2]), np.sort(order[n_rows // 2 :])


def replay(robot: Robot, table: TrackerTable, *, seed: int, points: int) -> Replay:
    """Replay ``table`` once (module docstring): split ``seed``, at most ``points`` poses."""
    base = point_model(robot)
    train, test = split(len(table.q_deg), seed)
    plan = plan_pool(robot, table.q_deg[train], points, PlanOptions(seed=seed))
    rows = train[plan.rows]
    anchor = table.xyz_mm[train[plan.theta0_row]]
    q, x = np.radians(table.q_deg), table.xyz_mm
    mpc = robot.encoder.mm_per_count

    def held_out(model: Model) -> float:
        return registered_rms_mm(tool_position(model, q[test]), x[test])

    wire = wire_fit(base, table.q_deg[rows], readings_mm(x[rows], anchor, mpc), mpc)
    theta0_deg = table.q_deg[train[plan.theta0_row]]
    bent, compliances = (
        wire_compliance_fit(robot, wire, theta0_deg) if robot.compliances else (None, ())
    )
    return Replay(
        nominal_mm=held_out(calibrate(base, q[rows], x[rows], TOOL_NAMES).model),
        tracker_mm=held_out(calibrate(base, q[rows], x[rows]).model),
        wire_mm=held_out(wire.model),
        wire_compliance_mm=None if bent is None else held_out(bent),
        anchor_mm=plan.anchor_mm,
        anchor_tracker_mm=anchor,
        theta0_deg=theta0_deg,
        points=len(rows),
        wire_parameters=wire.core.layout.geometry,
        compliances=compliances,
    )
