"""The public ``wirecal`` package: every name of ``__all__`` resolves, ``import wirecal``
stays cheap, and the README's example runs through the public API only."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

import wirecal

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"


def test_every_public_name_resolves():
    for name in wirecal.__all__:
        assert getattr(wirecal, name) is not None, name
    assert sorted(dir(wirecal)) == sorted(wirecal.__all__)


def test_import_wirecal_is_cheap(tmp_path):
    code = (
        "import sys, wirecal\n"
        "print(wirecal.__version__)\n"
        "print(' '.join(m for m in ('numpy', 'click', 'jinja2', 'lark') if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout.splitlines() == [wirecal.__version__, ""]


def test_readme_example(tmp_path, monkeypatch):
    """The README's Python example, as written there: load, simulate, check, solve."""
    monkeypatch.chdir(tmp_path)
    robot_file, plan_file = VIPER / "robot.toml", VIPER / "paper_plan.toml"
    # --- README example (keep in step with the README's "Python API" section) ---
    import wirecal

    robot = wirecal.load_robot(robot_file)
    plan = wirecal.load_plan(plan_file, robot)
    truth = {"th2": 0.3, "th3": -0.2, "a2": 0.1, "d4": -0.1}  # deg, mm; others 0
    text = wirecal.simulate_log(robot, plan, truth, seed=1, noise_mm=0.01)
    m = wirecal.check_log(wirecal.parse_log(text, "sim.csv"), plan, robot)
    result = wirecal.solve(robot, plan, m)
    best = result.estimates[result.recommended]
    print(result.recommended, best.as_dict(), result.predicted[result.recommended]["mean"])
    # --- end of the example ---
    expected = {n: truth.get(n, 0.0) for n in plan.order}
    got = result.estimates["joint"].as_dict()
    assert max(abs(got[n] - expected[n]) for n in expected) < 0.02
    assert result.predicted["joint"]["mean"] < 0.05
    assert best.method == result.recommended


def test_designed_plan_through_the_public_api():
    """Design a plan for the Viper at the paper's θ0, then simulate and solve with it."""
    robot = wirecal.load_robot(VIPER / "robot.toml")
    paper = wirecal.load_plan(VIPER / "paper_plan.toml", robot)
    plan = wirecal.design(robot, paper.theta0_deg).plan
    truth = {n: 0.5 for n in plan.order}
    text = wirecal.simulate_log(robot, plan, truth, seed=2)
    result = wirecal.solve(
        robot, plan, wirecal.check_log(wirecal.parse_log(text, "d.csv"), plan, robot)
    )
    got = result.estimates["joint"].as_dict()
    assert np.allclose([got[n] for n in plan.order], 0.5, atol=0.02)
