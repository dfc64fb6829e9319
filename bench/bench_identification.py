"""Accuracy and speed of identification: Monte Carlo against known truth.

For the Viper s650 and the paper's plan (corrected, and as printed), many simulated
calibrations with σ = 0.01 mm per reading, the encoder's quantisation and zero readings:
per method the parameter RMS error and the tool-point error over 1,000 random
configurations within the joint limits, beside the Cramér–Rao bound of the plan
measured by the same statistic. Then the speed of one solve and of the Monte Carlo.

    python bench/bench_identification.py [--trials N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.formats.log import parse_log  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.simulated_log import simulate_log  # noqa: E402
from wirecal.formats.truth import load_errors  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.log.measurements import check_log  # noqa: E402
from wirecal.solver.solve import solve  # noqa: E402

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
TABLE5 = load_errors(VIPER / "paper_table5_errors.toml", load_robot(VIPER / "robot.toml"))


def table(title, mc):
    print(f"\n{title}  ({mc.trials} calibrations, σ = 0.01 mm)")
    print(
        f"  {'method':<10}{'param RMS deg':>15}{'param RMS mm':>14}"
        f"{'tool mean mm':>14}{'tool max mm':>13}{'× CRB':>8}"
    )
    rows = [*mc.methods.items(), ("CRB", mc.crb)]
    for name, f in rows:
        ratio = f.tool_mean_mm / mc.crb.tool_mean_mm
        print(
            f"  {name:<10}{f.param_rms_deg:15.4f}{f.param_rms_mm:14.4f}"
            f"{f.tool_mean_mm:14.4f}{f.tool_max_mm:13.4f}{ratio:8.2f}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=500)
    args = ap.parse_args()
    robot = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    printed = load_plan(VIPER / "paper_plan_as_printed.toml", robot)
    T = args.trials
    t5 = np.tile([TABLE5[n] for n in plan.order], (T, 1))
    uniform = np.random.default_rng(1).uniform(-1, 1, (T, len(plan.order)))

    mc = montecarlo.run(robot, plan, t5, seed=2)
    table("Corrected paper plan, errors of the paper's Table 5", mc)
    table(
        "Corrected paper plan, errors uniform within ±1 deg / ±1 mm",
        montecarlo.run(robot, plan, uniform, seed=3),
    )
    table(
        "Paper plan AS PRINTED (step 7 misprint), Table 5 errors",
        montecarlo.run(robot, printed, t5, seed=4),
    )

    print("\nSpeed (one core)")
    for name, f in mc.methods.items():
        print(
            f"  Monte Carlo, {name:<8}: {f.rate(T):7.0f} calibrations/s"
            + ("  (includes its stepwise start)" if name == "joint" else "  (batched)")
        )
    text = simulate_log(robot, plan, TABLE5, seed=7)
    m = check_log(parse_log(text, "bench.csv"), plan, robot)
    solve(robot, plan, m)  # warm-up
    times = []
    for _ in range(30):
        t0 = time.perf_counter()
        solve(robot, plan, m)
        times.append(time.perf_counter() - t0)
    print(
        f"  one solve, both methods + predicted accuracy, 69 points: "
        f"{1e3 * np.median(times):.1f} ms (median of 30)"
    )


if __name__ == "__main__":
    main()
