"""The design for the joint method: better than the stepwise design at equal robot time,
still usable step by step; and the progress bar, silent unless stderr is a terminal."""

from __future__ import annotations

import io

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.app.progress import ProgressBar
from wirecal.app.psi_view import psi_table
from wirecal.cli.main import main
from wirecal.solver import montecarlo
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.planner import design

from .conftest import VIPER
from .designs import THETA0 as SHIPPED_THETA0
from .designs import designed

THETA0 = np.array(SHIPPED_THETA0["viper_s650"], float)  # 'wirecal plan' --for stepwise's


@pytest.fixture(scope="module")
def both():
    return {m: designed("viper_s650", m)[1] for m in ("joint", "stepwise")}


@pytest.mark.slow
def test_joint_design_beats_the_stepwise_design_at_equal_robot_time(both):
    """Same θ0, same 50 points: the joint design takes at most 3 % more robot time and
    its Cramér–Rao tool-point error is at least 4 % lower (0.0169 against 0.0179 mm since
    the Viper's upper arm and forearm got their intended radii, 70/55 mm, which removed
    candidates; 0.0129 against 0.0154 before); its stepwise prediction stays under 0.03 mm.
    (No more robot time before the Viper's floor and base column removed candidates,
    issue 21: 2.2 % more since.)"""
    joint, stepwise = both["joint"], both["stepwise"]
    assert joint.plan.n_points == stepwise.plan.n_points == 50
    assert joint.robot_time_s <= stepwise.robot_time_s * 1.03
    assert joint.predicted["joint"] <= 0.96 * stepwise.predicted["joint"]
    assert joint.predicted["stepwise"] < 0.03


@pytest.mark.slow
def test_fewer_joint_points_match_the_stepwise_design(viper, both):
    """40 points designed for the joint method come within 2 % of the bound of 50 stepwise
    ones in less robot time (0.8 % above it, 0.0180 against 0.0179 mm, since the Viper's
    upper arm and forearm got their intended radii; at or under it before)."""
    d = design(viper, THETA0, PlanOptions(points=40))
    assert d.plan.n_points == 40
    assert d.robot_time_s < 0.9 * both["stepwise"].robot_time_s
    assert d.predicted["joint"] <= 1.02 * both["stepwise"].predicted["joint"]


@pytest.mark.slow
def test_joint_plan_runs_step_by_step(viper, both):
    """Every point of the joint plan isolates its step's parameter (psi's verdict), and
    the stepwise method on simulated logs of it (Table-5-sized errors within ±1 deg/mm,
    σ 0.01 mm) removes at least 97 % of the tool-point error, within 0.075 mm (0.05 before
    the Viper's floor and base column removed candidates, issue 21: 0.066 since; 0.0715
    since its upper arm and forearm got their intended radii, 70/55 mm)."""
    plan = both["joint"].plan
    table = psi_table(viper, plan)
    assert all(r.ok for r in table.rows)
    truth = np.random.default_rng(11).uniform(-1, 1, (12, len(plan.order)))
    mc = montecarlo.run(viper, plan, truth, seed=12, n_workspace=300)
    assert mc.methods["stepwise"].tool_mean_mm < min(0.03 * mc.before_mm, 0.075)
    assert mc.methods["joint"].tool_mean_mm <= 1.5 * mc.crb.tool_mean_mm


@pytest.mark.slow
def test_header_states_method_time_and_both_accuracies(both):
    text = both["joint"].header()
    assert "Points chosen for the joint method" in text
    assert "Estimated robot time" in text
    assert "joint 0.01" in text
    assert "step-by-step 0.0" in text


def test_points_only_for_the_joint_design():
    r = CliRunner().invoke(
        main, ["plan", str(VIPER / "robot.toml"), "--for", "stepwise", "--points", "30"]
    )
    assert r.exit_code == 2
    assert "--points applies to --for joint" in r.output


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_silent_when_not_a_terminal():
    stream = io.StringIO()
    with ProgressBar("planning", stream) as bar:
        for k in range(11):
            bar.update(k / 10)
    assert stream.getvalue() == ""


def test_progress_bar_draws_on_a_terminal_and_clears():
    stream = _Terminal()
    with ProgressBar("planning", stream) as bar:
        bar.update(0.5)
        bar.update(0.501)  # same percentage: not redrawn
    text = stream.getvalue()
    assert text.count("planning") == 2  # 0 % and 50 %
    assert "[###############...............]  50%" in text
    assert text.endswith("\r")  # the line is cleared at the end


@pytest.mark.slow
def test_plan_command_output_has_no_progress_bar():
    """In a captured run (not a terminal) stderr carries no bar, stdout only the header."""
    r = CliRunner().invoke(
        main,
        ["plan", str(VIPER / "robot.toml"), "--theta0", "-72,-156,235,3,64,41", "--points", "20"],
    )
    assert r.exit_code == 0, r.output
    assert "\r" not in r.output
    assert "%" not in r.output.replace("% below", "")
    assert r.output.startswith("Designed by 'wirecal plan'")


def test_stage_lines_are_printed_and_counted():
    out, term = io.StringIO(), _Terminal()
    bar = ProgressBar("demo", term)
    stage = bar.stages(echo=False)
    stage("[1/4] first …")
    stage("[2/4] second …")
    assert bar.fraction == 0.25
    assert "[2/4] second" in term.getvalue()
    bar.echo("a line", out)
    assert out.getvalue() == "a line\n"


@pytest.mark.slow
def test_probe_search_starts_near_the_last_contact(
    viper, paper_plan, viper_setup, viper_validation_module, tmp_path
):
    """A robot as nominal: every one of the 19 × 11 grid points is found to 1/128 mm
    (flange 100 mm above the plate at -300 mm) in under half the moves of a search from
    the approach height in 1, 0.1 and 0.01 mm steps (44 per point here)."""
    from wirecal.formats.validation_files import read_validation_log
    from wirecal.twin.vplus.runs import run_validation

    setup, text = viper_setup, viper_validation_module
    v = run_validation(
        viper, paper_plan, {}, setup, tmp_path, text, controller={}, run=1, unmodelled=None
    )
    assert v.plane.status == "completed"
    log = read_validation_log(v.plane_log, "plane")
    z = log.rows[:, -1]
    assert len(z) == 19 * 11
    assert np.all((z >= -200.0 - 1 / 128) & (z <= -200.0 + 1e-3))
    plane_moves = v.controller.world.moves - 4 * setup.poses  # the configuration run's moves first
    assert plane_moves < 20 * len(z)
