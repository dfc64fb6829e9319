"""Design of experiments: 'wirecal plan' on every shipped arm, and the Viper's designed
plan beside the corrected paper plan.

Per arm: the planning time (θ0 chosen, one core), points, via points, estimated robot
time, the predicted tool-point error (Cramér–Rao for the joint method, the linearised
stepwise map with its leaks) and a Monte Carlo (uniform ±1 deg / ±1 mm errors, σ 0.01 mm)
against the tool-point error before calibration.

    python bench/bench_planning.py [--trials N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.formats.plan_file import load_plan  # noqa: E402
from wirecal.solver.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.formats.truth import load_errors  # noqa: E402
from wirecal.solver.planner import design, predicted_accuracy, robot_time  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARMS = ("viper_s650", "puma560", "abb_irb120", "ur5")
TABLE5 = load_errors(
    EXAMPLES / "viper_s650" / "paper_table5_errors.toml",
    load_robot(EXAMPLES / "viper_s650" / "robot.toml"),
)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    args = ap.parse_args()
    T = args.trials
    print(
        f"{'arm':<22}{'plan s':>8}{'points':>8}{'vias':>6}{'robot min':>11}"
        f"{'CRB mm':>9}{'stepw. mm':>11}{'MC before':>11}{'MC joint':>10}{'MC stepw.':>11}"
    )
    designs = {}
    for arm in ARMS:
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        t0 = time.perf_counter()
        d = design(robot)
        seconds = time.perf_counter() - t0
        designs[arm] = (robot, d)
        truth = np.random.default_rng(1).uniform(-1, 1, (T, len(d.plan.order)))
        mc = montecarlo.run(robot, d.plan, truth, seed=3)
        vias = sum(len(s.via_deg) for s in d.plan.steps)
        print(
            f"{robot.name:<22}{seconds:8.1f}{d.plan.n_points:8d}{vias:6d}"
            f"{d.robot_time_s / 60:11.2f}{d.predicted['joint']:9.4f}"
            f"{d.predicted['stepwise']:11.4f}{mc.before_mm:11.3f}"
            f"{mc.methods['joint'].tool_mean_mm:10.4f}"
            f"{mc.methods['stepwise'].tool_mean_mm:11.4f}"
        )

    robot, d = designs["viper_s650"]
    paper = load_plan(EXAMPLES / "viper_s650" / "paper_plan.toml", robot)
    print(
        f"\nViper s650: designed plan (θ0 {np.round(d.plan.theta0_deg).tolist()}) vs the "
        f"corrected paper plan; Monte Carlo {T} calibrations, σ 0.01 mm"
    )
    print(
        f"  {'plan':<10}{'points':>8}{'robot min':>11}{'CRB mm':>9}{'pred. stepw.':>14}"
        f"{'MC T5 joint':>13}{'MC T5 stepw.':>14}{'MC ±1 joint':>13}{'MC ±1 stepw.':>14}"
    )
    for label, plan in (("designed", d.plan), ("paper", paper)):
        pred = predicted_accuracy(robot, plan)
        t5 = np.tile([TABLE5[n] for n in plan.order], (T, 1))
        uniform = np.random.default_rng(1).uniform(-1, 1, (T, len(plan.order)))
        a = montecarlo.run(robot, plan, t5, seed=2).methods
        b = montecarlo.run(robot, plan, uniform, seed=3).methods
        print(
            f"  {label:<10}{plan.n_points:8d}{robot_time(robot, plan) / 60:11.2f}"
            f"{pred['joint']:9.4f}{pred['stepwise']:14.4f}"
            f"{a['joint'].tool_mean_mm:13.4f}{a['stepwise'].tool_mean_mm:14.4f}"
            f"{b['joint'].tool_mean_mm:13.4f}{b['stepwise'].tool_mean_mm:14.4f}"
        )
    print(
        "\n  tool-point errors: mean over 1,000 configurations within the limits (mm);"
        "\n  T5: the paper's Table 5 errors; ±1: uniform within ±1 deg / ±1 mm"
    )


if __name__ == "__main__":
    main()
