"""The public ``wirecal`` package: every name of ``__all__`` resolves, ``import wirecal``
stays cheap, and the README's example runs through the public API only."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import wirecal

from .conftest import ROOT

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
    """The README's Python example, as written there: design, simulate, check, solve, gate."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "examples").symlink_to(VIPER.parent)
    # --- README example (keep in step with docs/api.md) ---
    import wirecal

    robot = wirecal.load_robot("examples/viper_s650/robot.toml")
    plan = wirecal.design(robot, [0, -90, 210, -90, 0, -90]).plan  # at the paper's θ0
    truth = {"th2": 0.3, "th3": -0.2, "a2": 0.1, "d4": -0.1}  # true offsets, deg and mm
    text = wirecal.simulate_log(robot, plan, truth, seed=1)  # the log wc.run would write
    m = wirecal.check_log(wirecal.parse_log(text, "sim.csv"), plan, robot)
    result = wirecal.solve(robot, plan, m)
    verdict = wirecal.gate(result, result.recommended)  # WirecalError (exit 3) if implausible
    best = result.estimates[result.recommended]
    print(result.recommended, best.as_dict(), verdict.summary())
    # --- end of the example ---
    expected = {n: truth.get(n, 0.0) for n in plan.order}
    got = result.estimates["joint"].as_dict()
    # 0.024 (a3) since the Viper's cell (issue 21) changed the design at this θ0
    assert max(abs(got[n] - expected[n]) for n in expected) < 0.03
    assert verdict.passed
    assert best.method == result.recommended
    path, spec = wirecal.write_patch(
        "patch.toml",
        robot,
        best,
        plan_fingerprint=plan.fingerprint(),
        log_path="sim.csv",
        log_sha256=m.sha256,
        version=wirecal.__version__,
        plausibility=verdict.patch_field(),
    )
    patch = wirecal.read_patch(path)
    assert spec.exists()
    assert patch.offsets_for(robot, plan) == pytest.approx(best.as_dict(), abs=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "plan_file"),
    [("viper_s650", "paper_plan.toml"), ("ur5e", "plan.toml"), ("abb_irb120", "plan.toml")],
)
def test_generation_and_the_twin_in_any_language(name, plan_file, tmp_path, monkeypatch):
    """docs/api.md's second example, for each shipped language's example."""
    monkeypatch.chdir(tmp_path)
    robot = wirecal.load_robot(ROOT / "examples" / name / "robot.toml")
    plan = wirecal.load_plan(ROOT / "examples" / name / plan_file, robot)
    programs = wirecal.generate(robot, plan)
    written = wirecal.write_programs(robot, "out", programs)
    assert sorted(p.name for p in written) == sorted(programs)
    run = wirecal.measure_in_twin(robot, plan, {"th2": 0.3}, Path("twin"), programs, seed=1)
    assert (run.complete, run.stopped) == (True, None)
    assert run.log.is_file()
