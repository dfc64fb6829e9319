"""Speed and accuracy of the digital twin: the full Viper measurement program (wc.mount,
wc.run) and the controller solver (wc.solve, wc.solve2) run as written in the V+
interpreter, which also counts the arithmetic they execute; then the interpreted controller
solver against the Python reference on 12 random truths within ±4.5 deg/mm (every third
with a counter that wraps during the run).

    python bench/bench_twin.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from wirecal.app.compare import controller_runs
from wirecal.app.twin_runs import generate, measure_in_twin
from wirecal.formats.log import load_measurements, parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import load_errors
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
TRUTH = load_errors(VIPER / "paper_table5_errors.toml", load_robot(VIPER / "robot.toml"))
METHODS = ("stepwise", "joint")  # wc.solve, wc.solve2


def largest_difference(run, ref, method: str) -> float:
    return max(abs(run.offsets[n] - v) for n, v in ref.estimates[method].as_dict().items())


def random_truths(robot, plan, text: str, disk: Path, seeds=range(12)) -> dict[str, float]:
    """Largest difference of wc.solve / wc.solve2 from the reference over the seeds."""
    worst = {"stepwise": 0.0, "joint": 0.0}
    for seed in seeds:
        rng = np.random.default_rng([seed, 77])
        truth = dict(zip(robot.parameters, rng.uniform(-4.5, 4.5, 10), strict=True))
        start = 2**23 - 15_000 if seed % 3 == 0 else None
        log = simulate_log(robot, plan, truth, seed=seed, counter_start=start)
        m = check_log(parse_log(log, f"seed{seed}.csv"), plan, robot)
        ref = solve(robot, plan, m)
        runs = controller_runs(robot, plan, m, disk / f"seed{seed}", programs={"WIRECAL.V2": text})
        for method in METHODS:
            worst[method] = max(worst[method], largest_difference(runs[method], ref, method))
    return worst


def main() -> None:
    robot = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    (text,) = generate(robot, plan).values()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = measure_in_twin(robot, plan, TRUTH, Path(tmp), {"WIRECAL.V2": text}, seed=1)
        t_run = time.perf_counter() - t0
        assert result.run.status == "completed", result.run
        m = load_measurements(result.log, plan, robot)
        ref = solve(robot, plan, m)
        t0 = time.perf_counter()
        runs = controller_runs(robot, plan, m, Path(tmp) / "solve", programs={"WIRECAL.V2": text})
        t_solve = time.perf_counter() - t0
        rows = [(runs[k], largest_difference(runs[k], ref, k)) for k in METHODS]
        worst = random_truths(robot, plan, text, Path(tmp) / "truths")
    print(f"V+ module: {len(text.splitlines()):,} lines (parsed and checked by its generation)")
    print(
        f"wc.mount + wc.run in the twin: {t_run:.2f} s (target 5 s); simulated robot time "
        f"{result.world.clock / 60:.1f} min"
    )
    print(f"wc.solve and wc.solve2 in the twin: {t_solve:.2f} s together (target 2 s each)")
    for run, diff in rows:
        ops = run.operations
        print(
            f"{run.program}: {run.total_operations:,} arithmetic operations "
            f"executed ({ops['add']:,} add/sub, {ops['mul']:,} mul, {ops['div']:,} div, "
            f"{ops['sqrt']:,} SQRT), largest difference from the Python reference "
            f"{diff:.1e} deg/mm"
        )
    print(
        "interpreted controller vs Python reference, 12 random truths within ±4.5 deg/mm "
        f"(4 with a wrapping counter): wc.solve {worst['stepwise']:.1e}, "
        f"wc.solve2 {worst['joint']:.1e} deg/mm (tests: ≤ 1e-5 and ≤ 1e-4)"
    )


if __name__ == "__main__":
    main()
