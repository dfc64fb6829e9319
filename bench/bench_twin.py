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

from wirecal.app.compare import controller_solve
from wirecal.app.twin_runs import generate, measure_in_twin
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.formats.log import load_measurements, parse_log
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.simulated_log import simulate_log
from wirecal.solver.formats.truth import load_errors
from wirecal.solver.measurements import check_log
from wirecal.solver.solve import solve

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
TRUTH = load_errors(VIPER / "paper_table5_errors.toml", load_robot(VIPER / "robot.toml"))
METHODS = (("wc.solve", "stepwise", False), ("wc.solve2", "joint", True))


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
        for _, method, polish in METHODS:
            run = controller_solve(robot, plan, m, disk / method, polish=polish, text=text)
            worst[method] = max(worst[method], largest_difference(run, ref, method))
    return worst


def main() -> None:
    robot = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    (text,) = generate(robot, plan).values()
    t0 = time.perf_counter()
    parse_module(text, "WIRECAL.V2")
    t_parse = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = measure_in_twin(robot, plan, TRUTH, Path(tmp), {"WIRECAL.V2": text}, seed=1)
        t_run = time.perf_counter() - t0
        assert result.run.status == "completed", result.run
        m = load_measurements(result.log, plan, robot)
        ref = solve(robot, plan, m)
        rows = []
        for name, method, polish in METHODS:
            t0 = time.perf_counter()
            run = controller_solve(robot, plan, m, Path(tmp) / name, polish=polish, text=text)
            rows.append((name, time.perf_counter() - t0, run, largest_difference(run, ref, method)))
        worst = random_truths(robot, plan, text, Path(tmp) / "truths")
    print(f"V+ module: {len(text.splitlines()):,} lines, parsed and checked in {t_parse:.2f} s")
    print(
        f"wc.mount + wc.run in the twin: {t_run:.2f} s (target 5 s); simulated robot time "
        f"{result.world.clock / 60:.1f} min"
    )
    for name, t, run, diff in rows:
        ops = run.operations
        print(
            f"{name}: {t:.2f} s (target 2 s), {run.total_operations:,} arithmetic operations "
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
