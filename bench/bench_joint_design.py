"""Predicted accuracy against robot time: plans for the joint method and for the
stepwise method, 20…80 points, on the Viper s650 (θ0 fixed, the stepwise design's).

Per plan: points, estimated robot time, the Cramér–Rao tool-point error (joint method)
and the linearised stepwise prediction with its leaks (mean over the workspace, σ 0.01 mm).
The joint design takes the points in all; the stepwise design points/10 per step.

    python bench/bench_joint_design.py [--mc TRIALS]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.app.progress import ProgressBar  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.plan.options import PlanOptions  # noqa: E402
from wirecal.solver.plan.planner import design  # noqa: E402

ROBOT = Path(__file__).resolve().parents[1] / "examples" / "viper_s650" / "robot.toml"
THETA0 = np.array([-72, -156, 235, 3, 64, 41], float)
POINTS = range(20, 81, 10)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mc", type=int, default=0, help="Monte Carlo trials per plan (0: none)")
    args = ap.parse_args()
    robot = load_robot(ROBOT)
    rows = []
    with ProgressBar("designing 14 plans") as bar:
        for k, n in enumerate(POINTS):
            for m, method in enumerate(("joint", "stepwise")):
                opt = (
                    PlanOptions(method="joint", points=n)
                    if method == "joint"
                    else PlanOptions(method="stepwise", points_per_step=n // 10)
                )
                d = design(robot, THETA0, opt)
                mc = None
                if args.mc:
                    truth = np.random.default_rng(1).uniform(-1, 1, (args.mc, len(d.plan.order)))
                    mc = montecarlo.run(robot, d.plan, truth, seed=3).methods
                rows.append((n, method, d, mc))
                bar.update((2 * k + m + 1) / (2 * len(POINTS)))
    head = (
        f"{'points':>6} {'design':<9}{'robot min':>10}{'CRB joint mm':>14}{'pred. stepw. mm':>17}"
    )
    if args.mc:
        head += f"{'MC joint':>10}{'MC stepw.':>11}"
    print(head)
    for n, method, d, mc in rows:
        line = (
            f"{n:6d} {method:<9}{d.robot_time_s / 60:10.2f}{d.predicted['joint']:14.4f}"
            f"{d.predicted['stepwise']:17.4f}"
        )
        if mc:
            line += f"{mc['joint'].tool_mean_mm:10.4f}{mc['stepwise'].tool_mean_mm:11.4f}"
        print(line)


if __name__ == "__main__":
    main()
