"""The plausibility gate at the paper's run settings with a zero drift: passed, removed, error.

The Viper s650 and the paper plan; each trial a run at the paper's settings (20 % speed, 3 s
settle: ``PAPER_RUN``) on a realistic encoder with the given zero drift, true offsets within
±1 deg/mm, solved as ``wirecal solve`` does. Per drift: how many runs the gate passes, the
drift's measured rate and σ (medians), how many were removed with a warning, and the median
tool-point error against the truth after calibration (mm).

    python bench/bench_drift_gate.py [--trials 20] [--drift 1.0]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.app.coverage import simulated_calibration  # noqa: E402
from wirecal.app.demo import example_files  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.truth import random_errors  # noqa: E402
from wirecal.solver.accuracy import error_vs_truth_mm, workspace  # noqa: E402
from wirecal.solver.plausibility import assess  # noqa: E402
from wirecal.solver.run_parameters import PAPER_RUN  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--drift", type=float, default=1.0, help="mm/h")
    args = ap.parse_args()
    files = example_files()
    robot = load_robot(files["robot"])
    plan = load_plan(files["plan"], robot)
    q = workspace(robot)
    passed = warned = 0
    rates, sigmas, errors = [], [], []
    for seed in range(args.trials):
        truth = random_errors(robot, 1.0, np.random.default_rng([seed, 1]))
        result, _ = simulated_calibration(
            robot, plan, truth, seed, drift_mm_per_h=args.drift, run=PAPER_RUN
        )
        verdict = assess(result, result.recommended)
        passed += verdict.passed
        drift = result.drift
        assert drift is not None
        rates.append(drift.rate_mm_per_h)
        sigmas.append(drift.std_mm_per_h)
        warned += drift.warning is not None
        estimate = result.estimates[result.recommended].as_dict()
        errors.append(error_vs_truth_mm(robot, truth, estimate, q))
    print(f"zero drift {args.drift:g} mm/h, paper run settings, {args.trials} runs")
    print(f"  gate passed          {passed} of {args.trials}")
    print(f"  removed with warning {warned} of {args.trials}")
    print(f"  measured rate        {np.median(rates):.3f} mm/h (median), σ {np.median(sigmas):.3f}")
    print(f"  tool-point error     {np.median(errors):.4f} mm (median, vs truth)")


if __name__ == "__main__":
    main()
