"""The paper's two validation procedures (§3.6): the design of their runs.

The paper's two validation procedures (§3.6): the design of their runs, and their
analyses.

* Configuration change (§3.6.1): poses across the workspace, each reached in the four
  configurations above/below × noflip/flip (the shoulder kept); the draw-wire encoder sits
  at a fixed point outside the workspace. A well-calibrated robot puts the tool point at the
  same place in all four, so the wire length is the same; the metric is, per pose, the
  largest discrepancy among the four lengths.
* Plane fit (§3.6.2): a touch probe approaches a grid on a flat plate along −z until it
  trips; the controller's coordinates at contact are fitted by z = a·x + b·y + c (paper
  eq. 21–25) and the residuals Δ_i = a·x_i + b·y_i + c − z_i are the metric.

The setup and the logs are read by :mod:`wirecal.solver.formats.validation_files`.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

import numpy as np

from wirecal.solver import ik, pose
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
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


def _pose_reachable(robot: Robot, R, p, margin_deg: float):
    found = {}
    for s in ik.solve(robot, R, p, margin_deg=margin_deg):
        if s.within_limits and s.config[0] == "righty":
            found[s.config[1:]] = s.q
    return [found.get(c) for c in CONFIGS]


def config_poses(robot: Robot, setup: Setup, margin_deg: float = 1.0) -> np.ndarray:
    """Return ``setup.poses`` poses for the configuration validation.

    ``setup.poses`` transformations (x, y, z, yaw, pitch, roll) spread over the
    workspace, each reachable righty in all four configurations within the limits with a
    margin, with wire lengths within the encoder's range in every one.
    """
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
        if np.all((d > 50) & (d < robot.encoder.range_mm - 50)):
            out.append(t)
            if len(out) == setup.poses:
                return np.array(out)
    raise WirecalError(
        f"{setup.source}: configuration.poses: found only {len(out)} of "
        f"{setup.poses} poses reachable in all four configurations with the "
        "wire within range; move encoder_mm or ask for fewer poses"
    )


def plate_grid(robot: Robot, setup: Setup, margin_deg: float = 1.0):
    """Return the plate's grid points and the flange targets above them.

    The grid points on the plate and the flange targets above them (tool pointing down),
    each checked reachable (righty, above, noflip) at the approach height and 5 mm below
    the plate's nominal top.
    """
    nx, ny = setup.grid
    u = np.linspace(0, setup.plate_size_mm[0], nx)
    v = np.linspace(0, setup.plate_size_mm[1], ny)
    yaw = np.radians(setup.plate_yaw_deg)
    ex, ey = np.array([np.cos(yaw), np.sin(yaw), 0]), np.array([-np.sin(yaw), np.cos(yaw), 0])
    points = np.array([setup.plate_origin_mm + a * ex + b * ey for b in v for a in u])
    index = [(i + 1, j + 1) for j in range(ny) for i in range(nx)]
    targets, problems = [], []
    for (i, j), p in zip(index, points, strict=True):
        flange = p + np.array([0, 0, setup.probe_mm[2] + setup.approach_mm])
        t = (*flange, setup.plate_yaw_deg, 180.0, 0.0)
        for depth in (0.0, setup.approach_mm + 5.0):
            R, o = pose.matrix(*t)
            o = o - np.array([0, 0, depth])
            ok = any(
                s.within_limits and s.config == ("righty", "above", "noflip")
                for s in ik.solve(robot, R, o, margin_deg=margin_deg)
            )
            if not ok:
                problems.append(
                    f"{setup.source}: plate: grid point ({i}, {j}) at "
                    f"{np.round(p, 1).tolist()} is out of reach (righty, above, "
                    "noflip, tool down); move origin_mm or shrink the plate"
                )
                break
        targets.append(t)
    if problems:
        raise WirecalError(
            problems[:5] + ([f"… and {len(problems) - 5} more"] if len(problems) > 5 else [])
        )
    return index, points, np.array(targets)


# ---------- logs ----------
