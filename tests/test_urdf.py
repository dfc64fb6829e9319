"""URDF import and export: the DH model's forward kinematics equals the URDF's (an independent
URDF evaluator below: xml + Rodrigues), fixed joints, rpy rotations, y and flipped axes,
export of a calibrated model, round trips, and the refusals."""

from __future__ import annotations

import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.patch import write_patch
from wirecal.formats.robot_file import load_robot
from wirecal.formats.urdf import matrix_rpy, read_urdf
from wirecal.formats.urdf_model import read_chain
from wirecal.solver.dh_from_axes import dh_frames
from wirecal.solver.errors import WirecalError
from wirecal.solver.identify import Estimate
from wirecal.solver.kinematics import tool_position

ROOT = Path(__file__).resolve().parents[1]
ARMS = sorted((ROOT / "examples").glob("*/robot.toml"))
TOL_MM = 1e-9


# --- an independent URDF evaluator -------------------------------------------------------


def _rpy(r, p, y):
    def rx(a):
        return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])

    def ry(a):
        return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])

    def rz(a):
        return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])

    return rz(y) @ ry(p) @ rx(r)


def _axis_angle(k, q):
    k = np.asarray(k, float) / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(q) * K + (1 - np.cos(q)) * K @ K


def urdf_fk(path: Path, base: str, tip: str, q: np.ndarray) -> np.ndarray:
    """base → tip (4×4, mm) for the chain's moving joints at q (rad), straight from the XML."""
    joints = {}
    for el in ET.parse(path).getroot().findall("joint"):
        o = el.find("origin")
        ax = el.find("axis")
        joints[el.find("child").get("link")] = (
            el.find("parent").get("link"),
            el.get("type"),
            [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()],
            [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()],
            [float(v) for v in (ax.get("xyz") if ax is not None else "1 0 0").split()],
        )
    path_ = []
    link = tip
    while link != base:
        path_.append(joints[link])
        link = joints[link][0]
    T = np.eye(4)
    k = 0
    for _, kind, xyz, rpy, axis in reversed(path_):
        Tj = np.eye(4)
        Tj[:3, :3] = _rpy(*rpy)
        Tj[:3, 3] = 1000 * np.array(xyz)
        T = T @ Tj
        if kind != "fixed":
            M = np.eye(4)
            M[:3, :3] = _axis_angle(axis, q[k])
            T = T @ M
            k += 1
    return T


# --- test URDFs -----------------------------------------------------------------------------

JOINT = """  <joint name="{name}" type="{kind}">
    <parent link="{parent}"/><child link="{child}"/>
    <origin xyz="{xyz}" rpy="{rpy}"/>{axis}{limit}
  </joint>"""


def make_urdf(joints, links_extra="") -> str:
    links = {j[2] for j in joints} | {j[3] for j in joints}
    body = [f'  <link name="{x}"/>' for x in sorted(links)]
    for name, kind, parent, child, xyz, rpy, axis in joints:
        body.append(
            JOINT.format(
                name=name,
                kind=kind,
                parent=parent,
                child=child,
                xyz=xyz,
                rpy=rpy,
                axis="" if kind == "fixed" else f'\n    <axis xyz="{axis}"/>',
                limit=""
                if kind == "fixed"
                else '\n    <limit lower="-2.5" upper="2.5" effort="1" velocity="3.0"/>',
            )
        )
    return (
        '<?xml version="1.0"?>\n<robot name="test arm">\n'
        + "\n".join(body)
        + links_extra
        + "\n</robot>\n"
    )


# rpy rotations, y-axis joints, flipped axes, fixed joints before, within and after the chain
TWISTED = [
    ("mount", "fixed", "world", "base", "0.01 -0.02 0.03", "0 0 0.4", ""),
    ("j1", "revolute", "base", "l1", "0 0 0.3", "0 0 0.2", "0 0 1"),
    ("j2", "revolute", "l1", "l2", "0.05 0.1 0", "1.5707963267948966 0 0", "0 0 -1"),
    ("j3", "revolute", "l2", "l3", "0.4 0 0.02", "0 0 0.3", "0 0 -1"),
    ("spacer", "fixed", "l3", "l3b", "0.1 0.01 0", "0.1 -0.2 0.3", ""),
    ("j4", "revolute", "l3b", "l4", "0.2 0.03 0.05", "0.3 0.7 -0.2", "0 1 0"),
    ("j5", "revolute", "l4", "l5", "0 0.1 0", "-0.5 0.2 0.1", "0 -1 0"),
    ("j6", "revolute", "l5", "l6", "0.02 0 0.08", "0.1 0 0", "1 0 0"),
    ("flange", "fixed", "l6", "tool0", "0.01 0 0.05", "0 1.5707963267948966 0", ""),
    ("fixture", "fixed", "tool0", "wire", "-0.06 0 0.05", "0 0 0", ""),
]


@pytest.fixture(scope="module")
def twisted(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("urdf") / "twisted.urdf"
    p.write_text(make_urdf(TWISTED), encoding="utf-8")
    return p


def _import(urdf: Path, out: Path, *args: str) -> None:
    r = CliRunner().invoke(main, ["import-urdf", str(urdf), "-o", str(out), *args])
    assert r.exit_code == 0, r.output


angles = st.lists(st.floats(-2.5, 2.5), min_size=6, max_size=6)


@settings(max_examples=40, deadline=None)
@given(q=angles)
def test_import_has_the_urdfs_forward_kinematics(twisted, tmp_path_factory, q):
    out = tmp_path_factory.getbasetemp() / "twisted.toml"
    if not out.exists():
        _import(twisted, out, "--tip", "wire", "--base", "base")
    robot = load_robot(out)
    q = np.array(q)
    expected = urdf_fk(twisted, "base", "wire", q)[:3, 3]  # frame 0 is the base link here
    got = tool_position(robot.nominal, q[None])[0]
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOL_MM)


@settings(max_examples=30, deadline=None)
@given(q=angles)
def test_every_chain_link_pose_with_a_base_frame_dh_cannot_express(twisted, q):
    # from "world", joint 1's axis is off the x axis: frame 0 is then not the base frame
    ch = read_chain(read_urdf(twisted), "world", "wire")
    assert not np.allclose(ch.dh.frame0, np.eye(4))
    q = np.array(q)
    F = ch.dh.frame0 @ dh_frames(ch.dh.dh, q[None])[0]
    for link in ("l1", "l3b", "l6", "tool0", "wire"):
        k, D = ch.link_offsets[link]
        np.testing.assert_allclose(F[k] @ D, urdf_fk(twisted, "world", link, q), atol=TOL_MM)


def test_joint_zero_and_direction_are_the_urdfs(twisted, tmp_path):
    out = tmp_path / "r.toml"
    _import(twisted, out, "--tip", "wire", "--base", "base")
    robot = load_robot(out)
    np.testing.assert_allclose(robot.joint_min_deg, np.full(6, np.degrees(-2.5)))
    np.testing.assert_allclose(robot.joint_speed_deg_s, np.full(6, np.degrees(3.0)))
    # a small positive turn of every joint moves the tip as the URDF's does
    q = np.full(6, 1e-3)
    got = tool_position(robot.nominal, q[None])[0]
    np.testing.assert_allclose(got, urdf_fk(twisted, "base", "wire", q)[:3, 3], atol=TOL_MM)
    assert robot.urdf is not None
    assert robot.urdf.tip_link == "wire"
    assert Path(robot.urdf.path).resolve() == twisted.resolve()


@pytest.mark.parametrize("arm", ARMS, ids=lambda p: p.parent.name)
def test_shipped_arm_exported_then_imported(arm, tmp_path):
    robot = load_robot(arm)
    urdf, back = tmp_path / "arm.urdf", tmp_path / "arm.toml"
    r = CliRunner().invoke(main, ["export-urdf", str(arm), "-o", str(urdf)])
    assert r.exit_code == 0, r.output
    _import(urdf, back, "--tip", "wire_point", "--base", "link0")
    again = load_robot(back)
    # the mounting plane travels as the URDF's root link (the floor below frame 0), the
    # body limits as the URDF's joint limits (the vendor's ROS descriptions do the same)
    assert again.cell.floor_z_mm == pytest.approx(robot.cell.floor_z_mm, abs=1e-9)
    rng = np.random.default_rng(1)
    lo, hi = robot.limits_deg()
    q = np.radians(lo + rng.uniform(0, 1, (200, 6)) * (hi - lo))
    expected = tool_position(robot.nominal, q)
    np.testing.assert_allclose(tool_position(again.nominal, q), expected, atol=TOL_MM)
    np.testing.assert_allclose(again.joint_min_deg, lo, atol=1e-9)
    np.testing.assert_allclose(again.joint_max_deg, hi, atol=1e-9)
    np.testing.assert_allclose(again.joint_speed_deg_s, robot.joint_speed_deg_s, atol=1e-9)
    assert set(again.parameters) >= {"th2", "th3", "th4", "th5", "th6"}


def test_calibrated_urdf_reproduces_the_patched_model(twisted, tmp_path):
    robot_toml = tmp_path / "r.toml"
    _import(twisted, robot_toml, "--tip", "wire", "--base", "base")
    robot = load_robot(robot_toml)
    offsets = {"th2": 0.05, "a2": 0.3, "d4": -0.2, "al3": 0.02}
    patch = tmp_path / "p.toml"
    estimate = Estimate("joint", tuple(offsets), np.array(list(offsets.values())), 0.01)
    write_patch(
        patch,
        robot,
        estimate,
        plan_fingerprint="0" * 64,
        log_path="run.csv",
        log_sha256="0" * 64,
        version="test",
    )
    out = tmp_path / "cal.urdf"
    r = CliRunner().invoke(main, ["export-urdf", str(robot_toml), str(patch), "-o", str(out)])
    assert r.exit_code == 0, r.output
    model = robot.model({"th2": 0.05, "a2": 0.3, "d4": -0.2, "al3": 0.02})
    rng = np.random.default_rng(2)
    q = rng.uniform(-2.5, 2.5, (50, 6))
    got = np.array([urdf_fk(out, "base", "wire", x)[:3, 3] for x in q])
    np.testing.assert_allclose(got, tool_position(model, q), atol=TOL_MM)
    # only the chain's joint origins changed; the link off the base chain kept its
    old = {e.get("name"): e for e in ET.parse(twisted).getroot().findall("joint")}
    new = {e.get("name"): e for e in ET.parse(out).getroot().findall("joint")}
    assert set(old) == set(new)
    for name in old:
        assert old[name].find("axis") is None or (
            old[name].find("axis").get("xyz") == new[name].find("axis").get("xyz")
        )
    assert old["mount"].find("origin").get("xyz") == new["mount"].find("origin").get("xyz")
    # and re-imported, the calibrated URDF is the patched model
    again = tmp_path / "again.toml"
    _import(out, again, "--tip", "wire", "--base", "base")
    np.testing.assert_allclose(
        tool_position(load_robot(again).nominal, q), tool_position(model, q), atol=TOL_MM
    )


def test_export_keeps_visuals_and_refuses_a_changed_urdf(tmp_path):
    joints = [j for j in TWISTED if j[0] != "mount"]
    visual = (
        '\n  <link name="extra"><visual><geometry><box size="1 2 3"/></geometry></visual></link>'
        '\n  <joint name="extra_joint" type="fixed"><parent link="l2"/><child link="extra"/>'
        "</joint>"
    )
    src = tmp_path / "v.urdf"
    src.write_text(make_urdf(joints, visual), encoding="utf-8")
    robot_toml = tmp_path / "r.toml"
    _import(src, robot_toml, "--tip", "wire")
    out = tmp_path / "o.urdf"
    r = CliRunner().invoke(main, ["export-urdf", str(robot_toml), "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert ET.parse(out).getroot().find("link[@name='extra']/visual/geometry/box") is not None
    src.write_text(make_urdf(joints).replace('xyz="0.4 0 0.02"', 'xyz="0.41 0 0.02"'))
    r = CliRunner().invoke(main, ["export-urdf", str(robot_toml), "-o", str(tmp_path / "x")])
    assert r.exit_code == 2
    assert "re-import" in r.output


def _refusal(tmp_path, joints, *args) -> str:
    src = tmp_path / "bad.urdf"
    src.write_text(make_urdf(joints), encoding="utf-8")
    r = CliRunner().invoke(main, ["import-urdf", str(src), "-o", str(tmp_path / "r.toml"), *args])
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output
    assert not (tmp_path / "r.toml").exists()
    return r.output


def test_refuses_a_prismatic_joint_naming_it(tmp_path):
    joints = [*TWISTED[:3], ("slide", "prismatic", "l2", "l3", "0 0 0", "0 0 0", "1 0 0")]
    joints += TWISTED[4:]
    assert "joint 'slide' is a prismatic joint" in _refusal(tmp_path, joints, "--tip", "wire")


def test_refuses_a_tip_on_another_branch(tmp_path):
    joints = [*TWISTED, ("side", "revolute", "l2", "camera", "0 0 0", "0 0 0", "0 0 1")]
    out = _refusal(tmp_path, joints, "--tip", "camera", "--base", "l3")
    assert "no serial path from 'l3' to 'camera'" in out


def test_refuses_an_unknown_link_and_the_same_line(tmp_path):
    assert "--tip 'nope' is not a link" in _refusal(tmp_path, TWISTED, "--tip", "nope")
    same = [TWISTED[1], ("j1b", "revolute", "l1", "l2", "0 0 0.1", "0 0 0", "0 0 1")]
    assert "turn about the same line" in _refusal(tmp_path, same, "--tip", "l2")


def test_refuses_rounded_right_angles(tmp_path):
    # j2 → j3 is a rotation of 1.5708 − (π/2 + …) about x: 3.7e-6 rad from parallel
    joints = [TWISTED[1], (*TWISTED[2][:5], "1.5707963267948966 0 0", "0 0 1")]
    joints.append(("j3", "revolute", "l2", "l3", "0.4 0 0", "-1.5708 0 0", "0 1 0"))
    joints.append(("j4", "revolute", "l3", "l4", "0.3 0 0", "0 0 0", "0 0 1"))
    out = _refusal(tmp_path, joints, "--tip", "l4")
    assert "from parallel" in out
    assert "'j2' and 'j3'" in out
    assert "--parallel-tol-deg 0.00022" in out  # 3.7e-6 rad, and a margin
    robot_toml = tmp_path / "r.toml"
    r = CliRunner().invoke(
        main,
        [
            "import-urdf",
            str(tmp_path / "bad.urdf"),
            "-o",
            str(robot_toml),
            "--tip",
            "l4",
            "--parallel-tol-deg",
            "0.00022",
        ],
    )
    assert r.exit_code == 0, r.output
    assert "so the DH tip differs from the URDF's by up to" in r.output
    robot = load_robot(robot_toml)
    assert robot.urdf is not None
    assert robot.urdf.parallel_tol_deg == 0.00022
    r = CliRunner().invoke(main, ["export-urdf", str(robot_toml), "-o", str(tmp_path / "o.urdf")])
    assert r.exit_code == 0, r.output  # export re-derives the chain with the same tolerance


def test_missing_velocity_named(tmp_path):
    src = tmp_path / "v.urdf"
    src.write_text(make_urdf(TWISTED).replace('velocity="3.0"', "", 1), encoding="utf-8")
    r = CliRunner().invoke(
        main, ["import-urdf", str(src), "-o", str(tmp_path / "r.toml"), "--tip", "wire"]
    )
    assert r.exit_code == 2
    assert "joint 'j1': needs <limit velocity=…>" in r.output


def test_reader_errors_name_the_file(tmp_path):
    bad = tmp_path / "x.urdf"
    bad.write_text("<robot><joint name='a' type='revolute'><parent link='p'/></joint></robot>")
    with pytest.raises(WirecalError, match="joint 'a': needs <parent"):
        read_urdf(bad)
    bad.write_text("<robot")
    with pytest.raises(WirecalError, match="not valid XML"):
        read_urdf(bad)


def test_axes_a_rounding_error_from_parallel_are_made_parallel(tmp_path):
    # j3's axis is 3e-10 rad off j2's (a π/2 written with 9 digits does this)
    joints = [*TWISTED[1:3], ("j3", "revolute", "l2", "l3", "0.4 0 0.02", "3e-10 0 0", "0 0 -1")]
    joints += [("j4", "continuous", "l3", "l4", "0.3 0 0", "1.2 0 0", "0 0 1")]
    src = tmp_path / "s.urdf"
    src.write_text(make_urdf(joints), encoding="utf-8")
    r = CliRunner().invoke(
        main, ["import-urdf", str(src), "-o", str(tmp_path / "r.toml"), "--tip", "l4"]
    )
    assert r.exit_code == 0, r.output
    assert "'j2' and 'j3' are 3e-10 rad from parallel" in r.output
    assert "joint 'j4' is continuous" in r.output
    robot = load_robot(tmp_path / "r.toml")
    assert robot.dh[2, 0] == 0.0  # exactly parallel in the file
    np.testing.assert_array_equal(robot.joint_max_deg[3], 360.0)
    q = np.array([0.3, -0.4, 1.0, 0.7])
    got = tool_position(robot.nominal, q[None])[0]
    np.testing.assert_allclose(got, urdf_fk(src, "base", "l4", q)[:3, 3], atol=1e-6)


@settings(max_examples=200, deadline=None)
@given(
    roll=st.floats(-3.1, 3.1),
    yaw=st.floats(-3.1, 3.1),
    sign=st.sampled_from([1.0, -1.0]),
    off=st.sampled_from([0.0, 1e-12, 1e-9, 1e-7, 1e-5, 0.3]),
)
def test_rpy_of_a_rotation_near_gimbal_lock(roll, yaw, sign, off):
    # a calibrated tool frame at pitch ≈ ±90° (KUKA's tool0) once lost 7.6e-6 mm here
    R = _rpy(roll, sign * (np.pi / 2 - off), yaw)
    np.testing.assert_allclose(_rpy(*matrix_rpy(R)), R, atol=1e-15)


def test_a_solved_patch_exported_as_urdf(tmp_path):
    """simulate → solve → export-urdf on the Viper: the URDF is the patched model."""
    robot_path = ROOT / "examples" / "viper_s650" / "robot.toml"
    plan = ROOT / "examples" / "viper_s650" / "paper_plan.toml"
    log, patch, out = tmp_path / "run.csv", tmp_path / "patch.toml", tmp_path / "cal.urdf"
    for args in (
        ["simulate", robot_path, plan, "-o", log, "--random", "1", "--seed", "2"],
        ["solve", robot_path, plan, log, "-o", patch, "--method", "joint"],
        ["export-urdf", robot_path, patch, "-o", out],
    ):
        r = CliRunner().invoke(main, [str(a) for a in args])
        assert r.exit_code == 0, r.output
    robot = load_robot(robot_path)
    errors = {
        name: entry["offset"]
        for name, entry in tomllib.loads(patch.read_text())["parameters"].items()
    }
    assert set(errors) == set(robot.parameters)
    model = robot.model(errors)
    q = np.random.default_rng(4).uniform(-2, 2, (30, 6))
    got = np.array([urdf_fk(out, "link0", "wire_point", x)[:3, 3] for x in q])
    np.testing.assert_allclose(got, tool_position(model, q), atol=TOL_MM)


def test_the_robot_files_urdf_table_is_checked(tmp_path):
    text = (ROOT / "examples" / "viper_s650" / "robot.toml").read_text()
    bad = tmp_path / "r.toml"
    bad.write_text(text + '\n[urdf]\nsource = 3\nbase_link = "b"\nparallel_tol_deg = 1.0\n')
    with pytest.raises(WirecalError) as err:
        load_robot(bad)
    problems = "\n".join(err.value.problems)
    assert "urdf.source: is 3; give a non-empty string" in problems
    assert "urdf.tip_link: is missing" in problems
    assert "urdf.parallel_tol_deg: is 1.0; give a number > 0 and ≤ 0.05 deg" in problems
