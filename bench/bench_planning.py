"""Design of experiments: 'wirecal plan' on every shipped arm, and the Viper's designed
plan beside the corrected paper plan.

First the cost of planning: per arm and design (--for joint, --for stepwise) the whole
'wirecal plan' process, median wall-clock and CPU seconds over --repeat runs and its peak
resident memory (one core). Then per arm and design: points, via points, estimated robot
time, the predicted tool-point error (Cramér–Rao for the joint method, the linearised
stepwise map with its leaks) and a Monte Carlo (uniform ±1 deg / ±1 mm errors, σ 0.01 mm)
against the tool-point error before calibration.

    python bench/bench_planning.py [--trials N] [--repeat R]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.app.progress import ProgressBar  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.truth import load_errors  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.plan.options import PlanOptions  # noqa: E402
from wirecal.solver.plan.planner import design  # noqa: E402
from wirecal.solver.plan.predict import predicted_accuracy, robot_time  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARMS = ("viper_s650", "puma560", "abb_irb120", "ur5e")
TABLE5 = load_errors(
    EXAMPLES / "viper_s650" / "paper_table5_errors.toml",
    load_robot(EXAMPLES / "viper_s650" / "robot.toml"),
)


def plan_process(arm: str, method: str) -> tuple[float, float, float]:
    """Run 'wirecal plan' on an arm once: wall-clock s, CPU s and peak resident MiB."""
    cmd = [sys.executable, "-m", "wirecal.cli.main", "plan", str(EXAMPLES / arm / "robot.toml")]
    t0 = time.perf_counter()
    proc = subprocess.Popen([*cmd, "--for", method], stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t0
    if status:
        raise SystemExit(f"wirecal plan {arm} --for {method} failed ({status})")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


METHODS = ("joint", "stepwise")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--repeat", type=int, default=3, help="'wirecal plan' runs per arm")
    args = ap.parse_args()
    print_plan_costs(args.repeat)
    designs = print_designs(args.trials)
    print_viper_plans(designs, args.trials)


def print_plan_costs(repeat: int) -> None:
    """Print each arm's and design's 'wirecal plan' process: median wall, CPU, peak memory."""
    runs = {}
    with ProgressBar("timing 'wirecal plan'") as bar:
        for k, (arm, method) in enumerate((a, m) for a in ARMS for m in METHODS):
            runs[arm, method] = [plan_process(arm, method) for _ in range(repeat)]
            bar.update((k + 1) / (len(ARMS) * len(METHODS)))
    print(f"'wirecal plan', median of {repeat} runs (whole process, one core)")
    print(f"{'arm':<12}{'design':<10}{'wall s':>8}{'CPU s':>8}{'peak MiB':>10}")
    for (arm, method), r in runs.items():
        wall, cpu, mib = np.median(np.array(r), axis=0)
        print(f"{arm:<12}{method:<10}{wall:8.1f}{cpu:8.1f}{mib:10.0f}")


def print_designs(T: int) -> dict:
    """Print each arm's designs with a Monte Carlo of T calibrations; return the designs."""
    print(
        f"\n{'arm':<22}{'design':<10}{'plan s':>8}{'points':>8}{'vias':>6}{'robot min':>11}"
        f"{'CRB mm':>9}{'stepw. mm':>11}{'MC before':>11}{'MC joint':>10}{'MC stepw.':>11}"
    )
    designs = {}
    with ProgressBar("designing and Monte Carlo") as bar:
        rows = []
        for k, (arm, method) in enumerate((a, m) for a in ARMS for m in METHODS):
            robot = load_robot(EXAMPLES / arm / "robot.toml")
            t0 = time.perf_counter()
            d = design(robot, opt=PlanOptions(method=method))
            seconds = time.perf_counter() - t0
            designs[arm, method] = (robot, d)
            truth = np.random.default_rng(1).uniform(-1, 1, (T, len(d.plan.order)))
            mc = montecarlo.run(robot, d.plan, truth, seed=3)
            vias = sum(len(s.via_deg) for s in d.plan.steps)
            rows.append(
                f"{robot.name:<22}{method:<10}{seconds:8.1f}{d.plan.n_points:8d}{vias:6d}"
                f"{d.robot_time_s / 60:11.2f}{d.predicted['joint']:9.4f}"
                f"{d.predicted['stepwise']:11.4f}{mc.before_mm:11.3f}"
                f"{mc.methods['joint'].tool_mean_mm:10.4f}"
                f"{mc.methods['stepwise'].tool_mean_mm:11.4f}"
            )
            bar.update((k + 1) / (len(ARMS) * len(METHODS)))
    print("\n".join(rows))
    return designs


def print_viper_plans(designs: dict, T: int) -> None:
    """Print the Viper's designed plans beside the corrected paper plan (Monte Carlo of T)."""
    robot, d = designs["viper_s650", "joint"]
    _, ds = designs["viper_s650", "stepwise"]
    paper = load_plan(EXAMPLES / "viper_s650" / "paper_plan.toml", robot)
    print(
        "\nViper s650: designed plans (--for joint, --for stepwise) vs the corrected paper "
        f"plan; Monte Carlo {T} calibrations, σ 0.01 mm"
    )
    print(
        f"  {'plan':<10}{'points':>8}{'robot min':>11}{'CRB mm':>9}{'pred. stepw.':>14}"
        f"{'MC T5 joint':>13}{'MC T5 stepw.':>14}{'MC ±1 joint':>13}{'MC ±1 stepw.':>14}"
    )
    for label, plan in (("joint", d.plan), ("stepwise", ds.plan), ("paper", paper)):
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
