"""The cell (issue 21): the arm's body, the floor and keep-out volumes, checked everywhere.

The shipped UR5e plan is checked with this file's own forward kinematics (Universal Robots'
published standard DH parameters, not solver/kinematics); gen and psi --strict are shown
refusing plans that move through the arm, the floor or a box. Every language's gen refusing
its example's colliding plan, and its twin stopping it with the pre-flight bypassed, is
the conformance suite's safety section (tests/test_conformance_safety.py).
"""

from __future__ import annotations

import itertools
import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot, robot_file_text, robot_from_dict
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.candidates import blocked
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.planner import design
from wirecal.solver.plan.predict import predicted_accuracy

from .conftest import VIPER

EXAMPLES = Path(__file__).parent.parent / "examples"
UR5 = EXAMPLES / "ur5e"

# Universal Robots' published DH parameters of the UR5e (standard convention), mm and rad
UR_D = (162.5, 0.0, 0.0, 133.3, 99.7, 99.6)
UR_A = (0.0, -425.0, -392.2, 0.0, 0.0, 0.0)
UR_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)
UR_TOOL_MM = (-50.0, 0.0, 40.0)  # the example's wire fixture in the flange frame


def ur_points_mm(q_deg: np.ndarray) -> np.ndarray:
    """Return the UR5e's joint origins 1..6 and the tool point (7, 3) at joints q (deg)."""
    T = np.eye(4)
    out = []
    for i, q in enumerate(np.radians(q_deg)):
        c, s = math.cos(q), math.sin(q)
        ca, sa = math.cos(UR_ALPHA[i]), math.sin(UR_ALPHA[i])
        T = T @ np.array(
            [
                [c, -s * ca, s * sa, UR_A[i] * c],
                [s, c * ca, -c * sa, UR_A[i] * s],
                [0.0, sa, ca, UR_D[i]],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
        out.append(T[:3, 3].copy())
    out.append(T[:3, :3] @ np.array(UR_TOOL_MM) + T[:3, 3])
    return np.array(out)


def run_cli(*args: str):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def plan_text(robot: str, theta0: list[float], *points: list[float]) -> str:
    rows = "".join(f"    {list(p)},\n" for p in points)
    return (
        f'robot = "{robot}"\ntheta0_deg = {list(theta0)}\norder = ["th2"]\n\n'
        f'[[step]]\nparameter = "th2"\npoints_deg = [\n{rows}]\n'
    )


UR_THETA0 = [-195, 236, -54, -181, -127, 56]
VIPER_THETA0 = [0, -90, 210, -90, 0, -90]
# (robot, theta0, the colliding point, the pair named at the first colliding sample)
COLLIDING = {
    # the elbow folded to 172°: 14° short of straight back, the forearm's end is
    # √(425² + 392.2² − 2·425·392.2·cos 14°) = 104.7 mm from the shoulder, within the base
    # column's radius 60 + the forearm's 45
    "ur5e self": (UR5, UR_THETA0, [-195, 236, 172, -181, -127, 56], "link 1 (d1) and link 3 (a3)"),
    # the shoulder lowered to 200°: at 210° the tool point is 32 mm high (this file's FK),
    # inside the fixture's radius 40
    "ur5e floor": (UR5, UR_THETA0, [-195, 200, -54, -181, -127, 56], "tool fixture and the floor"),
    "viper floor": (VIPER, VIPER_THETA0, [0, 7, 210, -90, 0, -90], "tool fixture and the floor"),
    # the forearm (a3, d4; radius 55) meets the shoulder offset a1 (70) first on the way
    "viper self": (VIPER, VIPER_THETA0, [0, -159, 21, -90, 0, -90], "link 1 (a1) and link 4 (d4)"),
    "viper box": (
        VIPER,
        VIPER_THETA0,
        [0, -13, 237, -90, 0, -90],
        "tool fixture and box 'base column'",
    ),
}


def colliding_plan(tmp_path: Path, case: str) -> tuple[str, str, str]:
    folder, theta0, point, pair = COLLIDING[case]
    robot = load_robot(folder / "robot.toml")
    safe = [*theta0[:5], theta0[5] + 20]
    plan = tmp_path / "plan.toml"
    plan.write_text(plan_text(robot.name, theta0, safe, point), encoding="utf-8")
    return str(folder / "robot.toml"), str(plan), pair


# ---------- the shipped UR5e plan, checked independently ----------


def test_ur5e_plan_plans_every_parameter_inside_its_cell():
    """Every parameter planned; θ0, points, vias and every move: elbow within ±175° and
    every joint origin and the tool point above the table, by this file's own FK."""
    robot = load_robot(UR5 / "robot.toml")
    plan = load_plan(UR5 / "plan.toml", robot)
    assert sorted(plan.order) == sorted(robot.parameters)
    targets = [np.asarray(plan.theta0_deg, float)]
    for s in plan.steps:
        targets += [*s.via_deg, *s.points_deg, plan.theta0_deg]
    lowest = np.inf
    for a, b in itertools.pairwise(targets):
        n = int(np.ceil(np.max(np.abs(b - a)))) + 1  # a sample every degree or less
        for t in np.linspace(0.0, 1.0, n):
            q = a + t * (b - a)
            assert abs(q[2]) <= 175.0 + 1e-9
            lowest = min(lowest, float(ur_points_mm(q)[1:, 2].min()))
    # the smallest capsule radius is 40 mm: every origin on a link stays at least that high
    assert lowest >= 40.0


def test_ur5e_zero_pose_keeps_the_wrist_just_above_the_table():
    """At all joints 0 the UR5e's wrist 2 points down: its origin is d1 − d5 = 62.8 mm high,
    so link 5's capsule (radius 45) keeps 17.8 mm, 7.8 mm beyond the margin: the closest
    gap (the UR5's d1 − d5 = −5.49 mm put that capsule 50 mm into the table)."""
    robot = load_robot(UR5 / "robot.toml")
    gaps = robot.cell_gaps(np.zeros(6), np.zeros(3))
    assert ur_points_mm(np.zeros(6))[4, 2] == pytest.approx(162.5 - 99.7, abs=1e-9)
    assert gaps.smallest()[0] == pytest.approx(162.5 - 99.7 - 45.0 - 10.0, abs=1e-6)
    assert gaps.cause(0).startswith("link 5 (d5) and the floor: 18 mm apart, margin 10 mm")


def test_capsules_skip_adjacent_and_short_chained_pairs():
    """The Viper's forearm (d4) and upper arm (a2) meet at the elbow: skipped, its joint
    limits keep them apart; its d4 and the tool fixture are joined by 80 mm of links,
    less than their radii (55 + 37) and the margin: skipped; a1 and d4 are checked."""
    viper = load_robot(VIPER / "robot.toml")
    caps = viper.capsules
    skipped = {(a, b): why for a, b, why in caps.skipped}
    assert skipped[("link 2 (a2)", "link 4 (d4)")].startswith("adjacent")
    assert skipped[("link 4 (d4)", "tool fixture")].startswith("joined by 80 mm")
    checked = {(caps.names[i], caps.names[j]) for i, j in caps.pairs}
    assert ("link 1 (a1)", "link 4 (d4)") in checked


# ---------- gen, psi --strict and the twins ----------


@pytest.mark.parametrize("case", sorted(COLLIDING))
def test_gen_refuses_a_plan_moving_through_a_collision(tmp_path, case):
    robot, plan, pair = colliding_plan(tmp_path, case)
    out = tmp_path / "out"
    r = run_cli("gen", robot, plan, "-o", str(out))
    assert r.exit_code == 2
    assert f"step 1 (th2) point 2: the arm collides on the move there: {pair}" in r.output
    assert not out.exists()


def test_gen_refuses_a_ur5e_point_beyond_the_elbows_body_limit(tmp_path):
    plan = tmp_path / "plan.toml"
    folded = [-195, 236, 190, -181, -127, 56]
    plan.write_text(plan_text("Universal Robots UR5e", UR_THETA0, folded), encoding="utf-8")
    r = run_cli("gen", str(UR5 / "robot.toml"), str(plan), "-o", str(tmp_path / "out"))
    assert r.exit_code == 2
    beyond = "joint 3 = 190 deg is beyond its body limits [-175, 175]"  # not "within" (AU24)
    assert f"step 1 (th2) point 1: {beyond}" in r.output


def test_psi_strict_fails_on_a_collision(tmp_path):
    robot, plan, pair = colliding_plan(tmp_path, "viper floor")
    assert run_cli("psi", robot, plan).exit_code == 0  # a warning without --strict
    r = run_cli("psi", robot, plan, "--strict")
    assert r.exit_code == 1
    assert f"error: {plan}: step 1 (th2) point 2: the arm collides" in r.output
    assert pair in r.output


# ---------- plan: incomplete plans and blocked candidates ----------


def _viper_with(tmp_path: Path, old: str, new: str) -> str:
    text = (VIPER / "robot.toml").read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "robot.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return str(path)


@pytest.mark.slow
def test_plan_exits_non_zero_when_a_parameter_cannot_be_planned(tmp_path):
    robot = _viper_with(tmp_path, 'parameters = ["th2"', 'parameters = ["th1", "th2"')
    out = tmp_path / "plan.toml"
    theta0 = "0,-90,210,-90,0,-90"
    args = ["plan", robot, "-o", str(out), "--theta0", theta0, "--for", "stepwise"]
    r = run_cli(*args)
    assert r.exit_code == 2
    assert "1 of the 11 parameters of [calibration] cannot be planned" in r.output
    assert "not planned: th1: unobservable" in r.output
    assert not out.exists()
    r = run_cli(*args, "--allow-partial")
    assert r.exit_code == 0
    header = out.read_text(encoding="utf-8")
    assert "# not planned: th1: unobservable" in header
    assert "the 1 parameters not planned at their prior" in header


def test_predicted_error_counts_an_unplanned_parameter_at_its_prior():
    """d1 left at its prior (0.5 mm) moves the tool 0.5 mm along z everywhere: the mean
    error is at least 0.5 mm and at most 0.5 mm plus the planned parameters' error."""
    viper = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", viper)
    planned = predicted_accuracy(viper, plan)
    with_d1 = predicted_accuracy(viper, plan, unplanned=("d1",))
    for method in ("joint", "stepwise"):
        assert 0.5 - 1e-9 <= with_d1[method] <= 0.5 + planned[method] + 1e-9


def test_no_theta0_says_what_blocked_it(tmp_path):
    robot = load_robot(_viper_with(tmp_path, "floor_z_mm = -335.0", "floor_z_mm = 2000.0"))
    with pytest.raises(WirecalError) as exc:
        design(robot)
    assert "all 1000 θ0 drawn collide (cell)" in exc.value.problems[0]
    assert "and the floor" in exc.value.problems[0]
    with pytest.raises(WirecalError, match=r"theta0 \[0.0, -90.0.*collides \(cell\)"):
        design(robot, np.array(VIPER_THETA0, float))


def test_blocked_counts_name_the_cell():
    """With the floor raised from -335 to -250 mm, more of the candidates around the
    paper's θ0 reach into it: the count of candidates the cell blocks grows."""
    viper = load_robot(VIPER / "robot.toml")
    raised = robot_from_dict(
        {
            **tomllib.loads((VIPER / "robot.toml").read_text(encoding="utf-8")),
            "cell": {"floor_z_mm": -250.0},
        },
        "raised.toml",
    )
    opt = PlanOptions(samples=50)
    counts = []
    for robot in (viper, raised):
        text = blocked(robot, np.array(VIPER_THETA0, float), opt)
        found = re.search(r"^of (\d+) candidates, blocked: .*?(\d+) cell \(the arm in", text)
        assert found, text
        counts.append(int(found.group(2)))
    assert counts[1] > counts[0] > 0


# ---------- the [cell] table ----------

BASE = tomllib.loads((VIPER / "robot.toml").read_text(encoding="utf-8"))


def robot_with_cell(cell: dict):
    return robot_from_dict({**BASE, "cell": cell}, "r.toml")


def test_cell_table_reads_every_key():
    r = robot_with_cell(
        {
            "floor_z_mm": -300.0,
            "margin_mm": 5.0,
            "body_min_deg": [-170, -190, -29, -190, -120, -360],
            "body_max_deg": [170, 45, 200, 190, 120, 360],
            "box": [{"name": "table", "min_mm": [300, -200, -300], "max_mm": [700, 200, -250]}],
            "half_space": [{"name": "wall", "point_mm": [100, 0, 0], "normal": [-1, 0, 0]}],
            "encoder_housing": {"direction": [0, 0, -1], "length_mm": 100, "radius_mm": 40},
        }
    )
    assert (r.cell.floor_z_mm, r.cell.margin_mm) == (-300.0, 5.0)
    assert r.limits_deg()[1][2] == 200.0
    assert r.cell.boxes[0].name == "table"
    assert r.cell.half_spaces[0].normal == (-1, 0, 0)
    assert r.cell.housing is not None
    assert r.cell.housing.length_mm == 100
    # the wall at x = 100 mm: the paper's θ0 reaches forward, hundreds of mm beyond it
    gaps = r.cell_gaps(np.array(VIPER_THETA0, float), np.zeros(3))
    assert gaps.smallest()[0] < -100
    assert " and the wall: " in gaps.cause(0)


def test_limits_inset_by_the_margin_inside_the_body_limits():
    """Viper joint 3: −29..256 deg, the cell's body limits −20..200; joint 1 ±170."""
    r = robot_with_cell(
        {
            "body_min_deg": [-170, -190, -20, -190, -120, -360],
            "body_max_deg": [170, 45, 200, 190, 120, 360],
        }
    )
    lo, hi = r.limits_deg(5.0)
    assert (lo[2], hi[2]) == (-15.0, 195.0)  # the body limits, 5 deg inside
    assert (lo[0], hi[0]) == (-165.0, 165.0)  # no narrower than the joint limits
    lo, hi = r.limits_deg(5.0, body=False)  # what the controller enforces
    assert (lo[2], hi[2]) == (-24.0, 251.0)
    lo, hi = r.limits_deg(np.array([1, 2, 3, 4, 5, 6.0]))  # a margin per joint
    assert (lo[2], hi[5]) == (-17.0, 354.0)
    assert r.limits_deg()[0][2] == -20.0


@pytest.mark.parametrize(
    ("cell", "message"),
    [
        ({"floor": 0.0}, "r.toml: cell.floor: unknown key (did you mean 'floor_z_mm'?)"),
        (
            {"box": [{"name": "b", "min_mm": [0, 0, 0], "max_mm": [1, 1, 0]}]},
            "r.toml: cell.box[1].max_mm: [1.0, 1.0, 0.0] is not above min_mm",
        ),
        (
            {"half_space": [{"name": "w", "point_mm": [0, 0, 0], "normal": [0, 0, 2]}]},
            "r.toml: cell.half_space[1].normal: value 3 is 2",
        ),
        (
            {"body_min_deg": [0, 0, 0, 0, 0, 0], "body_max_deg": [1, 1, 0, 1, 1, 1]},
            "r.toml: cell.body_max_deg: joint 3: 0 is not above body_min_deg",
        ),
        ({"margin_mm": -1.0}, "r.toml: cell.margin_mm: is -1.0"),
    ],
)
def test_bad_cell_keys_are_named(cell, message):
    with pytest.raises(WirecalError) as exc:
        robot_with_cell(cell)
    assert any(p.startswith(message) for p in exc.value.problems), exc.value.problems


coord = st.floats(-2000, 2000, allow_nan=False)


@settings(max_examples=25, deadline=None)
@given(lo=st.tuples(coord, coord, coord), hi=st.tuples(coord, coord, coord))
def test_a_box_loads_exactly_when_its_max_is_above_its_min(lo, hi):
    box = {"name": "b", "min_mm": list(lo), "max_mm": list(hi)}
    if all(a < b for a, b in zip(lo, hi, strict=True)):
        assert robot_with_cell({"box": [box]}).cell.boxes[0].max_mm == hi
    else:
        with pytest.raises(WirecalError, match=r"cell\.box\[1\]\.max_mm: "):
            robot_with_cell({"box": [box]})


@settings(max_examples=25, deadline=None)
@given(v=st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 3))
def test_a_half_space_normal_loads_exactly_when_it_is_a_unit_vector(v):
    space = {"name": "w", "point_mm": [0, 0, 0], "normal": list(v)}
    if abs(float(np.linalg.norm(v)) - 1) <= 0.01:
        n = robot_with_cell({"half_space": [space]}).cell.half_spaces[0].normal
        assert float(np.linalg.norm(n)) == pytest.approx(1.0, abs=1e-12)
    else:
        with pytest.raises(WirecalError, match=r"normal: has length"):
            robot_with_cell({"half_space": [space]})


angles = st.lists(st.floats(-180, 180, allow_nan=False), min_size=6, max_size=6)


@settings(max_examples=30, deadline=None)
@given(q=angles, turn=st.floats(-180, 180, allow_nan=False))
def test_turning_joint_1_moves_no_gap_of_the_ur5e(q, turn):
    """Joint 1 turns the whole arm about the vertical axis: the distances between links
    and to the floor (all the UR5e's checks) stay the same, to 1e-6 mm."""
    robot = load_robot(UR5 / "robot.toml")
    a = np.array(q)
    b = a + np.array([turn, 0, 0, 0, 0, 0])
    ga, gb = robot.cell_gaps(a, np.zeros(3)), robot.cell_gaps(b, np.zeros(3))
    np.testing.assert_allclose(ga.gap, gb.gap, atol=1e-6)


@settings(max_examples=30, deadline=None)
@given(q=angles, drop=st.floats(0, 500, allow_nan=False))
def test_lowering_the_floor_widens_exactly_the_floor_gaps(q, drop):
    viper = tomllib.loads((VIPER / "robot.toml").read_text(encoding="utf-8"))
    high = robot_from_dict({**viper, "cell": {"floor_z_mm": -100.0}}, "high.toml")
    low = robot_from_dict({**viper, "cell": {"floor_z_mm": -100.0 - drop}}, "low.toml")
    gh, gl = high.cell_gaps(np.array(q), np.zeros(3)), low.cell_gaps(np.array(q), np.zeros(3))
    floor = np.array([label.endswith("and the floor") for label in gh.labels])
    np.testing.assert_allclose(gl.gap[floor], gh.gap[floor] + drop, atol=1e-9)
    np.testing.assert_allclose(gl.gap[~floor], gh.gap[~floor], atol=1e-9)


@pytest.mark.parametrize("arm", ["viper_s650", "puma560", "abb_irb120", "ur5e"])
def test_a_written_robot_file_keeps_its_cell(arm):
    """robot_file_text (import-urdf, the encoder-scale workflow) writes [cell] back."""
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    again = robot_from_dict(tomllib.loads(text), "again.toml")
    assert again.cell == robot.cell
    assert again.cell.floor_z_mm == {"viper_s650": -335.0, "puma560": -671.83}.get(arm, 0.0)
