"""Replay a laser tracker's data through one simulated wire (``bench/bench_tracker_replay.py``).

One replay of a :class:`~wirecal.solver.tracker.data.TrackerTable`: its rows split at
random into halves; from the training half the pool planner
(:func:`~wirecal.solver.plan.pool.plan_pool`) chooses θ0 and at most N poses. On those N
poses, four models:

* **nominal** — the robot file's DH, with the tool point and base frame fitted to the x, y, z
  (:func:`~wirecal.solver.tracker.fit.calibrate` on the tool point alone);
* **tracker** — the 3-D calibration of the same poses (the tool point, the base frame and the
  identifiable DH errors);
* **wire** — the wire's fixed end at the point the tracker measured at θ0; each pose's
  reading is the distance from it to the measured point, rounded to the encoder's count,
  with a zero the fit does not know; identified by ``wirecal fit``'s wire model with a
  prior where the readings are weak (:func:`~wirecal.solver.wire_prior.map_fit`: every DH
  error of rows 2…n, the attachment, the anchor and one offset);
* **wire + compliance** — the same readings fitted with the joint compliances of the robot
  file's ``[calibration] compliances`` beside them (issue 30's model δθ_j = c_j·τ_j(q),
  :mod:`~wirecal.solver.gravity`; the file's masses, else the assumed ones), each with its
  prior; the plan is made for this fit when the file asks compliances
  (:func:`~wirecal.solver.plan.pool.wire_pool`), and the rigid wire uses the same poses;
* each judged on the held-out half: its tool points rigidly registered onto the measured
  ones (:func:`~wirecal.solver.tracker.fit.registered_rms_mm`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.fit.calibrate import Data, nominal_floor, point_model
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.params import TOOL_NAMES
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.pool import plan_pool
from wirecal.solver.robot import Robot
from wirecal.solver.tracker.data import TrackerTable
from wirecal.solver.tracker.fit import calibrate, registered_rms_mm
from wirecal.solver.wire_prior import map_fit, wire_layout

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
    predicted_mm: float  # the plan's predicted tool-point error at the reading noise


def readings_mm(xyz_mm: np.ndarray, anchor_mm: np.ndarray, mm_per_count: float) -> np.ndarray:
    """Return the wire's readings: ‖x − anchor‖ rounded to whole counts, plus the zero."""
    counts = np.round(np.linalg.norm(xyz_mm - anchor_mm, axis=1) / mm_per_count)
    return counts * mm_per_count + ZERO_MM


def wire_map(
    base: Model,
    compliances: tuple[str, ...],
    q_deg: np.ndarray,
    length_mm: np.ndarray,
    robot: Robot,
) -> Model:
    """Return the model one wire's readings give (:func:`~wirecal.solver.wire_prior.map_fit`)."""
    mpc = robot.encoder.mm_per_count
    q_rad = np.radians(q_deg)
    session = np.zeros(len(q_rad), dtype=int)
    floor = nominal_floor(base, Data(q_rad, length_mm, session, 0.0), 1e-6, mpc)
    data = Data(q_rad, length_mm, session, floor)
    return map_fit(base, wire_layout(base, compliances), data, PlanOptions.prior).model


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

    def held_out(model: Model) -> float:
        return registered_rms_mm(tool_position(model, q[test]), x[test])

    length = readings_mm(x[rows], anchor, robot.encoder.mm_per_count)
    wire = wire_map(base, (), table.q_deg[rows], length, robot)
    bent = (
        wire_map(base, robot.compliances, table.q_deg[rows], length, robot)
        if robot.compliances
        else None
    )
    return Replay(
        nominal_mm=held_out(calibrate(base, q[rows], x[rows], TOOL_NAMES).model),
        tracker_mm=held_out(calibrate(base, q[rows], x[rows]).model),
        wire_mm=held_out(wire),
        wire_compliance_mm=None if bent is None else held_out(bent),
        anchor_mm=plan.anchor_mm,
        anchor_tracker_mm=anchor,
        theta0_deg=table.q_deg[train[plan.theta0_row]],
        points=len(rows),
        predicted_mm=plan.predicted_mm,
    )
