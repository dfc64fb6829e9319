"""Inverse kinematics of the UR5e: the closed form (solver/ik/ur.py, Newton-polished) against
the numeric search that solved it before (damped least squares from 24 random starts and the
spherical-wrist seeds), on random reachable poses of the nominal and of a calibrated UR5e.

Per model: solutions found by each, the closed form's solutions the search missed, the
poses with a miss, the largest flange-position residual (mm) and the time per pose.

    python bench/bench_ik_ur.py [--poses N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from unittest import mock  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.ik import solutions as ik  # noqa: E402
from wirecal.solver.ik import ur as ik_ur  # noqa: E402

UR5 = Path(__file__).resolve().parents[1] / "examples" / "ur5e" / "robot.toml"


def _run(robot, model, poses):
    sols, residual = [], 0.0
    t0 = time.perf_counter()
    for R, o in poses:
        found = ik.solve(robot, R, o, model=model)
        sols.append(found)
        for s in found:
            residual = max(residual, float(np.linalg.norm(ik.flange_pose(model, s.q)[1] - o)))
    return sols, residual, (time.perf_counter() - t0) / len(poses)


def _same(a, b):
    return np.allclose((a - b + np.pi) % (2 * np.pi) - np.pi, 0, atol=1e-6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=200)
    args = ap.parse_args()
    robot = load_robot(UR5)
    lo, hi = robot.joint_min_deg, robot.joint_max_deg
    rng = np.random.default_rng(0)
    calibrated = robot.model(
        dict(zip(robot.parameters, rng.uniform(-1, 1, len(robot.parameters)), strict=True))
    )
    print(
        f"{'model':<12}{'method':<13}{'solutions':>10}{'missed':>8}{'poses':>7}"
        f"{'max resid. mm':>15}{'ms/pose':>9}"
    )
    for label, model in (("nominal", robot.nominal), ("calibrated", calibrated)):
        q = np.radians(lo + rng.uniform(0, 1, (args.poses, 6)) * (hi - lo))
        poses = [ik.flange_pose(model, x) for x in q]
        closed, res_c, t_c = _run(robot, model, poses)
        with mock.patch.object(ik_ur, "ur_structure", return_value=False):
            numeric, res_n, t_n = _run(robot, model, poses)
        missed = [
            sum(not any(_same(c.q, s.q) for s in n) for c in cl)
            for cl, n in zip(closed, numeric, strict=True)
        ]
        extra = sum(
            not any(_same(s.q, c.q) for c in cl)
            for cl, n in zip(closed, numeric, strict=True)
            for s in n
        )
        own = sum(any(_same(c.q, x) for c in cl) for cl, x in zip(closed, q, strict=True))
        print(
            f"{label:<12}{'closed form':<13}{sum(map(len, closed)):>10}{'':>8}{'':>7}"
            f"{res_c:>15.2e}{1000 * t_c:>9.1f}"
        )
        print(
            f"{'':<12}{'numeric':<13}{sum(map(len, numeric)):>10}{sum(missed):>8}"
            f"{sum(m > 0 for m in missed):>7}{res_n:>15.2e}{1000 * t_n:>9.1f}"
        )
        print(
            f"{'':<12}the closed form found the sampled configuration in {own} of "
            f"{args.poses} poses; the search found {extra} solution(s) it did not"
        )


if __name__ == "__main__":
    main()
