"""Robot time against accuracy, for the Viper s650: the paper's run and the time-optimal one.

For three runs — the paper plan at the paper's settings (20 % speed, 3 s settle), the
designed plan (``wirecal plan``) at the same settings, and the designed plan's
time-optimal run (each move at the SPEED the wire allows, the settle rule, the readings
per point from the noise model) — prints:

* the robot time of a run of the generated module on the digital twin, from its log's
  ``t_s`` column (the last reading's t_s plus its sampling), beside the time model's
  (:func:`~wirecal.solver.run_parameters.run_timeline`) and the twin's clock;
* the Cramér–Rao bound (as ``wirecal plan`` predicts it: mean over the workspace, σ
  0.01 mm; and at the Monte Carlo's truth with the zero readings' error) and the Monte
  Carlo joint and stepwise tool-point errors
  (σ = 0.01 mm readings plus the quantisation, the paper's Table 5 errors), mean over
  1,000 configurations;
* with ``--twin-trials K``: the joint and stepwise tool-point errors of K runs on the twin
  per run setting, each log solved: the twin adds what the Monte Carlo does not model —
  the counter's jitter over the readings and the vibration the settle rule waits out.

    python bench/bench_robot_time.py [--plan designed.toml] [--trials N] [--twin-trials K]
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

from wirecal.app.twin_runs import measure_in_twin  # noqa: E402
from wirecal.formats.log import load_measurements, read_log  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.truth import load_errors  # noqa: E402
from wirecal.gen.request import GenRequest  # noqa: E402
from wirecal.solver import montecarlo  # noqa: E402
from wirecal.solver.accuracy import workspace  # noqa: E402
from wirecal.solver.params import ErrorSet  # noqa: E402
from wirecal.solver.plan.planner import design  # noqa: E402
from wirecal.solver.plan.predict import predicted_accuracy  # noqa: E402
from wirecal.solver.run_parameters import (  # noqa: E402
    DEFAULT_RUN,
    PAPER_RUN,
    READING_INTERVAL_S,
    RunParameters,
    run_timeline,
)
from wirecal.solver.solve import solve  # noqa: E402

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"


def twin_time_s(robot, plan, run: RunParameters, truth: dict[str, float]) -> tuple[float, float]:
    """Robot time from the twin's log (last t_s plus its sampling), and the twin's clock."""
    with tempfile.TemporaryDirectory() as folder:
        r = measure_in_twin(robot, plan, truth, Path(folder), request=GenRequest(run=run), seed=1)
        if r.run is None or r.run.status != "completed":
            raise SystemExit(f"the twin's run did not complete: {r.run}")
        last = read_log(r.log).readings[-1]
        return last.t_s + READING_INTERVAL_S * (last.samples - 1), r.world.clock - 0.5


def twin_accuracy(robot, plan, run: RunParameters, truth: dict[str, float], trials: int):
    """Mean tool-point error (mm) of the joint and stepwise estimates from twin runs' logs."""
    errors = ErrorSet(plan.order, robot.n_joints)
    true = errors.to_internal([truth[n] for n in plan.order])[None]
    q_ws = workspace(robot, 1000)
    out: dict[str, list[float]] = {"joint": [], "stepwise": []}
    for seed in range(trials):
        with tempfile.TemporaryDirectory() as folder:
            r = measure_in_twin(
                robot, plan, truth, Path(folder), request=GenRequest(run=run), seed=100 + seed
            )
            result = solve(robot, plan, load_measurements(r.log, plan, robot))
        for method, errs in out.items():
            est = errors.to_internal(result.estimates[method].values)[None]
            errs.append(float(montecarlo.tool_errors(robot, plan.order, est, true, q_ws).mean()))
    return {method: float(np.mean(errs)) for method, errs in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plan", help="the designed plan (default: design it now, as wirecal plan)")
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--twin-trials", type=int, default=0)
    args = ap.parse_args()
    robot = load_robot(VIPER / "robot.toml")
    table5 = load_errors(VIPER / "paper_table5_errors.toml", robot)
    paper = load_plan(VIPER / "paper_plan.toml", robot)
    t0 = time.perf_counter()
    designed = load_plan(args.plan, robot) if args.plan else design(robot, None).plan
    print(f"designed plan: {designed.n_points} points ({time.perf_counter() - t0:.0f} s)")
    runs = (
        ("paper plan, 20 %, 3 s settle", paper, PAPER_RUN),
        ("designed plan, 20 %, 3 s settle", designed, PAPER_RUN),
        ("designed plan, time-optimal", designed, DEFAULT_RUN),
    )
    print(
        f"\n{'run':<34}{'points':>7}{'log t_s':>10}{'model':>9}{'clock':>9}"
        f"{'plan CRB':>10}{'MC CRB':>9}{'MC joint':>10}{'MC step':>9}"
    )
    print(f"{'':<34}{'':>7}{'min':>10}{'min':>9}{'min':>9}{'mm':>10}{'mm':>9}{'mm':>10}{'mm':>9}")
    for name, plan, run in runs:
        log_s, clock_s = twin_time_s(robot, plan, run, table5)
        model_s = run_timeline(robot, plan, run).total_s
        truths = np.tile([table5[n] for n in plan.order], (args.trials, 1))
        mc = montecarlo.run(robot, plan, truths, seed=2)
        print(
            f"{name:<34}{plan.n_points:>7}{log_s / 60:>10.2f}{model_s / 60:>9.2f}"
            f"{clock_s / 60:>9.2f}{predicted_accuracy(robot, plan)['joint']:>10.4f}"
            f"{mc.crb.tool_mean_mm:>9.4f}"
            f"{mc.methods['joint'].tool_mean_mm:>10.4f}{mc.methods['stepwise'].tool_mean_mm:>9.4f}"
        )
    if args.twin_trials:
        print(f"\ntwin runs solved ({args.twin_trials} per setting, Table 5 errors): mean mm")
        for name, plan, run in runs:
            acc = twin_accuracy(robot, plan, run, table5, args.twin_trials)
            print(f"{name:<34} joint {acc['joint']:.4f}   stepwise {acc['stepwise']:.4f}")
    print(
        f"\ntime-optimal run: highest SPEED {DEFAULT_RUN.speed_pct:g} % where the wire allows "
        f"(max_wire_speed_mm_s {robot.encoder.max_wire_speed_mm_s:g}, max_wire_accel_mm_s2 "
        f"{robot.encoder.max_wire_accel_mm_s2:g}), settle rule (max "
        f"{DEFAULT_RUN.settle_max_s:g} s), {DEFAULT_RUN.readings} readings per point"
    )


if __name__ == "__main__":
    main()
