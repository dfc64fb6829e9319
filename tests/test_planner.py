"""wirecal plan: the designed plans keep every constraint, pass Ψ, and beat the paper's."""

from __future__ import annotations

import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.app.psi_view import psi_table
from wirecal.cli.main import main
from wirecal.formats.plan_file import load_plan, plan_from_dict
from wirecal.formats.robot_file import load_robot
from wirecal.solver import montecarlo
from wirecal.solver.cell.clearance import wire_clearance, wire_trim_mm
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.moves import move_samples
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.planner import design
from wirecal.solver.plan.predict import predicted_accuracy, robot_time
from wirecal.solver.run_parameters import PAPER_RUN, run_timeline
from wirecal.solver.wire_range import RANGE_MARGIN_MM, check_wire_range, run_moves

from .conftest import VIPER
from .designs import THETA0
from .designs import designed as shared_design

pytestmark = pytest.mark.slow  # designs plans for four arms: tens of seconds

OPT = PlanOptions()
STEPWISE = PlanOptions(method="stepwise")


@pytest.fixture(
    scope="module", params=[(arm, m) for arm in sorted(THETA0) for m in ("joint", "stepwise")]
)
def designed(request):
    return shared_design(*request.param)


def _sequences(plan):
    for s in plan.steps:
        yield np.array([plan.theta0_deg, *s.via_deg, *s.points_deg, plan.theta0_deg])


def test_every_parameter_is_planned(designed):
    robot, d = designed
    assert d.excluded == {}
    assert sorted(d.plan.order) == sorted(robot.parameters)
    counts = [len(s.points_deg) for s in d.plan.steps]
    if d.method == "stepwise":
        assert counts == [OPT.points_per_step] * len(counts)
    else:  # the same number of points in all, each step with its fewest
        assert sum(counts) == OPT.points_per_step * len(counts)
        assert min(counts) >= OPT.min_points


def test_points_keep_the_joint_limits_with_the_margin(designed):
    robot, d = designed
    q = np.concatenate([seq for seq in _sequences(d.plan)])
    assert np.all(q >= robot.joint_min_deg + OPT.margin_deg - 1e-9)
    assert np.all(q <= robot.joint_max_deg - OPT.margin_deg + 1e-9)


def test_wire_length_within_the_encoder_range(designed):
    robot, d = designed
    model = robot.nominal
    p0 = tool_position(model, np.radians(d.plan.theta0_deg)[None])[0]
    q, _, _ = d.plan.all_points()
    length = np.linalg.norm(tool_position(model, np.radians(q)) - p0, axis=1)
    assert length.min() >= OPT.min_wire_mm
    assert length.max() <= robot.encoder.range_mm - OPT.range_margin_mm


def test_wirecal_gen_accepts_the_wire_range_along_every_move(designed):
    """The range check of 'wirecal gen' (every move of wc.run, sampled every 2°) passes on
    every designed plan: the planner checks the wire's length along its moves too (before,
    the UR5's default plan reached 1253.6 mm on the move to a step-7 point and gen refused
    it)."""
    robot, d = designed
    q, _ = move_samples(
        np.array([m[1] for m in run_moves(d.plan)]), np.array([m[2] for m in run_moves(d.plan)])
    )
    p0 = tool_position(robot.nominal, np.radians(d.plan.theta0_deg)[None])[0]
    length = np.linalg.norm(tool_position(robot.nominal, np.radians(q)) - p0, axis=1)
    assert length.max() <= robot.encoder.range_mm - RANGE_MARGIN_MM
    check_wire_range(robot, d.plan)  # raises otherwise


def test_the_wire_stays_clear_of_the_links_along_every_move(designed):
    """Sampled every 0.5° (the planner: every 2°), so a gap the planner's sampling
    missed shows up here; 2 mm slack for the sampling."""
    robot, d = designed
    model = robot.nominal
    p0 = tool_position(model, np.radians(d.plan.theta0_deg)[None])[0]
    for seq in _sequences(d.plan):
        for a, b in itertools.pairwise(seq):
            t = np.linspace(0, 1, 1 + int(np.ceil(np.max(np.abs(b - a)) / 0.5)))[:, None]
            gap = wire_clearance(
                model, np.radians(a + t * (b - a)), p0, robot.link_radius_mm, wire_trim_mm(robot)
            )
            assert gap.min() >= OPT.clearance_mm - 2.0, (a, b, gap.min())
            assert abs(b[-1] - a[-1]) <= 180


def test_points_are_spread_out(designed):
    _, d = designed
    for s in d.plan.steps:
        for a, b in itertools.combinations(s.points_deg, 2):
            assert np.max(np.abs(a - b)) >= OPT.spread_deg


def test_psi_reports_every_row_ok(designed):
    robot, d = designed
    table = psi_table(robot, d.plan)
    assert table.rows
    assert all(r.ok for r in table.rows)
    assert table.identifiability.rank == len(d.plan.order)


def test_the_same_inputs_give_the_same_plan(designed):
    robot, d = designed
    again = design(robot, d.plan.theta0_deg, PlanOptions(method=d.method))
    assert again.plan.fingerprint() == d.plan.fingerprint()


def test_monte_carlo_recovers_the_errors(designed):
    """Uniform ±1 deg / ±1 mm errors, σ 0.01 mm: the joint estimate within 1.5× the
    Cramér–Rao bound; the stepwise one (biased by what leaks between steps) removes at
    least 97 % of the tool-point error over the workspace."""
    robot, d = designed
    truth = np.random.default_rng(5).uniform(-1, 1, (12, len(d.plan.order)))
    mc = montecarlo.run(robot, d.plan, truth, seed=6, n_workspace=300)
    assert mc.before_mm > 1.0
    assert mc.methods["joint"].tool_mean_mm <= 1.5 * mc.crb.tool_mean_mm
    assert mc.methods["stepwise"].tool_mean_mm < 0.03 * mc.before_mm


def test_viper_plan_beats_the_corrected_paper_plan(viper, paper_plan):
    _, d = shared_design("viper_s650", STEPWISE.method)
    paper = predicted_accuracy(viper, paper_plan)
    assert d.plan.n_points <= paper_plan.n_points
    assert d.robot_time_s <= robot_time(viper, paper_plan)
    assert d.predicted["joint"] <= paper["joint"]
    assert d.predicted["stepwise"] <= paper["stepwise"]
    # the leak-aware choice never does worse than the largest-|Ψ| choice it is compared to
    assert all(s.leak_ours <= s.leak_paper * (1 + 1e-9) for s in d.steps)


def test_robot_time_counts_moves_settles_and_returns(viper):
    """One step, one point 30° away on joint 1 (328 °/s at the paper's 20 %; the encoder's
    wire limits left out: the return move, which winds the wire back to zero at θ0, would
    be slowed by the acceleration limit — tests/test_settle.py pins that): the move to θ0
    from θ0 (0.5 s ramp), out and back
    2 × (30 / 65.6 + 0.5 s), three stops (zero, point, closing zero) of 3 s settle, the
    settle rule's window 4 × 0.02 s on a vibration long decayed, and 10 readings 0.02 s
    apart."""
    plan = plan_from_dict(
        {
            "theta0_deg": [0, -90, 180, 0, 45, 0],
            "order": ["th6"],
            "step": [{"parameter": "th6", "points_deg": [[30, -90, 180, 0, 45, 0]]}],
        },
        viper,
    )
    viper = replace(
        viper,
        encoder=replace(viper.encoder, max_wire_speed_mm_s=None, max_wire_accel_mm_s2=None),
    )
    stop = 3 + 0.08 + 0.18
    expected = 0.5 + 2 * (30 / (328 * 0.2) + 0.5) + 3 * stop
    assert robot_time(viper, plan, PAPER_RUN) == pytest.approx(expected, rel=1e-12)
    timeline = run_timeline(viper, plan, PAPER_RUN)
    np.testing.assert_allclose(timeline.speed_pct, [20, 20, 20])
    np.testing.assert_allclose(
        timeline.reading_s,
        [3.58, 0.5 + stop + 30 / 65.6 + 0.5 + 3.08, expected - 0.18],
        rtol=1e-12,
    )


def _edited(tmp_path: Path, old: str, new: str) -> Path:
    text = (VIPER / "robot.toml").read_text()
    assert old in text
    out = tmp_path / "robot.toml"
    out.write_text(text.replace(old, new))
    return out


def test_unreachable_encoder_range_is_a_clear_error(tmp_path):
    robot = _edited(tmp_path, "range_mm = 1250.0", "range_mm = 60.0")
    r = CliRunner().invoke(main, ["plan", str(robot), "--theta0", "-72,-156,235,3,64,41"])
    assert r.exit_code == 2
    assert "almost no usable configuration" in r.output
    assert "encoder range" in r.output
    assert "Traceback" not in r.output


def test_unobservable_parameters_are_reported_not_dropped(tmp_path):
    robot = load_robot(_edited(tmp_path, 'parameters = ["th2"', 'parameters = ["th1", "th2"'))
    d = design(robot, np.array(THETA0["viper_s650"], float))
    assert "th1" not in d.plan.order
    assert d.excluded["th1"].startswith("unobservable")
    assert "not planned: th1: unobservable" in d.header()


def test_theta0_near_a_limit_is_refused(viper):
    with pytest.raises(WirecalError, match="joint 5 = 118 deg is within 5 deg of its limits"):
        design(viper, np.array([0, -90, 180, 0, 118, 0], float))


def test_cli_writes_a_plan_that_psi_accepts_and_refuses_to_overwrite(tmp_path):
    out = tmp_path / "plan.toml"
    args = ["plan", str(VIPER / "robot.toml"), "-o", str(out), "--theta0", "-72,-156,235,3,64,41"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    assert "Estimated robot time" in r.output
    assert f"wrote {out}" in r.output
    text = out.read_text()
    assert text.startswith("# Designed by 'wirecal plan'")
    plan = load_plan(out, load_robot(VIPER / "robot.toml"))
    assert plan.n_points == 50
    psi = CliRunner().invoke(main, ["psi", str(VIPER / "robot.toml"), str(out), "--strict"])
    assert psi.exit_code == 0, psi.output
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 2
    assert "--force" in again.output
    assert out.read_text() == text


@pytest.mark.parametrize(
    ("bad", "message"), [("1,2,3", "has 3 values; the robot has 6"), ("a,b", "give 6 joint angles")]
)
def test_cli_bad_theta0(bad, message):
    r = CliRunner().invoke(main, ["plan", str(VIPER / "robot.toml"), "--theta0", bad])
    assert r.exit_code == 2
    assert message in r.output
