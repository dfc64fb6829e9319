"""Speed of the digital twin: the full Viper measurement program (wc.mount, wc.run) and the
controller solver (wc.solve, wc.solve2) run as written in the V+ interpreter.

    python bench/bench_twin.py
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from wirecal.gen.vplus.program import module_text
from wirecal.solver.formats.log import read_log
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.truth import load_errors
from wirecal.solver.measurements import load_measurements
from wirecal.solver.solve import solve
from wirecal.twin.cell import controller_solve, run_measurement
from wirecal.twin.vplus.parser import parse_module

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
TRUTH = load_errors(VIPER / "paper_table5_errors.toml", load_robot(VIPER / "robot.toml"))


def main() -> None:
    robot = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    text = module_text(robot, plan)
    t0 = time.perf_counter()
    parse_module(text, "WIRECAL.V2")
    t_parse = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = run_measurement(robot, plan, TRUTH, Path(tmp), seed=1, text=text)
        t_run = time.perf_counter() - t0
        assert result.run.status == "completed", result.run
        log = read_log(result.log)
        ref = solve(robot, plan, load_measurements(result.log, plan, robot))
        rows = []
        for polish, name, method in ((False, "wc.solve", "stepwise"), (True, "wc.solve2", "joint")):
            t0 = time.perf_counter()
            values, _, ops = controller_solve(
                robot, plan, log, Path(tmp) / name, polish=polish, text=text
            )
            rows.append(
                (
                    name,
                    time.perf_counter() - t0,
                    ops,
                    max(abs(values[n] - v) for n, v in ref.estimates[method].as_dict().items()),
                )
            )
    print(f"V+ module: {len(text.splitlines()):,} lines, parsed and checked in {t_parse:.2f} s")
    print(
        f"wc.mount + wc.run in the twin: {t_run:.2f} s (target 5 s); simulated robot time "
        f"{result.cell.clock / 60:.1f} min"
    )
    for name, t, ops, diff in rows:
        print(
            f"{name}: {t:.2f} s (target 2 s), {ops:,} arithmetic operations executed, "
            f"largest difference from the Python reference {diff:.1e} deg/mm"
        )


if __name__ == "__main__":
    main()
