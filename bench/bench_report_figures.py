"""What the report's figures cost: Ψ, residuals, correlations and a validation histogram.

Per shipped example (its plan, a simulated run with true errors within ±1 deg/mm, seed
5), the CPU time (``time.process_time``) of each figure of ``wirecal report``
(:mod:`wirecal.app.report`, matplotlib's Agg drawing and PNG writing included), every
figure drawn once unmeasured first (matplotlib imported, its fonts loaded; the Ψ figure
of a Ψ twice as large, not the one measured). "psi, another run": the Ψ figure of the
report of a second run of the plan (seed 6: other errors, other readings, the same Ψ), as
the tests report run after run of one plan. With
``--before`` (a checkout of the code before), each run a fresh process per tree, the two
trees' runs interleaved (:mod:`interleaved`), medians and the ratio now / before, and
whether the two drew the same PNG files, byte for byte.

    python bench/bench_report_figures.py [--runs N] [--before CHECKOUT]
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

from interleaved import bench_main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SHIPPED = ("viper_s650", "ur5e", "abb_irb120")


def _figures() -> tuple[dict, list]:
    """Return each figure's drawing (name → call returning its PNG data URI), and warm-ups."""
    from dataclasses import replace

    import numpy as np

    from wirecal.app import report
    from wirecal.app.demo import plan_beside
    from wirecal.formats.log import parse_log
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.formats.simulated_log import simulate_log
    from wirecal.formats.truth import random_errors
    from wirecal.solver.log.measurements import check_log
    from wirecal.solver.solve import solve
    from wirecal.solver.validation.analysis import Stats

    def run(robot, plan, seed: int):
        errors = random_errors(robot, 1.0, np.random.default_rng(seed))
        text = simulate_log(robot, plan, errors, seed=seed)
        return solve(robot, plan, check_log(parse_log(text, "run.csv"), plan, robot))

    draw, warm = {}, []
    for name in SHIPPED:
        robot = load_robot(EXAMPLES / name / "robot.toml")
        plan_path = plan_beside(EXAMPLES / name / "robot.toml")
        assert plan_path is not None
        plan = load_plan(plan_path, robot)
        result, another = run(robot, plan, 5), run(robot, plan, 6)
        joint = result.estimates["joint"]
        doubled = replace(result, psi=2 * result.psi)
        warm.append(lambda r=doubled: report.psi_figure(r))
        draw[f"{name} psi"] = lambda r=result: report.psi_figure(r)
        draw[f"{name} psi, another run"] = lambda r=another: report.psi_figure(r)
        if "stepwise" in result.estimates:
            draw[f"{name} residuals"] = lambda r=result: report.residual_figure(r)
        draw[f"{name} correlation"] = lambda j=joint: report.correlation_figure(
            j.names, j.correlation
        )
    rng = np.random.default_rng(1)
    before, after = Stats.of(rng.gamma(2, 0.2, 40)), Stats.of(rng.gamma(2, 0.03, 40))
    draw["histogram"] = lambda: report.histogram_figure(
        report.Validation("configuration", before, after)
    )
    return draw, warm


def child() -> None:
    """One run in this process: print each figure's CPU seconds and PNG digest as JSON."""
    draw, warm = _figures()
    for work in warm + [w for name, w in draw.items() if "psi" not in name]:
        work()
    found: dict[str, dict] = {"cpu_s": {}, "digest": {}}
    for name, work in draw.items():
        t0 = time.process_time()
        uri = work()
        found["cpu_s"][name] = time.process_time() - t0
        found["digest"][name] = hashlib.sha256(uri.encode()).hexdigest()[:16]
    found["cpu_s"]["all figures"] = sum(found["cpu_s"].values())
    print(json.dumps(found))


def main() -> None:
    """Time this tree and ``--before``'s alternately; print the medians and ratios."""
    bench_main("bench_report_figures", child, __doc__, "PNG files")


if __name__ == "__main__":
    main()
