"""The zero readings of an arm that does not return exactly to θ0 (solver/zero_reading.py)."""

from __future__ import annotations

import copy
import json
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.app.coverage import GAUGE_LENGTH_MM, with_gauge
from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import robot_file_text, robot_from_dict
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.log.measurements import check_log
from wirecal.solver.simulate import Unmodelled
from wirecal.solver.solve import solve
from wirecal.solver.zero_reading import expected_zero_mm, length_sigma_mm
from wirecal.twin.world import DEFAULT_UNMODELLED, World

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _robot(arm: str, **calibration):
    data = copy.deepcopy(tomllib.loads((EXAMPLES / arm / "robot.toml").read_text()))
    data["calibration"].update(calibration)
    return robot_from_dict(data, f"{arm}.toml")


@pytest.mark.parametrize(
    ("arm", "plan"), [("ur5e", "plan.toml"), ("viper_s650", "paper_plan.toml")]
)
def test_expected_zero_is_the_mean_of_the_twins_zero_readings(arm, plan):
    robot = _robot(arm)
    theta0 = load_plan(EXAMPLES / arm / plan, robot).theta0_deg
    q = np.tile(theta0, (100_000, 1))
    landed = q + Unmodelled(0.02, 0.0).joint_errors_deg(robot.nominal, q, np.random.default_rng(3))
    p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
    read = np.linalg.norm(tool_position(robot.nominal, np.radians(landed)) - p0, axis=1)
    # Monte Carlo of 10⁵ returns: its standard error is 0.16 % of the mean.
    assert expected_zero_mm(robot.nominal, theta0, 0.02) == pytest.approx(read.mean(), rel=0.01)
    assert 0.005 < read.mean() < 0.03  # the size the docs quote (11–19 µm)
    # Linear in the repeatability: δ scales with σ_q.
    assert expected_zero_mm(robot.nominal, theta0, 0.04) == pytest.approx(
        2 * expected_zero_mm(robot.nominal, theta0, 0.02), rel=1e-9
    )


def test_declared_repeatability_lengthens_every_wire_by_the_expected_zero():
    robot = _robot("ur5e")
    declared = replace(robot, repeatability_mm=0.02)
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    text = simulate_log(robot, plan, {}, seed=4, unmodelled=Unmodelled(0.02, 0.0))
    plain = check_log(parse_log(text, "run"), plan, robot).distance_mm
    read = check_log(parse_log(text, "run"), plan, declared).distance_mm
    shift = expected_zero_mm(robot.nominal, plan.theta0_deg, 0.02)
    np.testing.assert_allclose(read - plain, shift, rtol=0, atol=1e-12)


def _text(robot) -> str:
    return robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")


def test_robot_file_reads_writes_and_refuses_repeatability():
    robot = _robot("ur5e", repeatability_mm=0.03)
    assert robot.repeatability_mm == 0.03
    again = robot_from_dict(tomllib.loads(_text(robot)), "again.toml")
    assert again.repeatability_mm == 0.03
    assert _robot("ur5e").repeatability_mm is None
    assert "repeatability_mm" not in _text(_robot("ur5e"))
    for bad in (0.0, -0.01, 5.0):
        with pytest.raises(WirecalError, match=r"ur5e\.toml.*repeatability_mm"):
            _robot("ur5e", repeatability_mm=bad)


@pytest.mark.slow
def test_declared_repeatability_removes_the_geometrys_bias():
    """Rigid UR5e, gauge, the twin's repeatability: d6's mean error over 10 runs."""
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", _robot("ur5e"))
    mean = {}
    for declared in (None, 0.02):
        robot = with_gauge(replace(_robot("ur5e"), repeatability_mm=declared))
        errors = []
        for seed in range(1, 11):
            truth = random_errors(robot, 1.0, np.random.default_rng([seed, 1]))
            text = simulate_log(robot, plan, truth, seed=seed, unmodelled=Unmodelled(0.02, 0.0))
            result = solve(robot, plan, check_log(parse_log(text, "run"), plan, robot))
            errors.append(result.estimates["joint"].as_dict()["d6"] - truth["d6"])
        mean[declared] = np.mean(errors)
    # Without it every length reads ~0.019 mm short and d6 absorbs ~0.011 mm of it.
    assert mean[None] < -0.006
    assert abs(mean[0.02]) < 0.4 * abs(mean[None])  # 10 runs: its standard error ~0.0016


def test_cli_solve_reads_the_lengths_from_the_declared_repeatability(tmp_path):
    plan = str(EXAMPLES / "ur5e" / "plan.toml")
    text = (EXAMPLES / "ur5e" / "robot.toml").read_text()
    plain, declared = tmp_path / "plain.toml", tmp_path / "declared.toml"
    plain.write_text(text)
    declared.write_text(text.replace("[calibration]\n", "[calibration]\nrepeatability_mm = 0.02\n"))
    log = tmp_path / "run.log"
    res = CliRunner().invoke(main, ["simulate", str(plain), plan, "-o", str(log), "--seed", "2"])
    assert res.exit_code == 0, res.output
    d6 = {}
    for path in (plain, declared):
        res = CliRunner().invoke(main, ["solve", str(path), plan, str(log), "--json"])
        assert res.exit_code == 0, res.output
        d6[path.name] = json.loads(res.output)["methods"]["joint"]["parameters"]["d6"]
    # Every length 18.7 µm longer (E‖δ‖ at the UR5e's θ0, 0.02 mm): d6 takes about 0.6 of it.
    assert 0.005 < d6["declared.toml"] - d6["plain.toml"] < 0.019


def _landing_rms_mm(robot, unmodelled) -> float:
    """RMS over the UR5e plan's rows of the wire length the arm's landing adds (no noise)."""
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    exact = simulate_log(robot, plan, {}, seed=5, noise_mm=0.0)
    landed = simulate_log(robot, plan, {}, seed=5, noise_mm=0.0, unmodelled=unmodelled)
    rigid = replace(robot, repeatability_mm=None)  # read both alike: no zero correction
    d = [check_log(parse_log(t, "run"), plan, rigid).distance_mm for t in (exact, landed)]
    return float(np.sqrt(np.mean((d[1] - d[0]) ** 2)))


def test_the_twins_arm_repeats_as_the_robot_file_declares():
    plain, declared = _robot("ur5e"), _robot("ur5e", repeatability_mm=0.05)
    assert Unmodelled().for_robot(plain).repeatability_mm == 0.02  # the default, stated
    assert Unmodelled().for_robot(declared).repeatability_mm == 0.05
    assert Unmodelled(0.03).for_robot(declared).repeatability_mm == 0.03  # explicit wins
    # The landing's scatter is linear in the repeatability (σ_q ∝ r, the same draws): 2.5×.
    small = _landing_rms_mm(plain, Unmodelled(compliance_deg_per_m=0.0))
    large = _landing_rms_mm(declared, Unmodelled(compliance_deg_per_m=0.0))
    assert small > 0.002  # the default arm does not land exactly
    assert large == pytest.approx(2.5 * small, rel=0.06)  # less: the counts round alike


def test_cli_simulate_lands_the_arm_within_the_declared_repeatability(tmp_path):
    plan_path = EXAMPLES / "ur5e" / "plan.toml"
    text = (EXAMPLES / "ur5e" / "robot.toml").read_text()
    plain, declared = tmp_path / "plain.toml", tmp_path / "declared.toml"
    plain.write_text(text)
    declared.write_text(text.replace("[calibration]\n", "[calibration]\nrepeatability_mm = 0.05\n"))
    robot = _robot("ur5e")
    plan = load_plan(plan_path, robot)
    d = []
    for path in (plain, declared):
        log = tmp_path / f"{path.stem}.log"
        args = ["simulate", str(path), str(plan_path), "-o", str(log), "--seed", "2"]
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 0, res.output
        d.append(check_log(parse_log(log.read_text(), "run"), plan, robot).distance_mm)
    # The same seed: the same truth, encoder and noise; the plain arm lands exactly, as
    # before, the declared one with joints of σ 0.025 mm / 600 mm each: 0.062 mm RMS of
    # wire here (six joints, the UR5e's levers), 2.5 × the 0.02 mm arm's (the test above).
    rms = float(np.sqrt(np.mean((d[1] - d[0]) ** 2)))
    assert 0.03 < rms < 0.12


def test_the_twins_world_takes_the_declared_repeatability(tmp_path):
    """The twin (validation runs, ``simulate --controller``) lands its arm as declared."""
    robot = _robot("ur5e", repeatability_mm=0.03)
    q0 = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot).theta0_deg
    world = World(robot, {}, q0, tmp_path, unmodelled=DEFAULT_UNMODELLED)
    assert world.unmodelled is not None
    assert world.unmodelled.repeatability_mm == 0.03
    plain = World(_robot("ur5e"), {}, q0, tmp_path, unmodelled=DEFAULT_UNMODELLED)
    assert plain.unmodelled is not None
    assert plain.unmodelled.repeatability_mm == 0.02  # the twin's default, as before


def test_length_scatter_is_that_of_the_twins_landing():
    """σ of each point's wire length from the arm's landing: against a Monte Carlo of the twin."""
    robot = _robot("ur5e")
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    q = np.array([p for s in plan.steps for p in s.points_deg])
    p0 = tool_position(robot.nominal, np.radians(plan.theta0_deg)[None])[0]
    exact = np.linalg.norm(tool_position(robot.nominal, np.radians(q)) - p0, axis=1)
    rng = np.random.default_rng(5)
    draws = []
    for _ in range(2000):
        landed = q + Unmodelled(0.02, 0.0).joint_errors_deg(robot.nominal, q, rng)
        draws.append(np.linalg.norm(tool_position(robot.nominal, np.radians(landed)) - p0, axis=1))
    rms = np.sqrt(np.mean(np.var(np.array(draws) - exact, axis=0)))
    # 2000 draws per point: the RMS of the σ is known to ~1 %.
    sigma = length_sigma_mm(robot.nominal, np.radians(q), np.radians(plan.theta0_deg), 0.02)
    assert sigma == pytest.approx(rms, rel=0.03)
    assert 0.005 < rms < 0.02  # the size it has at 0.02 mm (0.011 mm)


def _gauge_reading_mm(robot, plan, seed: int, landing_mm: float) -> tuple[float, float]:
    """Return the σ of one gauge reading the scale took (one pair, certified exactly) and σ."""
    text = simulate_log(robot, plan, {}, seed=seed, unmodelled=Unmodelled(landing_mm, 0.0))
    result = solve(robot, plan, check_log(parse_log(text, "run"), plan, robot))
    return result.scale.std * GAUGE_LENGTH_MM / np.sqrt(2), result.sigma_mm


def test_the_gauges_reading_noise_leaves_out_the_arms_landing():
    """The gauge is read without the arm: its σ is the readings', not the residual's."""
    plain = with_gauge(_robot("ur5e"), uncertainty_mm=0.0, repeats=1)
    declared = replace(plain, repeatability_mm=0.02)
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", plain)
    seeds = range(1, 4)
    # The reading noise itself: the residual of an arm that lands exactly (noise, counts).
    reading = np.mean([_gauge_reading_mm(plain, plan, s, 1e-9)[1] for s in seeds])
    taken = np.mean([_gauge_reading_mm(declared, plan, s, 0.02)[0] for s in seeds])
    before = np.mean([_gauge_reading_mm(plain, plan, s, 0.02)[0] for s in seeds])
    # Three runs of ~60 points: each σ within ~10 % (taken 11 % above); the arm adds ~38 %.
    assert taken == pytest.approx(reading, rel=0.2)
    assert before > 1.25 * reading  # without the key: the residual's σ, as before
