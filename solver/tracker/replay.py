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
  file's ``[calibration] compliances`` beside them (what ``wirecal solve`` fits for such a
  file) (issue 30's model δθ_j = c_j·τ_j(q),
  :mod:`~wirecal.solver.gravity`; the file's masses, else the assumed ones), each with its
  prior; the plan is made for this fit when the file asks compliances
  (:func:`~wirecal.solver.plan.pool.wire_pool`), and the rigid wire uses the same poses;
* each judged on the held-out half: its tool points rigidly registered onto the measured
  ones (:func:`~wirecal.solver.tracker.fit.registered_rms_mm`).

:func:`lottery` replays the rigid wire from every θ0 the planner tried, each with its own
planned poses, and from the chosen θ0 with every training pose the wire reaches: what the
choice of θ0 and the count of poses are worth on a data set (``--anchors`` of the bench).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.params import TOOL_NAMES
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.pool import (
    PoolPlan,
    anchor_plans,
    eligible_rows,
    plan_pool,
    pool_wire_mm,
)
from wirecal.solver.robot import Robot
from wirecal.solver.tracker.data import TrackerTable
from wirecal.solver.tracker.fit import calibrate, registered_rms_mm
from wirecal.solver.wire_prior import WireMap, fit_wire

ZERO_MM = -123.456
"""The reading at zero distance: any value; the fit is not told it (an unknown zero)."""

JOINT_RESOLUTION_DEG = 1e-6
"""The tracker tables' joints, taken as exact: the readings' floor is the count's."""


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


def split(n_rows: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the training and held-out rows of a random 50/50 split."""
    order = np.random.default_rng(seed).permutation(n_rows)
    return np.sort(order[: n_rows // 2]), np.sort(order[n_rows // 2 :])


def held_out_mm(model: Model, table: TrackerTable, test: np.ndarray) -> float:
    """Return ``model``'s 3-D RMS (mm) on rows ``test`` after a rigid registration."""
    q_rad = np.radians(table.q_deg[test])
    return registered_rms_mm(tool_position(model, q_rad), table.xyz_mm[test])


def wire_fit(
    robot: Robot,
    table: TrackerTable,
    wire: tuple[int, np.ndarray],
    compliances: tuple[str, ...] = (),
) -> WireMap:
    """Return one wire's fit: ``wire`` = (θ0's row, the rows read), the anchor at θ0's point.

    :func:`~wirecal.solver.wire_prior.fit_wire`, the fit ``wirecal solve`` runs on a plan
    from a pool, on the readings :func:`readings_mm` of the rows.
    """
    theta0_row, rows = wire
    anchor = table.xyz_mm[theta0_row]
    length = readings_mm(table.xyz_mm[rows], anchor, robot.encoder.mm_per_count)
    q_deg = table.q_deg[rows]
    return fit_wire(robot, compliances, q_deg, length, PlanOptions.prior, JOINT_RESOLUTION_DEG)[0]


def one_wire_mm(
    robot: Robot,
    table: TrackerTable,
    wire: tuple[int, np.ndarray],
    test: np.ndarray,
    compliances: tuple[str, ...] = (),
) -> float:
    """Return the held-out figure of one wire (:func:`wire_fit`)."""
    return held_out_mm(wire_fit(robot, table, wire, compliances).model, table, test)


Choose = Callable[[Robot, np.ndarray, int, PlanOptions], PoolPlan]
"""How a replay chooses θ0 and the poses from the training rows (the pool planner's choice)."""


def replay(
    robot: Robot, table: TrackerTable, *, seed: int, points: int, choose: Choose = plan_pool
) -> Replay:
    """Replay ``table`` once (module docstring): split ``seed``, at most ``points`` poses.

    ``choose``: the planner's choice by default; the bench's ``--preflight`` passes the one
    ``plan --pool -o PLAN.toml`` writes, with ``gen``'s pre-flight applied.
    """
    base = point_model(robot)
    train, test = split(len(table.q_deg), seed)
    plan = choose(robot, table.q_deg[train], points, PlanOptions(seed=seed))
    rows = train[plan.rows]
    wire = (int(train[plan.theta0_row]), rows)
    q, x = np.radians(table.q_deg), table.xyz_mm
    return Replay(
        nominal_mm=held_out_mm(calibrate(base, q[rows], x[rows], TOOL_NAMES).model, table, test),
        tracker_mm=held_out_mm(calibrate(base, q[rows], x[rows]).model, table, test),
        wire_mm=one_wire_mm(robot, table, wire, test),
        wire_compliance_mm=(
            one_wire_mm(robot, table, wire, test, robot.compliances) if robot.compliances else None
        ),
        anchor_mm=plan.anchor_mm,
        anchor_tracker_mm=x[wire[0]],
        theta0_deg=table.q_deg[wire[0]],
        points=len(rows),
        predicted_mm=plan.predicted_mm,
    )


@dataclass(frozen=True)
class Lottery:
    """One rigid wire from every θ0 the pool planner tried, and from its θ0 at every pose."""

    predicted_mm: np.ndarray  # (k,) each θ0's predicted error (the planner's figure)
    wire_mm: np.ndarray  # (k,) held-out figure of one wire from each θ0, its planned poses
    chosen: int  # the planner's θ0 (the least predicted error), an index of both
    every_pose_mm: float  # one wire from the chosen θ0 read at every eligible training pose
    tracker_mm: float  # the tracker calibration of the chosen θ0's planned poses
    tracker_every_pose_mm: float  # the tracker calibration of every training pose


def lottery(robot: Robot, table: TrackerTable, *, seed: int, points: int) -> Lottery:
    """Replay one wire from every θ0 tried (:func:`~wirecal.solver.plan.pool.anchor_plans`).

    What the planner's choice of θ0 is worth against the held-out figure of the others,
    and what more poses from the same θ0 could give: every training pose whose wire lies
    within the encoder's range (:func:`~wirecal.solver.plan.pool.eligible_rows`).
    """
    base = point_model(robot)
    train, test = split(len(table.q_deg), seed)
    opt = PlanOptions(seed=seed)
    plans = anchor_plans(robot, table.q_deg[train], points, opt)
    predicted = np.array([pl.predicted_mm for pl in plans])
    chosen = int(np.argmin(predicted))
    theta0, rows = int(train[plans[chosen].theta0_row]), train[plans[chosen].rows]
    p = tool_position(base, np.radians(table.q_deg[train]))
    every = train[eligible_rows(p, plans[chosen].theta0_row, pool_wire_mm(robot, opt))]
    q, x = np.radians(table.q_deg), table.xyz_mm
    return Lottery(
        predicted_mm=predicted,
        wire_mm=np.array(
            [
                one_wire_mm(robot, table, (int(train[pl.theta0_row]), train[pl.rows]), test)
                for pl in plans
            ]
        ),
        chosen=chosen,
        every_pose_mm=one_wire_mm(robot, table, (theta0, every), test),
        tracker_mm=held_out_mm(calibrate(base, q[rows], x[rows]).model, table, test),
        tracker_every_pose_mm=held_out_mm(calibrate(base, q[train], x[train]).model, table, test),
    )
