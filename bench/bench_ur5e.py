"""The UR5e: Monte Carlo on its shipped plan, and the URScript chain's speed in the twin.

Many simulated calibrations of the UR5e with its plan (examples/ur5e/plan.toml), σ = 0.01 mm
per reading, the encoder's quantisation and the zero readings: per method the parameter
RMS error and the tool-point error over 1,000 random configurations within the joint
limits, beside the Cramér–Rao bound of the plan by the same statistic. Then the time of
one measurement run of the generated wc_run in the twin (the log through wirecal receive
over loopback) and of the whole ``wirecal demo --robot examples/ur5e/robot.toml``.

    python bench/bench_ur5e.py [--trials N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.app.demo import run_demo  # noqa: E402
from wirecal.app.twin_runs import generate, measure_in_twin  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.truth import random_errors  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402

UR5E = Path(__file__).resolve().parents[1] / "examples" / "ur5e"


def table(title: str, mc) -> None:
    print(f"\n{title}  ({mc.trials} calibrations, σ = 0.01 mm)")
    print(
        f"  {'method':<10}{'param RMS deg':>15}{'param RMS mm':>14}"
        f"{'tool mean mm':>14}{'tool max mm':>13}{'× CRB':>8}"
    )
    for name, f in [*mc.methods.items(), ("CRB", mc.crb)]:
        ratio = f.tool_mean_mm / mc.crb.tool_mean_mm
        print(
            f"  {name:<10}{f.param_rms_deg:15.4f}{f.param_rms_mm:14.4f}"
            f"{f.tool_mean_mm:14.4f}{f.tool_max_mm:13.4f}{ratio:8.2f}"
        )
    print(f"  before calibration: tool mean {mc.before_mm:.4f} mm")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=500)
    args = ap.parse_args()
    robot = load_robot(UR5E / "robot.toml")
    plan = load_plan(UR5E / "plan.toml", robot)
    uniform = np.random.default_rng(1).uniform(-1, 1, (args.trials, len(plan.order)))
    table(
        f"UR5e, its plan ({plan.n_points} points), errors uniform within ±1 deg / ±1 mm",
        montecarlo.run(robot, plan, uniform, seed=3),
    )

    print("\nThe URScript chain in the twin (one core)")
    texts = generate(robot, plan)
    truth = random_errors(robot, 1.0, np.random.default_rng([1, 1]))
    times = []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(5):
            t0 = time.perf_counter()
            run = measure_in_twin(robot, plan, truth, Path(tmp) / str(k), texts, seed=k)
            times.append(time.perf_counter() - t0)
            assert run.complete
        clock = run.world.clock
        print(
            f"  wc_mount + wc_run, {plan.n_points} points, through wirecal receive: "
            f"{1e3 * np.median(times):.0f} ms (median of 5) for {clock:.0f} s of robot time"
        )
        t0 = time.perf_counter()
        run_demo(Path(tmp) / "demo", robot=UR5E / "robot.toml")
        print(f"  wirecal demo --robot examples/ur5e/robot.toml: {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
