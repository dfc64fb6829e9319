"""What a generation costs, per language: the pre-flight, the rendering, the checker.

``Generator.programs()`` = the pre-flight (limits, wire range, cell, software line) +
the language's rendering + its own checker over the output (issue 33). For each shipped
example, the median of a few runs of each part and of the whole, and the checker's share
of the whole; the checker's memory of checked texts is cleared before each run (V+'s
parser keeps its last few modules itself: its rendering has parsed the text already).

    python bench/bench_generation.py [--runs N]
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from pathlib import Path

from wirecal.app.demo import plan_beside
from wirecal.app.languages import registered
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.gen.preflight import _lint, output_problems, preflight
from wirecal.gen.request import GenRequest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SHIPPED = ("viper_s650", "ur5e", "abb_irb120")
"""The examples timed, each with its shipped plan (the demo's, :func:`plan_beside`)."""


def median_s(work: Callable[[], object], runs: int) -> float:
    """Median wall time (s) of ``runs`` calls of ``work``, the checker's memory cleared."""
    times = []
    for _ in range(runs):
        _lint.cache_clear()
        t0 = time.perf_counter()
        work()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def row(name: str, runs: int) -> str:
    """Return one example's line: each part's median and the checker's share."""
    robot = load_robot(EXAMPLES / name / "robot.toml")
    plan_path = plan_beside(EXAMPLES / name / "robot.toml")
    assert plan_path is not None
    plan = load_plan(plan_path, robot)
    gen, request = registered(robot).generator, GenRequest()
    out = gen.render(robot, plan, request)
    pre = median_s(lambda: preflight(robot, plan, request, gen.language), runs)
    render = median_s(lambda: gen.render(robot, plan, request), runs)
    check = median_s(lambda: output_problems(robot, out, gen.language), runs)
    whole = median_s(lambda: gen.programs(robot, plan, request), runs)
    return (
        f"{name:12} {gen.key:9} {pre:9.3f}s {render:6.3f}s {check:7.3f}s {whole:10.3f}s "
        f"{check / whole:6.0%}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    print("example      language  pre-flight  render  checker  programs()  checker share")
    for name in SHIPPED:
        print(row(name, args.runs))


if __name__ == "__main__":
    main()
