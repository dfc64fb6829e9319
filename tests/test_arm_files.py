"""The shipped arm files are physical: no configuration within the limits folds a link onto
another, and the PUMA 560 equals the Robotics Toolbox's model with its joint limits."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from wirecal.formats.robot_file import load_robot
from wirecal.solver.kinematics import frames

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

# The closest two joint frames that are not neighbours may come (mm), sampled over the
# limits. Frames whose origins coincide at every configuration (a spherical wrist's, a
# shoulder's) count once; frame 0 (the mounting point) is left out. The bounds sit below
# each arm's sampled minimum: PUMA 346 mm (shoulder to wrist centre at full elbow bend),
# Viper 59.6 and UR5e 43.5 mm (flange beside the shoulder), IRB 120 100 mm.
FOLD_BOUND_MM = {"puma560": 300.0, "viper_s650": 50.0, "ur5e": 35.0, "abb_irb120": 90.0}


def closest_non_neighbours_mm(robot, lo_deg, hi_deg, samples=20000) -> float:
    rng = np.random.default_rng(0)
    q = np.radians(lo_deg + rng.uniform(0, 1, (samples, robot.n_joints)) * (hi_deg - lo_deg))
    o = frames(robot.nominal, q).o
    keep = [1]
    for k in range(2, robot.n_joints + 1):
        if np.max(np.linalg.norm(o[:, k] - o[:, keep[-1]], axis=1)) > 1e-6:
            keep.append(k)
    P = o[:, keep]
    return min(
        float(np.min(np.linalg.norm(P[:, i] - P[:, j], axis=1)))
        for i in range(len(keep))
        for j in range(i + 2, len(keep))
    )


@pytest.mark.parametrize("arm", sorted(FOLD_BOUND_MM))
def test_no_configuration_within_the_limits_folds_the_arm(arm):
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    gap = closest_non_neighbours_mm(robot, robot.joint_min_deg, robot.joint_max_deg)
    assert gap > FOLD_BOUND_MM[arm]


def test_the_old_puma_joint_3_range_folded_the_arm():
    robot = load_robot(EXAMPLES / "puma560" / "robot.toml")
    lo, hi = robot.joint_min_deg.copy(), robot.joint_max_deg.copy()
    lo[2], hi[2] = -45.0, 225.0  # the range this file had, mirrored by mistake
    assert closest_non_neighbours_mm(robot, lo, hi) < 160.0 < FOLD_BOUND_MM["puma560"]


# The Robotics Toolbox's Puma560 (models/DH/Puma560.py): standard DH rows (d, a, α) in mm,
# and its Wang & Chen joint limits (deg).
RTB_DH = [(0, 0, 90), (0, 431.8, 0), (150.05, 20.3, -90), (431.8, 0, 90), (0, 0, -90), (0, 0, 0)]
RTB_LIMITS = [(-160, 160), (-45, 225), (-225, 45), (-110, 170), (-100, 100), (-266, 266)]
OFFSET_DEG = np.array([0, 180, 0, 0, 0, -90.0])  # q_file = q_rtb + OFFSET


def _rtb_flange(q):
    T = np.eye(4)
    for qi, (d, a, al) in zip(q, RTB_DH, strict=True):
        c, s, ca, sa = np.cos(qi), np.sin(qi), np.cos(np.radians(al)), np.sin(np.radians(al))
        T = T @ np.array(
            [[c, -s * ca, s * sa, a * c], [s, c * ca, -c * sa, a * s], [0, sa, ca, d], [0, 0, 0, 1]]
        )
    return T


def _file_flange(robot, q):
    f = frames(robot.nominal, q[None])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = f.R_last[0], f.o[0, -1]
    return T


def test_puma_is_the_toolbox_model_with_the_stated_offsets():
    robot = load_robot(EXAMPLES / "puma560" / "robot.toml")
    base = np.diag([-1.0, -1.0, 1.0, 1.0])  # the file's base: the Toolbox's turned 180° about z
    q0 = np.zeros(6)
    tool = np.linalg.inv(base @ _rtb_flange(q0)) @ _file_flange(robot, q0 + np.radians(OFFSET_DEG))
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, (50, 6)):
        got = _file_flange(robot, q + np.radians(OFFSET_DEG))
        np.testing.assert_allclose(got, base @ _rtb_flange(q) @ tool, atol=1e-9)


def test_puma_limits_are_the_toolboxs_mapped():
    robot = load_robot(EXAMPLES / "puma560" / "robot.toml")
    lo = np.array([lim[0] for lim in RTB_LIMITS]) + OFFSET_DEG
    hi = np.array([lim[1] for lim in RTB_LIMITS]) + OFFSET_DEG
    lo[1], hi[1] = lo[1] - 360, hi[1] - 360  # J2 [135, 405] is the same range as [-225, 45]
    np.testing.assert_array_equal(robot.joint_min_deg, lo)
    np.testing.assert_array_equal(robot.joint_max_deg, hi)
