"""A realistic encoder: Monte Carlo calibrations beside the error budget's prediction.

The Viper s650, its true encoder 500 ppm off scale (the robot file's tolerance 500 ppm),
the temperature rising 0.5 K over the run (drum 23 ppm/K, arm 12 ppm/K), reading noise
σ 0.01 mm; true offsets uniform within ±1 deg / ±1 mm. With and without the reference
step (a gauge of two nests 500 mm apart, certified to 0.002 mm, seated 3 times), on the
corrected paper plan and the designed plan (``wirecal plan``). Per case: the Monte Carlo
mean tool-point error over 1000 configurations (averaged over trials) and the budget's
predicted total, and their ratio; the goal: with the reference the joint method's mean
≤ 0.03 mm and within 1.3× the budget, without it the budget within 1.3× of the error.

    python bench/bench_encoder.py [--trials N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.app.coverage import with_gauge  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.plan.planner import design  # noqa: E402
from wirecal.solver.scale import ARM_PPM_PER_K  # noqa: E402
from wirecal.solver.simulate import TEMPERATURE_CHANGE_K, EncoderTruth  # noqa: E402

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
SCALE_PPM = 500.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    args = ap.parse_args()
    T = args.trials
    base = load_robot(VIPER / "robot.toml")
    without = replace(base, encoder=replace(base.encoder, scale_tolerance_ppm=SCALE_PPM))
    with_ref = with_gauge(without)
    true_encoder = EncoderTruth(
        scale_ppm=SCALE_PPM,
        temperature_change_k=TEMPERATURE_CHANGE_K,
        drum_ppm_per_k=base.encoder.temperature_coefficient_ppm_per_k,
        arm_ppm_per_k=ARM_PPM_PER_K,
    )
    plans = {
        "paper plan": load_plan(VIPER / "paper_plan.toml", base),
        "designed plan": design(base).plan,
    }
    truth = np.random.default_rng(1).uniform(-1, 1, (T, len(base.parameters)))
    print(
        f"{T} calibrations each; true scale +{SCALE_PPM:g} ppm, +{TEMPERATURE_CHANGE_K:g} K "
        "over the run; mean tool-point error over 1000 configurations (mm)"
    )
    print(
        f"{'plan':<15}{'reference':<11}{'method':<10}{'MC mean':>9}{'budget':>9}"
        f"{'MC/budget':>11}{'CRB':>8}{'scale left ppm':>16}{'s':>7}"
    )
    for plan_name, plan in plans.items():
        for ref_name, robot in (("yes", with_ref), ("no", without)):
            order = [robot.parameters.index(n) for n in plan.order]
            t0 = time.perf_counter()
            mc = montecarlo.run(
                robot, plan, truth[:, order], seed=5, encoder=true_encoder, noise_mm=0.01
            )
            seconds = time.perf_counter() - t0
            for method in ("joint", "stepwise"):
                got = mc.methods[method].tool_mean_mm
                pred = mc.budget[method].total
                print(
                    f"{plan_name:<15}{ref_name:<11}{method:<10}{got:9.4f}{pred:9.4f}"
                    f"{got / pred:11.2f}{mc.budget[method].terms['noise']:8.4f}"
                    f"{mc.scale_error_ppm:16.1f}{seconds:7.0f}"
                )


if __name__ == "__main__":
    main()
