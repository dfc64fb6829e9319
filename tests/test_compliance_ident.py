"""Which compliances one wire identifies, offline compensation, and the robot file's key."""

from __future__ import annotations

import copy
import json
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.app.twin_runs import measure_in_twin
from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.patch import read_patch
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import robot_file_text, robot_from_dict
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import load_errors, random_errors
from wirecal.solver.compliance import (
    SIGMA_LIMIT_URAD_PER_NM,
    compensated_joints,
    compliance_observability,
)
from wirecal.solver.distance import wire_lengths
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import frames, tool_position
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ALL_C = tuple(f"c{j}" for j in range(1, 7))
UR5E = tomllib.loads((EXAMPLES / "ur5e" / "robot.toml").read_text())


def _ur5e(**gravity):
    data = copy.deepcopy(UR5E)
    data["gravity"].update(gravity)
    return robot_from_dict(data, "ur5e.toml")


def test_compensated_joints_put_the_bent_arm_where_the_rigid_one_is():
    robot = _ur5e(compliance_urad_per_nm=[0.0, 8.0, 8.0, 4.0, 4.0, 2.0])
    rng = np.random.default_rng(5)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    rigid = replace(robot.nominal, compliance=None)
    command = compensated_joints(robot.nominal, q)
    sag = np.linalg.norm(tool_position(robot.nominal, q) - tool_position(rigid, q), axis=1)
    assert sag.max() > 0.05  # the sag to compensate: tenths of a mm at 8 µrad/(N·m)
    np.testing.assert_allclose(
        tool_position(robot.nominal, command), tool_position(rigid, q), atol=1e-9
    )
    bent, wanted = frames(robot.nominal, command), frames(rigid, q)
    np.testing.assert_allclose(bent.R_last, wanted.R_last, atol=1e-12)  # the pose, not only p


def test_compensation_of_a_rigid_arm_is_the_identity():
    robot = _ur5e()
    q = np.radians([[10.0, -80.0, 60.0, 0.0, 45.0, 0.0]])
    np.testing.assert_array_equal(compensated_joints(robot.nominal, q), q)


def test_one_wire_on_the_ur5e_plan_identifies_c2_c3_and_says_why_not_the_others():
    robot = _ur5e()
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    q, _, _ = plan.all_points()
    r = compliance_observability(robot.nominal, q, plan.theta0_deg, robot.parameters, ALL_C, 0.01)
    assert r.identified == ("c2", "c3")
    assert SIGMA_LIMIT_URAD_PER_NM == pytest.approx(8.0 / 12**0.5)  # the prior range's σ
    assert r.sigma_urad_per_nm["c2"] <= 0.5  # the shoulder's torque varies most
    assert r.sigma_urad_per_nm["c3"] <= SIGMA_LIMIT_URAD_PER_NM
    assert "gravity has no torque about joint 1" in r.reasons["c1"]  # axis 1 vertical
    assert "gravity has no torque about joint 6" in r.reasons["c6"]  # link 6 on its axis
    for name in ("c4", "c5"):  # the wrist's torques are a few N·m at most
        assert r.sigma_urad_per_nm[name] > SIGMA_LIMIT_URAD_PER_NM
        assert "too small or varies too little" in r.reasons[name]


def test_solve_when_every_compliance_asked_for_is_identified():
    """The file asks for c2 and c3, the two the UR5e plan identifies: no compliance is left
    at its prior. ``solve`` used to stop with a traceback (the budget's Jacobian of no
    compliance could not be shaped)."""
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = ["c2", "c3"]
    robot = robot_from_dict(data, "ur5e.toml")
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    truth = random_errors(robot, 1.0, np.random.default_rng(2))
    text = simulate_log(robot, plan, truth, seed=2)
    result = solve(robot, plan, check_log(parse_log(text, "run.csv"), plan, robot))
    assert result.compliance is not None
    assert result.compliance.identified == ("c2", "c3")
    budget = result.budgets["joint"]
    assert budget.bound_compensated is not None
    assert 0 < budget.bound_compensated < 1.0  # mm
    assert 0 < budget.bound < 1.0


def test_a_wall_mounted_arm_shows_joint_1_its_torque():
    robot = _ur5e(direction=[1.0, 0.0, 0.0])
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    q, _, _ = plan.all_points()
    r = compliance_observability(robot.nominal, q, plan.theta0_deg, robot.parameters, ALL_C, 0.01)
    assert "c1" not in r.reasons or "no torque" not in r.reasons["c1"]


def test_a_constant_torque_makes_the_compliance_a_joint_offset():
    # only joint 1 (vertical) moves: τ2 is the same at every point, c2·τ2 is a th2 offset
    robot = _ur5e()
    q = np.array([[a, -60.0, 80.0, -90.0, 60.0, 0.0] for a in range(-60, 61, 10)], float)
    theta0 = np.array([-75.0, -60.0, 80.0, -90.0, 60.0, 0.0])
    r = compliance_observability(robot.nominal, q, theta0, ("th2",), ("c2",), 0.01)
    assert r.identified == ()
    assert "th2" in r.reasons["c2"]
    assert "to tell it from the geometry" in r.reasons["c2"]


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        (["c7"], "'c7' is not a compliance; use c1..c6"),
        (["th2"], "'th2' is not a compliance"),
        (["c2", "c2"], "'c2' is listed twice"),
    ],
)
def test_compliances_key_is_checked(value, problem):
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = value
    with pytest.raises(WirecalError) as info:
        robot_from_dict(data, "r.toml")
    assert any(
        p.startswith("r.toml: calibration.compliances:") and problem in p
        for p in info.value.problems
    ), info.value.problems


def test_compliances_need_the_masses():
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = ["c2"]
    del data["gravity"]
    with pytest.raises(
        WirecalError, match=r"compliances: needs the arm's masses: add a \[gravity\]"
    ):
        robot_from_dict(data, "r.toml")


def test_compliances_key_writes_back():
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = ["c2", "c3"]
    robot = robot_from_dict(data, "r.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    assert robot_from_dict(tomllib.loads(text), "again.toml").compliances == ("c2", "c3")


def test_observe_and_psi_name_the_compliances_only_when_the_file_asks(tmp_path):
    plan = str(EXAMPLES / "ur5e" / "plan.toml")
    plain = CliRunner().invoke(main, ["observe", str(EXAMPLES / "ur5e" / "robot.toml"), plan])
    assert plain.exit_code == 0
    assert "ompliance" not in plain.output
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = list(ALL_C)
    path = tmp_path / "ur5e.toml"
    path.write_text(
        robot_file_text(robot_from_dict(data, "x"), header=[], row_notes=[""] * 6, encoder_note="")
    )
    text = CliRunner().invoke(main, ["observe", str(path), plan])
    assert text.exit_code == 0, text.output
    assert "Compliances identified with the geometry: c2 (σ" in text.output
    assert "), c3 (σ" in text.output
    assert "c1 is not identified: gravity has no torque about joint 1" in text.output
    js = json.loads(CliRunner().invoke(main, ["observe", str(path), plan, "--json"]).output)
    assert js["compliance"]["identified"] == ["c2", "c3"]
    assert js["compliance"]["sigma_urad_per_nm"]["c1"] is None
    assert set(js["compliance"]["not_identified"]) == {"c1", "c4", "c5", "c6"}
    psi = CliRunner().invoke(main, ["psi", str(path), plan])
    assert "Compliances identified with the geometry: c2 (σ" in psi.output
    psi_js = json.loads(CliRunner().invoke(main, ["psi", str(path), plan, "--json"]).output)
    assert psi_js["compliance"]["identified"] == ["c2", "c3"]


@pytest.mark.slow
def test_simulate_solve_patch_carry_an_identified_compliance(tmp_path):
    # the true arm sags (c2..c5 drawn within 2–8 µrad/(N·m)); solve identifies c2 with σ,
    # the patch carries it in [compliance], the SPEC table and the UR companion say the
    # controller takes none, and the JSON gives both bounds
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = ["c2", "c3", "c4", "c5"]
    robot_path = tmp_path / "ur5e.toml"
    robot_path.write_text(
        robot_file_text(robot_from_dict(data, "x"), header=[], row_notes=[""] * 6, encoder_note="")
    )
    plan, log, patch = (
        str(EXAMPLES / "ur5e" / "plan.toml"),
        tmp_path / "run.csv",
        tmp_path / "p.toml",
    )
    run = CliRunner().invoke(
        main, ["simulate", str(robot_path), plan, "-o", str(log), "--seed", "3"]
    )
    assert run.exit_code == 0, run.output
    truth = tomllib.loads((tmp_path / "run.truth.toml").read_text())["errors"]
    assert 2.0 <= truth["c2"] <= 8.0
    out = CliRunner().invoke(main, ["solve", str(robot_path), plan, str(log), "-o", str(patch)])
    assert out.exit_code == 0, out.output
    assert "Compliances identified with the geometry: c2" in out.output
    c2 = tomllib.loads(patch.read_text())["compliance"]["c2"]
    assert c2["unit"] == "urad/Nm"
    assert abs(c2["value"] - truth["c2"]) <= 3 * c2["std"]  # 3σ: the test's tolerance
    assert 0.1 <= c2["std"] <= 0.5
    assert "c2" not in tomllib.loads(patch.read_text())["parameters"]
    spec = (tmp_path / "p.spec.txt").read_text()
    assert "Not carried: the gravity compliances" in spec
    assert "wirecal.compensated_joints" in spec
    assert (
        "# Not carried: the gravity compliances" in (tmp_path / "p.ur_calibration.conf").read_text()
    )
    back = read_patch(patch)
    assert back.compliance["c2"].value == pytest.approx(c2["value"])
    js = json.loads(
        CliRunner().invoke(main, ["solve", str(robot_path), plan, str(log), "--json"]).output
    )
    budget = js["encoder"]["budget"]["joint"]
    assert budget["bound95_compensated_mm"] <= budget["bound95_mm"]
    assert js["methods"]["joint"]["parameters"]["c2"] == pytest.approx(c2["offset"])
    assert js["compliance"]["identified"] == ["c2", "c3"]


def test_without_the_key_the_assumed_sag_stays():
    robot = robot_from_dict(tomllib.loads((EXAMPLES / "viper_s650" / "robot.toml").read_text()))
    assert robot.compliances == ()
    assert robot.gravity_sag_deg_per_m == 0.01  # the assumed sag stays without the key


def test_the_assumed_sag_gives_way_to_compliances():
    data = copy.deepcopy(UR5E)
    data["calibration"]["compliances"] = ["c2"]
    assert robot_from_dict(data, "r.toml").gravity_sag_deg_per_m == 0.0
    data["calibration"]["gravity_sag_deg_per_m"] = 0.01
    with pytest.raises(WirecalError, match="gravity_sag_deg_per_m: is the assumed sag"):
        robot_from_dict(data, "r.toml")


def test_a_truth_compliance_needs_the_masses(tmp_path):
    data = copy.deepcopy(UR5E)
    del data["gravity"]
    robot = robot_from_dict(data, "r.toml")
    truth = tmp_path / "t.toml"
    truth.write_text("[errors]\nth2 = 0.1\nc2 = 5.0\n")
    with pytest.raises(WirecalError, match=r"errors\.c2: a compliance needs the robot file's"):
        load_errors(truth, robot)


@pytest.mark.slow
def test_the_twins_true_arm_sags_by_its_compliance(tmp_path):
    # the V+ twin runs the generated module on a true arm with c2 = c3 = 40 µrad/(N·m)
    # (large, so the sag stands out of the twin's noise): its readings differ from the
    # rigid arm's (same seed) as the bent model's wire lengths differ: correlated above
    # 0.95, the median point within a count
    data = tomllib.loads((EXAMPLES / "viper_s650" / "robot.toml").read_text())
    data["calibration"]["compliances"] = ["c2", "c3"]
    robot = robot_from_dict(data, str(EXAMPLES / "viper_s650" / "robot.toml"))
    plan = load_plan(EXAMPLES / "viper_s650" / "paper_plan.toml", robot)
    lengths = []
    for c in (0.0, 40.0):
        run = measure_in_twin(robot, plan, {"c2": c, "c3": c}, tmp_path / str(c), seed=1)
        m = check_log(parse_log(Path(run.log).read_text(), "twin"), plan, robot)
        lengths.append(m.distance_mm)
    q, _, _ = plan.all_points()
    q, q0 = np.radians(q), np.radians(plan.theta0_deg)
    bent = wire_lengths(robot.model({"c2": 40.0, "c3": 40.0}), q, q0)
    expected = bent - wire_lengths(robot.nominal, q, q0)
    seen = lengths[1] - lengths[0]
    assert np.abs(expected).max() > 0.1  # the sag the wire sees
    assert np.corrcoef(seen, expected)[0, 1] > 0.95
    assert np.median(np.abs(seen - expected)) <= abs(robot.encoder.mm_per_count)
