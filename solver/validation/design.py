"""The paper's two validation procedures (§3.6), and a third of wire lengths: their design.

The paper's two validation procedures (§3.6): the design of their runs, and their
analyses; and wire lengths at new points (:func:`distance_plan`), for controllers whose
programs move in joint space only.

* Configuration change (§3.6.1): poses across the workspace, each reached in the four
  configurations above/below × noflip/flip (the shoulder kept); the draw-wire encoder sits
  at a fixed point outside the workspace. A well-calibrated robot puts the tool point at the
  same place in all four, so the wire length is the same; the metric is, per pose, the
  largest discrepancy among the four lengths.
* Plane fit (§3.6.2): a touch probe approaches a grid on a flat plate along −z until it
  trips; the controller's coordinates at contact are fitted by z = a·x + b·y + c (paper
  eq. 21–25) and the residuals Δ_i = a·x_i + b·y_i + c − z_i are the metric.

The setup and the logs are read by :mod:`wirecal.formats.validation_files`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

import numpy as np

from wirecal.solver import pose
from wirecal.solver.errors import WirecalError
from wirecal.solver.ik import solutions as ik
from wirecal.solver.kinematics import tool_position
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.memo import Kept, digest
from wirecal.solver.plan.calibration_plan import Plan, Step
from wirecal.solver.plan.moves import move_ok, move_samples
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot

CONFIGS = (("above", "noflip"), ("above", "flip"), ("below", "noflip"), ("below", "flip"))
"""The four configurations of the configuration-change test, numbered 1–4 in its log."""


@dataclass(frozen=True)
class Setup:
    """The setup of the two validation procedures (see the setup file's format)."""

    encoder_mm: np.ndarray
    poses: int
    seed: int
    plate_origin_mm: np.ndarray
    plate_yaw_deg: float
    plate_size_mm: tuple[float, float]
    grid: tuple[int, int]
    approach_mm: float
    probe_mm: np.ndarray
    signal: int
    source: str = "<setup>"

    def fingerprint(self) -> str:
        """Return the sha256 fingerprint of the setup (its source left out)."""
        canon = {
            k: (
                np.round(np.asarray(v, dtype=float), 6).tolist()
                if isinstance(v, np.ndarray | tuple | float | int)
                else v
            )
            for k, v in self.__dict__.items()
            if k != "source"
        }
        return hashlib.sha256(json.dumps(canon, sort_keys=True).encode()).hexdigest()


CARTESIAN_SLACK_MM = 1.0
"""Cartesian targets keep this much more than the cell's margin: the controller's IK in
single precision lands a fraction of a millimetre from the nominal solution."""


def _pose_reachable(robot: Robot, R, p, margin_deg: float):
    found = {}
    for s in ik.solve(robot, R, p, margin_deg=margin_deg):
        if s.within_limits and s.config[0] == "righty":
            found[s.config[1:]] = s.q
    return [found.get(c) for c in CONFIGS]


def check_frame(robot: Robot, setup: Setup) -> None:
    """Refuse a setup whose encoder or plate lies below the robot file's floor.

    Its coordinates are then in another frame 0 (the shipped Viper file's frame 0 is at the
    shoulder, 335 mm above the floor; a URDF import's is where the URDF's chain begins).
    """
    floor = robot.cell.floor_z_mm
    places = (
        ("configuration.encoder_mm", setup.encoder_mm),
        ("plate.origin_mm", setup.plate_origin_mm),
    )
    problems = [
        f"{setup.source}: {key}: z {xyz[2]:g} mm lies below the robot file's floor ([cell] "
        f"floor_z_mm = {floor:g} in frame 0): the setup was measured in another frame 0 (a "
        "URDF import's is where the URDF's chain begins); measure it again in this robot "
        "file's frame 0"
        for key, xyz in places
        if xyz[2] < floor
    ]
    if problems:
        raise WirecalError(problems)


def config_poses(robot: Robot, setup: Setup, margin_deg: float = 1.0) -> np.ndarray:
    """Return ``setup.poses`` poses for the configuration validation.

    ``setup.poses`` transformations (x, y, z, yaw, pitch, roll) spread over the
    workspace, each reachable righty in all four configurations within the limits with a
    margin, with wire lengths within the encoder's range and the arm clear of itself and
    the cell (:mod:`~wirecal.solver.cell.model`) in every one.
    """
    check_frame(robot, setup)
    model = robot.nominal
    rng = np.random.default_rng(setup.seed)
    reach = np.abs(robot.dh[:, 1]).sum() + np.abs(robot.dh[:, 3]).sum()
    out = []
    for _ in range(400 * setup.poses):
        r = rng.uniform(0.35, 0.85) * reach
        az, el = rng.uniform(-np.pi / 2, np.pi / 2), rng.uniform(-0.6, 0.9)
        x, y, z = r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)
        yaw, pitch, roll = rng.uniform(-90, 90), rng.uniform(100, 170), rng.uniform(-90, 90)
        t = tuple(float(v) for v in np.round([x, y, z, yaw, pitch, roll], 1))
        qs = _pose_reachable(robot, *pose.matrix(*t), margin_deg)
        if any(q is None for q in qs):
            continue
        d = np.linalg.norm(tool_position(model, np.array(qs)) - setup.encoder_mm, axis=1)
        gaps = robot.cell_gaps(np.degrees(qs), setup.encoder_mm)  # ik gives rad
        clear = gaps.smallest() >= CARTESIAN_SLACK_MM
        if np.all((d > 50) & (d < robot.encoder.range_mm - 50) & clear):
            out.append(t)
            if len(out) == setup.poses:
                return np.array(out)
    raise WirecalError(
        f"{setup.source}: configuration.poses: found only {len(out)} of "
        f"{setup.poses} poses reachable in all four configurations with the "
        "wire within range and the arm clear of the cell; move encoder_mm or ask for "
        "fewer poses"
    )


KEPT_GRIDS = 8
"""How many plates' grids are kept: a validation module's generation and the checks of the
same robot and setup ask for the same grid, each point's inverse kinematics at two depths."""

_KEPT_GRIDS: Kept[tuple[list, np.ndarray, np.ndarray]] = Kept(KEPT_GRIDS)


def plate_grid(robot: Robot, setup: Setup, margin_deg: float = 1.0):
    """Return the plate's grid points and the flange targets above them.

    The grid points on the plate and the flange targets above them (tool pointing down),
    each checked reachable (righty, above, noflip), with the arm clear of itself and the
    cell, at the approach height and 5 mm below the plate's nominal top. In the order the
    probe visits them: row by row, every other
    row reversed, so that each point neighbours the one before it (the probe's search
    starts from the depth found there). Kept by the contents of the robot, the setup and
    the margin (:mod:`~wirecal.solver.memo`): the same grid is solved once, its arrays
    read-only; a grid with problems is not kept (asked again, it raises again).
    """
    key = digest(robot, setup, margin_deg)
    index, points, targets = _KEPT_GRIDS.get(key, lambda: _solved_grid(robot, setup, margin_deg))
    return list(index), points, targets


def _solved_grid(robot: Robot, setup: Setup, margin_deg: float):
    """:func:`plate_grid`, solved; its arrays read-only."""
    check_frame(robot, setup)
    nx, ny = setup.grid
    u = np.linspace(0, setup.plate_size_mm[0], nx)
    v = np.linspace(0, setup.plate_size_mm[1], ny)
    yaw = np.radians(setup.plate_yaw_deg)
    ex, ey = np.array([np.cos(yaw), np.sin(yaw), 0]), np.array([-np.sin(yaw), np.cos(yaw), 0])
    index = [(i + 1, j + 1) for j in range(ny) for i in range(nx)[:: 1 if j % 2 == 0 else -1]]
    points = np.array([setup.plate_origin_mm + u[i - 1] * ex + v[j - 1] * ey for i, j in index])
    above = np.array([0, 0, setup.probe_mm[2] + setup.approach_mm])
    targets = [(*(p + above), setup.plate_yaw_deg, 180.0, 0.0) for p in points]
    depths = (0.0, setup.approach_mm + 5.0)
    solved = [[_down_solutions(robot, t, depth, margin_deg) for depth in depths] for t in targets]
    ok: list[np.ndarray] = []
    column = []  # per target and depth: the first solution within limits' place in ok, or None
    for two in solved:
        inside = [[s.q for s in right if s.within_limits] for right in two]
        column.append(
            [len(ok) + sum(map(len, inside[:d])) if q else None for d, q in enumerate(inside)]
        )
        ok += [q for qs in inside for q in qs]
    # the arm's gaps to itself and the cell at every target and depth, in one evaluation
    gaps = robot.cell_gaps(np.degrees(ok), setup.encoder_mm) if ok else None
    problems = [
        problem
        for (i, j), p, two, cols in zip(index, points, solved, column, strict=True)
        if (
            problem := _grid_problem(
                robot,
                setup,
                margin_deg,
                gaps,
                f"({i}, {j}) at {np.round(p, 1).tolist()}",
                two,
                cols,
            )
        )
    ]
    if problems:
        raise WirecalError(
            problems[:5] + ([f"… and {len(problems) - 5} more"] if len(problems) > 5 else [])
        )
    flanges = np.array(targets)
    points.flags.writeable = flanges.flags.writeable = False
    return index, points, flanges


def _grid_problem(robot, setup, margin_deg, gaps, point: str, two: list, columns: list) -> str:
    """Return a grid point's first problem at its two depths ("" if none).

    ``two``: its solutions at each depth; ``columns``: each depth's first solution within
    limits, its column of ``gaps`` (None: none within limits).
    """
    where = f"{setup.source}: plate: grid point {point}"
    for right, k in zip(two, columns, strict=True):
        if k is not None and gaps is not None and gaps.smallest()[k] < CARTESIAN_SLACK_MM:
            return (
                f"{where}: the arm would collide: {gaps.cause(k)}; "
                "move origin_mm or correct [cell] in the robot file"
            )
        if k is None:
            return (
                f"{where} {_beyond_limits(robot, right[0].q, margin_deg)}"
                if right
                else f"{where} is out of reach (righty, above, noflip, tool down); move "
                "origin_mm or shrink the plate"
            )
    return ""


def _down_solutions(robot: Robot, target: tuple, depth_mm: float, margin_deg: float) -> list:
    """Return the solutions (righty, above, noflip) for the flange ``depth_mm`` below ``target``."""
    R, o = pose.matrix(*target)
    o = o - np.array([0, 0, depth_mm])
    return [
        s
        for s in ik.solve(robot, R, o, margin_deg=margin_deg)
        if s.config == ("righty", "above", "noflip")
    ]


def _beyond_limits(robot: Robot, q_rad: np.ndarray, margin_deg: float) -> str:
    """Say which joint a reachable pose needs beyond its limits (less the margin)."""
    q = np.degrees(q_rad)
    lo, hi = robot.joint_min_deg + margin_deg, robot.joint_max_deg - margin_deg
    k = int(np.argmax(np.maximum(lo - q, q - hi)))
    return (
        f"is reachable (righty, above, noflip, tool down) only with joint {k + 1} at "
        f"{q[k]:.1f} deg, beyond its limits {robot.joint_min_deg[k]:g} … "
        f"{robot.joint_max_deg[k]:g} deg less the margin {margin_deg:g}: move origin_mm or "
        "check the robot file's joint limits and frame 0"
    )


# ---------- logs ----------


def distance_plan(
    robot: Robot,
    plan: Plan,
    per_step: int = 5,
    spread_deg: float = 40.0,
    seed: int = 0,
    options: PlanOptions | None = None,
) -> Plan:
    """Design a run of new points for validating wire lengths, shaped like ``plan``.

    Same θ0, order and number of steps as ``plan``, each step ``per_step`` points drawn
    around θ0 (every joint within ±``spread_deg``, ``options.margin_deg`` inside its
    body limits). A point is kept when the planner's rules hold for the move to it from the
    previous target (:func:`~wirecal.solver.plan.moves.move_ok`: the arm clear of itself and
    the cell, the wire clear of the links,
    joint 6 turning at most 180°) and its nominal wire length is within the encoder's
    range (``options.min_wire_mm`` … range_mm − ``options.range_margin_mm``) along that
    move. A second run of the measurement program over these points measures wire lengths
    the calibration never used; the nominal and the calibrated model then predict them
    (:func:`distance_residuals`). For a controller without Cartesian validation programs
    (URScript's programs move in joint space only).
    """
    options = options or PlanOptions()
    rng = np.random.default_rng([seed, 11])
    lo, hi = robot.limits_deg(options.margin_deg)
    model = robot.nominal
    theta0 = np.asarray(plan.theta0_deg, dtype=float)
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    highest = robot.encoder.range_mm - options.range_margin_mm
    steps = []
    for step in plan.steps:
        points: list[np.ndarray] = []
        previous = theta0
        for _ in range(10_000):
            if len(points) == per_step:
                break
            draw = theta0 + rng.uniform(-spread_deg, spread_deg, theta0.shape)
            q = np.round(np.clip(draw, lo, hi), 2)
            path, _ = move_samples(previous, q)
            d = np.linalg.norm(tool_position(model, np.radians(path)) - p0, axis=1)
            if (
                d[-1] > options.min_wire_mm
                and d.max() < highest
                and move_ok(robot, model, p0, previous, q, options)[0]
            ):
                points.append(q)
                previous = q
        if len(points) < per_step:
            raise WirecalError(
                f"no {per_step} validation points for step {step.parameter} within "
                f"±{spread_deg:g}° of θ0: lower the spread"
            )
        steps.append(Step(step.parameter, np.array(points), np.zeros((0, len(theta0)))))
    return Plan(theta0, plan.order, tuple(steps), robot=plan.robot, description="validation")


def distance_residuals(robot: Robot, m: Measurements, offsets: dict[str, float]) -> np.ndarray:
    """Return |measured − predicted| wire lengths (mm) of a run, for a model of the robot.

    Predicted by the model ``offsets`` give (nominal: {}) from the logged joints: the
    distance between the tool point at each point and at θ0 (the first zero reading's
    joints), as the encoder sits there.
    """
    model = robot.model(offsets)
    p = tool_position(model, np.radians(m.joints_deg))
    p0 = tool_position(model, np.radians(m.theta0_deg)[None])[0]
    return np.abs(m.distance_mm - np.linalg.norm(p - p0, axis=1))
