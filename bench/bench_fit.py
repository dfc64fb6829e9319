"""``wirecal fit`` on simulated tables: held-out RMS of the cable length beside the floor.

Three arms (Viper s650, ABB IRB 120, UR5e), data sets of 100 to 2000 rows from
:func:`~wirecal.solver.fit_synth.synthetic_table`: random configurations in the middle 80 %
of the joint ranges, joints logged to 0.1°, lengths to 0.01 mm with 0.02 mm reading noise,
an anchor anywhere in the cell, three sessions with offset jumps of 3–30 mm, three snagged
and two mistyped rows. Per case (mean over the seeds): the held-out RMS (random 20 %,
5 repeats), the quantisation floor over the same rows, their ratio, the same with the joints
refined from the controller's x, y, z (--refine-joints), whether the sessions were found
within ±2 rows, and the time of one fit (one BLAS thread). Goal: ratio ≤ 1.2 from a few
hundred rows; 1000 rows in seconds.

    python bench/bench_fit.py [--seeds N]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.solver.fit_result import FitOptions, fit_table  # noqa: E402
from wirecal.solver.fit_synth import synthetic_table  # noqa: E402
from wirecal.solver.formats.robot_file import load_robot  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARMS = ("viper_s650", "abb_irb120", "ur5e")
SIZES = (100, 300, 1000, 2000)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    print(
        f"{'arm':<12}{'rows':>6}{'held-out':>10}{'floor':>8}{'ratio':>7}"
        f"{'refined':>9}{'floor':>8}{'ratio':>7}{'sessions':>10}{'fit s':>7}"
    )
    for arm in ARMS:
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        for n in SIZES:
            rows = []
            for seed in range(args.seeds):
                syn = synthetic_table(robot, n, seed=seed)
                t0 = time.perf_counter()
                fit_table(robot, syn.table, FitOptions(holdout="none"))
                seconds = time.perf_counter() - t0
                r = fit_table(robot, syn.table, FitOptions(refine_joints=True))
                m, f = r.main, r.refined
                assert f is not None
                found = np.array(m.core.starts)
                ok = found.size == len(syn.starts) and np.all(np.abs(found - syn.starts) <= 2)
                rows.append(
                    (
                        m.holdout.rms_mm,
                        m.holdout.floor_mm,
                        f.holdout.rms_mm,
                        f.holdout.floor_mm,
                        ok,
                        seconds,
                    )
                )
            a = np.array(rows, dtype=float)
            mean = a.mean(axis=0)
            print(
                f"{arm:<12}{n:>6}{mean[0]:>10.4f}{mean[1]:>8.4f}{mean[0] / mean[1]:>7.2f}"
                f"{mean[2]:>9.4f}{mean[3]:>8.4f}{mean[2] / mean[3]:>7.2f}"
                f"{int(a[:, 4].sum()):>6}/{args.seeds:<3}{mean[5]:>7.2f}"
            )


if __name__ == "__main__":
    main()
