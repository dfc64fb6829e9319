"""The wire's exit: the bend over a pulley or an eyelet edge, the pulley in the one distance
model (lengths, Jacobian, Ψ), the eyelet's unmodelled edge wrap in simulate, the keys."""

from __future__ import annotations

import copy
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

import wirecal
from wirecal.formats.fileio import read_toml
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot, robot_file_text, robot_from_dict
from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import (
    Eyelet,
    Pulley,
    edge_wrap_mm,
    exit_angle_deg,
    far_field_edge_wrap_mm,
    physical_wire_mm,
    wire_path,
    wrap,
)
from wirecal.solver.kinematics import tool_position, with_errors
from wirecal.solver.plan.exit import cone_problems, largest_exit_deg, unmodelled_exit_mm
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.simulate import true_lengths

from .conftest import TABLE5, VIPER

BASE = read_toml(VIPER / "robot.toml", "robot file")
AXIS = (-0.64, 0.0, 0.768)  # about the paper plan's mean wire direction


def _robot(**encoder) -> wirecal.Robot:
    data = copy.deepcopy(BASE)
    for key in ("exit", "axis", "max_exit_deg", "exit_edge_radius_mm", "pulley_radius_mm"):
        data["encoder"].pop(key, None)
    data["encoder"].update(encoder)
    return robot_from_dict(data, "r.toml")


def _no_sag(robot: wirecal.Robot) -> wirecal.Robot:
    """``robot`` without the assumed gravity sag: with it the sagged θ0 point lies inside
    the pulley's circle and solve refuses (tests/test_exit_sag_guard.py)."""
    return replace(robot, gravity_sag_deg_per_m=0.0)


def _basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors across ``axis``."""
    u = np.cross(axis, [0.3, 0.5, 0.8])
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def _string_over_circle(s: float, w: float, r: float) -> float:
    """Independent construction of the taut wire from the exit (coming along the axis) over
    a circle of radius r (centre (r, 0)) to the point (s across, w along): it follows the
    arc to the tangent point T(β) whose radius is perpendicular to the span T → P (the
    first such β along the arc, found by root finding), then runs straight."""

    def tangency(beta: float) -> float:
        tx, ty = r - r * math.cos(beta), r * math.sin(beta)
        return (s - tx) * (tx - r) + (w - ty) * ty

    grid = np.linspace(0.0, 2 * math.pi, 4001)[1:]
    k = int(np.argmax([tangency(b) >= 0 for b in grid]))
    beta = brentq(tangency, grid[k - 1] if k else 1e-12, grid[k], xtol=1e-15)
    tx, ty = r - r * math.cos(beta), r * math.sin(beta)
    return r * beta + math.hypot(s - tx, w - ty)


# -- the bend --------------------------------------------------------------------------


def test_edge_wrap_figures_of_the_issue():
    """ρ(φ − sin φ): 0.024 mm at ρ = 1 mm and 30°, 0.08 mm at 45° (far from the exit)."""
    assert far_field_edge_wrap_mm(30.0, 1.0) == pytest.approx(0.0236, abs=5e-5)
    assert far_field_edge_wrap_mm(45.0, 1.0) == pytest.approx(0.0783, abs=5e-5)
    eyelet = Eyelet((0.0, 0.0, 1.0), 90.0, 1.0)
    for phi, expected in ((30.0, 0.0236), (45.0, 0.0783)):
        far = 1e6 * np.array([math.sin(math.radians(phi)), 0.0, math.cos(math.radians(phi))])
        assert edge_wrap_mm(far, eyelet) == pytest.approx(expected, abs=5e-5)
        # at 500 mm the exact wrap is within ρ²/D of the far-field figure
        near = far / 2000
        assert abs(edge_wrap_mm(near, eyelet) - expected) < 1.5e-3


@settings(max_examples=200, deadline=None)
@given(
    dist=st.floats(5.0, 2000.0),
    phi_deg=st.floats(0.5, 150.0),  # on the axis: test_on_the_axis_the_wire_runs_straight
    r=st.floats(0.05, 50.0),
    axis=st.tuples(*(st.floats(-1, 1),) * 3).filter(lambda a: np.linalg.norm(a) > 0.1),
    spin=st.floats(0.0, 2 * math.pi),
)
def test_wrap_is_the_taut_wire_over_the_circle(dist, phi_deg, r, axis, spin):
    """Exact length against a numerical shortest path, in any plane about any axis."""
    a = np.asarray(axis) / np.linalg.norm(axis)
    s, w = dist * math.sin(math.radians(phi_deg)), dist * math.cos(math.radians(phi_deg))
    if (s - r) ** 2 + w**2 <= r**2 * 1.0001:  # inside the circle: no wire reaches it
        return
    e1, e2 = _basis(a)
    across = math.cos(spin) * e1 + math.sin(spin) * e2
    length, direction = wrap(s * across + w * a, a, r)
    assert length == pytest.approx(_string_over_circle(s, w, r), abs=1e-6)
    assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-12)


@settings(max_examples=100, deadline=None)
@given(
    v=st.tuples(*(st.floats(-800, 800),) * 3).filter(lambda v: np.linalg.norm(v) > 60),
    r=st.floats(0.5, 25.0),
)
def test_wrap_gradient_against_finite_differences(v, r):
    a = np.array([0.0, 0.6, 0.8])
    v = np.asarray(v)
    _, g = wrap(v, a, r)
    h = 1e-5
    fd = [(wrap(v + h * e, a, r)[0] - wrap(v - h * e, a, r)[0]) / (2 * h) for e in np.eye(3)]
    np.testing.assert_allclose(g, fd, atol=1e-7)


def test_a_point_exit_is_the_zero_radius_bend():
    v = np.random.default_rng(1).normal(size=(50, 3)) * 300
    d, n = wire_path(None, v)
    length, direction = wrap(v, (0.0, 0.0, 1.0), 0.0)
    np.testing.assert_allclose(length, d, rtol=1e-14)
    np.testing.assert_allclose(direction, n, atol=1e-14)
    np.testing.assert_array_equal(physical_wire_mm(Eyelet((0.0, 0.0, 1.0), 3.0, 0.0), v), d)


def test_on_the_axis_the_wire_runs_straight():
    length, direction = wrap(np.array([0.0, 0.0, 300.0]), (0.0, 0.0, 1.0), 10.0)
    assert length == pytest.approx(300.0, abs=1e-12)
    np.testing.assert_allclose(direction, [0.0, 0.0, 1.0], atol=1e-15)
    # sideways at the pulley's top: a quarter of the pulley, then 290 mm level to the point
    length, direction = wrap(np.array([300.0, 0.0, 10.0]), (0.0, 0.0, 1.0), 10.0)
    assert length == pytest.approx(10 * math.pi / 2 + 290.0, abs=1e-9)
    np.testing.assert_allclose(direction, [1.0, 0.0, 0.0], atol=1e-12)


def test_exit_angle():
    assert exit_angle_deg(np.array([1.0, 0.0, 1.0]), (0.0, 0.0, 1.0)) == pytest.approx(45.0)
    assert exit_angle_deg(np.array([0.0, 0.0, -2.0]), (0.0, 0.0, 1.0)) == pytest.approx(180.0)


# -- the pulley in the one distance model ----------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    r=st.floats(1.0, 30.0),
)
def test_pulley_jacobian_against_finite_differences(seed, r):
    robot = _robot(exit="pulley", axis=list(AXIS), pulley_radius_mm=r)
    rng = np.random.default_rng(seed)
    names = [*robot.parameters, "al1", "d2", "tool_x", "tool_z"]
    es = robot.errors(names)
    x0 = es.to_internal(rng.normal(0, 0.3, len(names)))
    theta0 = np.radians([0, -90, 210, -90, 0, -90])
    q = theta0 + rng.uniform(-1.2, 1.2, (6, 6))
    model = with_errors(robot.nominal, names, x0)
    d, J = wire_jacobian(model, q, theta0, names)
    usable = np.isfinite(d) & (d > 80)  # well outside the pulley's circle
    h = 1e-6
    for k in range(len(names)):
        step = np.zeros(len(names))
        step[k] = h
        up = wire_lengths(with_errors(robot.nominal, names, x0 + step), q, theta0)
        down = wire_lengths(with_errors(robot.nominal, names, x0 - step), q, theta0)
        np.testing.assert_allclose(J[usable, k], ((up - down) / (2 * h))[usable], atol=2e-6)


def test_pulley_psi_is_the_jacobian_in_boundary_units(paper_plan):
    robot = _robot(exit="pulley", axis=list(AXIS), pulley_radius_mm=5.0)
    q, _, _ = paper_plan.all_points()
    names = robot.parameters
    psi = sensitivity(robot.nominal, q, paper_plan.theta0_deg, names).psi
    _, J = wire_jacobian(robot.nominal, np.radians(q), np.radians(paper_plan.theta0_deg), names)
    np.testing.assert_allclose(psi, robot.errors(names).per_boundary(J), atol=1e-12)
    point = sensitivity(_robot().nominal, q, paper_plan.theta0_deg, names).psi
    assert np.abs(psi - point).max() > 0.01  # the pulley does change Ψ


def test_pulley_robot_simulated_and_solved_recovers_the_truth(paper_plan):
    """Joint method on the paper plan with a 5 mm guide pulley: within 0.01 deg/mm of the
    truth (Table 5's offsets), while a point model on the same log is off by far more."""
    robot = _no_sag(_robot(exit="pulley", axis=list(AXIS), pulley_radius_mm=5.0))
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    text = wirecal.simulate_log(robot, plan, TABLE5, seed=3)
    m = wirecal.check_log(wirecal.parse_log(text, "sim.csv"), plan, robot)
    got = wirecal.solve(robot, plan, m).estimates["joint"].as_dict()
    assert max(abs(got[n] - TABLE5.get(n, 0.0)) for n in plan.order) < 0.01
    point = _robot()
    m = wirecal.check_log(wirecal.parse_log(text, "sim.csv"), plan, point, accept_foreign=True)
    wrong = wirecal.solve(point, plan, m).estimates["joint"].as_dict()
    assert max(abs(wrong[n] - TABLE5.get(n, 0.0)) for n in plan.order) > 0.1


def test_a_plan_point_within_the_pulley_is_named():
    robot = _robot(exit="pulley", axis=list(AXIS), pulley_radius_mm=15.0)
    with pytest.raises(WirecalError) as info:
        load_plan(VIPER / "paper_plan.toml", robot)
    assert info.value.problems == [
        f"{VIPER / 'paper_plan.toml'}: step[3].points_deg[{k}]: the tool point there is within "
        "the guide pulley's circle (encoder.pulley_radius_mm), where no wire reaches it; move "
        "or remove the point"
        for k in (4, 7)
    ]


@pytest.mark.slow  # a measurement run and two controller solves in the twin
def test_pulley_robot_through_the_twin_and_the_controller_solver(tmp_path):
    """wc.run in the twin over a 5 mm pulley; wc.solve and wc.solve2 agree with the PC."""
    from wirecal.app.compare import controller_runs

    from .twin_runs import measure_in_twin

    robot = _no_sag(_robot(exit="pulley", axis=list(AXIS), pulley_radius_mm=5.0))
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    run = measure_in_twin(robot, plan, TABLE5, tmp_path / "run", seed=4)
    m = wirecal.load_measurements(run.log, plan, robot)
    ref = wirecal.solve(robot, plan, m)
    joint = ref.estimates["joint"].as_dict()
    # the paper plan's reading-noise σ per parameter is at most about 0.012 deg/mm (the
    # Cramér–Rao bound; the twin now also vibrates and settles): the largest of the ten
    # errors stays within 0.03 (measured 0.017)
    assert max(abs(joint[n] - TABLE5.get(n, 0.0)) for n in plan.order) < 0.03
    for method, ctl in controller_runs(robot, plan, m, tmp_path).items():
        reference = ref.estimates[method].as_dict()
        assert max(abs(ctl.offsets[n] - reference[n]) for n in reference) <= 1e-4


# -- the eyelet --------------------------------------------------------------------------


def test_simulate_adds_the_eyelet_edge_wrap(paper_plan):
    robot = _robot(exit="eyelet", axis=list(AXIS), max_exit_deg=90.0, exit_edge_radius_mm=1.0)
    model = robot.model(TABLE5)
    ideal = true_lengths(model, paper_plan)
    real = true_lengths(model, paper_plan, robot.encoder.exit)
    extra = unmodelled_exit_mm(robot, paper_plan, model)
    np.testing.assert_allclose(real - ideal, extra, atol=1e-9)
    # every point within 0.5 mm of the far-field ρ(φ − sin φ), which is up to 0.5 mm
    v = tool_position(model, np.radians(paper_plan.all_points()[0])) - tool_position(
        model, np.radians(paper_plan.theta0_deg)[None]
    )
    far = far_field_edge_wrap_mm(exit_angle_deg(v, robot.encoder.exit.axis), 1.0)
    np.testing.assert_allclose(extra, far, atol=0.02)
    assert 0.4 < extra.max() < 0.55
    # the model is still the point exit: the robot's Ψ equals the ideal robot's
    assert robot.nominal.pulley is None
    assert unmodelled_exit_mm(_robot(), paper_plan).max() == 0.0


def test_the_paper_plan_beyond_a_narrow_cone_loads_with_a_warning(tmp_path, paper_plan):
    robot = _robot(exit="eyelet", axis=list(AXIS), max_exit_deg=3.0, exit_edge_radius_mm=1.0)
    plan = load_plan(VIPER / "paper_plan.toml", robot)  # still loads
    problems = cone_problems(robot, plan)
    assert len(problems) == plan.n_points  # not one point within ±3°
    assert "beyond max_exit_deg 3 of r.toml" in problems[0]
    assert largest_exit_deg(robot, plan) == pytest.approx(84.8, abs=0.1)
    assert cone_problems(_robot(), plan) == []


# -- the robot file keys -----------------------------------------------------------------

KEY_CASES = {
    "exit kind": ({"exit": "ring"}, 'encoder.exit: is "ring"; give "point"'),
    "eyelet needs axis": (
        {"exit": "eyelet", "max_exit_deg": 3.0, "exit_edge_radius_mm": 1.0},
        "encoder.axis: is missing",
    ),
    "axis not unit": (
        {"exit": "pulley", "axis": [0.0, 0.5, 0.5], "pulley_radius_mm": 5.0},
        "encoder.axis: has length 0.7071; give the unit vector",
    ),
    "axis component": (
        {"exit": "pulley", "axis": [0.0, 0.0, 2.0], "pulley_radius_mm": 5.0},
        "encoder.axis: value 3 is 2.0; give a number within ±1",
    ),
    "cone too wide": (
        {"exit": "eyelet", "axis": [0, 0, 1], "max_exit_deg": 120, "exit_edge_radius_mm": 1},
        "encoder.max_exit_deg: is 120; give a number > 0 and ≤ 90 deg",
    ),
    "cone missing": (
        {"exit": "eyelet", "axis": [0, 0, 1], "exit_edge_radius_mm": 1.0},
        "encoder.max_exit_deg: is missing",
    ),
    "edge negative": (
        {"exit": "eyelet", "axis": [0, 0, 1], "max_exit_deg": 3, "exit_edge_radius_mm": -1},
        "encoder.exit_edge_radius_mm: is -1; give a number between 0 and 100 mm",
    ),
    "pulley radius": (
        {"exit": "pulley", "axis": [0, 0, 1], "pulley_radius_mm": 0.0},
        "encoder.pulley_radius_mm: is 0.0; give a number > 0 and ≤ 100 mm",
    ),
    "eyelet key on a pulley": (
        {"exit": "pulley", "axis": [0, 0, 1], "pulley_radius_mm": 5.0, "max_exit_deg": 3.0},
        'encoder.max_exit_deg: belongs to exit = "eyelet", not "pulley"; remove it or change exit',
    ),
    "key without exit": (
        {"axis": [0, 0, 1]},
        'encoder.axis: belongs to exit = "eyelet" or "pulley", not "point"; remove it or change',
    ),
    "pulley key on the point exit": (
        {"exit": "point", "pulley_radius_mm": 5.0},
        'encoder.pulley_radius_mm: belongs to exit = "pulley", not "point"',
    ),
    "misspelt key": (
        {"exit": "pulley", "axis": [0, 0, 1], "pulley_radius": 5.0},
        "encoder.pulley_radius: unknown key (did you mean 'pulley_radius_mm'?)",
    ),
}


@pytest.mark.parametrize("case", sorted(KEY_CASES))
def test_exit_key_messages(case):
    keys, message = KEY_CASES[case]
    with pytest.raises(WirecalError) as info:
        _robot(**keys)
    assert any(f"r.toml: {message}" in p for p in info.value.problems), info.value.problems


@pytest.mark.parametrize(
    "keys",
    [
        {},
        {
            "exit": "eyelet",
            "axis": [0.0, 0.6, 0.8],
            "max_exit_deg": 3.0,
            "exit_edge_radius_mm": 0.5,
        },
        {"exit": "pulley", "axis": [0.0, 0.0, -1.0], "pulley_radius_mm": 12.5},
    ],
    ids=["point", "eyelet", "pulley"],
)
def test_exit_keys_written_back(tmp_path, keys):
    robot = _robot(**keys)
    text = robot_file_text(robot, header=["x"], row_notes=[""] * 6, encoder_note="enc")
    path = tmp_path / "robot.toml"
    path.write_text(text)
    assert load_robot(path).encoder.exit == robot.encoder.exit
    assert ("exit =" in text) == bool(keys)  # the point exit is the default, not written


def test_exit_types():
    robot = _robot(exit="pulley", axis=[0, 0, 1], pulley_radius_mm=5.0)
    assert robot.encoder.exit == Pulley((0.0, 0.0, 1.0), 5.0)
    assert robot.nominal.pulley == robot.encoder.exit


# -- the planner keeps an eyelet's points within its cone ---------------------------------

# per arm: θ0 of tests/test_planner.py and an axis near the mean wire direction there
CONE_ARMS = {
    "viper_s650": ([-72, -156, 235, 3, 64, 41], [0.069, 0.871, 0.487]),
    "puma560": ([112, -123, -32, 8, -53, -288], [0.032, 0.751, -0.66]),
    "abb_irb120": ([21, 5, -36, -43, -43, -184], [0.092, -0.351, -0.932]),
    "ur5e": ([-195, 236, -54, -181, -127, 56], [0.897, -0.05, 0.439]),  # seed 0, in its cell
}


@pytest.mark.slow  # designs a plan per arm
@pytest.mark.parametrize("arm", sorted(CONE_ARMS))
def test_planner_keeps_the_eyelet_cone(arm):
    theta0, axis = CONE_ARMS[arm]
    axis = list(np.asarray(axis) / np.linalg.norm(axis))
    data = read_toml(VIPER.parent / arm / "robot.toml", "robot file")
    data["encoder"].update(exit="eyelet", axis=axis, max_exit_deg=60.0, exit_edge_radius_mm=1.0)
    robot = robot_from_dict(data, arm)
    d = wirecal.design(robot, np.array(theta0, float))
    q, _, _ = d.plan.all_points()
    p = tool_position(robot.nominal, np.radians(q))
    p0 = tool_position(robot.nominal, np.radians(d.plan.theta0_deg)[None])[0]
    cosine = (p - p0) @ np.asarray(axis) / np.linalg.norm(p - p0, axis=1)
    angle = np.degrees(np.arccos(np.clip(cosine, -1, 1)))
    assert angle.max() <= 60.0 + 1e-9
    assert f"largest exit angle {angle.max():.1f} deg." in d.header()
    assert len(d.plan.order) >= 2  # the cone leaves something to calibrate


# -- through the command line ------------------------------------------------------------


def _robot_file(tmp_path, **encoder) -> str:
    text = (VIPER / "robot.toml").read_text().replace('exit = "point"\n', "")
    extra = "".join(
        f"{k} = {v!r}\n" if not isinstance(v, str) else f'{k} = "{v}"\n' for k, v in encoder.items()
    )
    text = text.replace("belt_mode = 0\n", "belt_mode = 0\n" + extra)
    path = tmp_path / "robot.toml"
    path.write_text(text)
    return str(path)


def _cli(*args):
    from click.testing import CliRunner

    from wirecal.cli.main import main

    return CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=False)


def test_cli_psi_warns_about_points_beyond_the_cone(tmp_path):
    robot = _robot_file(
        tmp_path, exit="eyelet", axis=list(AXIS), max_exit_deg=3.0, exit_edge_radius_mm=1.0
    )
    plan = VIPER / "paper_plan.toml"
    r = _cli("psi", robot, plan)
    assert r.exit_code == 0
    warnings = [line for line in r.stderr.splitlines() if "beyond max_exit_deg 3" in line]
    assert len(warnings) == 69  # every point of the paper plan
    assert warnings[0].startswith("warning: ")
    assert _cli("psi", robot, plan, "--strict").exit_code == 1


def test_cli_simulate_and_solve_a_pulley_robot(tmp_path):
    robot = _robot_file(tmp_path, exit="pulley", axis=list(AXIS), pulley_radius_mm=5.0)
    text = Path(robot).read_text()  # no assumed sag: _no_sag's reason
    no_sag = "[calibration]\ngravity_sag_deg_per_m = 0.0\n"
    Path(robot).write_text(text.replace("[calibration]\n", no_sag))
    plan, log = VIPER / "paper_plan.toml", tmp_path / "run.csv"
    assert _cli("simulate", robot, plan, "-o", log, "--seed", 4, "--random", 0.5).exit_code == 0
    r = _cli("solve", robot, plan, log)
    assert r.exit_code == 0, r.output
    assert "wire exit: swivel guide pulley, radius 5 mm, axis (" in r.stdout
