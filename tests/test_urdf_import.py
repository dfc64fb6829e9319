"""URDF to programs in two commands (issue 21 item 4): import-urdf's wire point, language,
link radii, [cell] and placeholder speeds, then plan and gen on the real UR5 and Viper s650
URDFs with no edit."""

from __future__ import annotations

import itertools
import math
import tempfile
import tomllib
from pathlib import Path

import click
import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.cli.urdf import _numbers
from wirecal.formats.patch import write_patch
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot, robot_from_dict
from wirecal.formats.stl import stl_vertices
from wirecal.solver.errors import WirecalError
from wirecal.solver.identify import Estimate
from wirecal.solver.joint_speeds import placeholder_speeds
from wirecal.solver.kinematics import frames, tool_position

from .conftest import DATA
from .test_urdf import TOL_MM, make_urdf, urdf_fk

UR5_URDF = DATA / "ur5.urdf"
VIPER_URDF = DATA / "viper_s650.urdf"
UR5_DATASHEET_DH = {"d1": 89.159, "a2": 425.0, "a3": 392.25, "d4": 109.15, "d5": 94.65}
VIPER_SPEEDS = "328,300,375,375,375,600"  # DESIGN.md's Viper s650 data


def run(*args, ok: bool = True):
    r = CliRunner().invoke(main, [str(a) for a in args])
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    if ok:
        assert r.exit_code == 0, r.output
    return r


def radii_by_length(lengths_mm: list[float]) -> list[float]:
    """The stated rule, written out: 15 % of the length, at least 5 % of the sum, whole mm up."""
    total = sum(lengths_mm)
    return [math.ceil(max(0.15 * x, 0.05 * total)) for x in lengths_mm]


# --- the UR5 from ur_description --------------------------------------------------------------


@pytest.fixture(scope="module")
def ur5(tmp_path_factory):
    d = tmp_path_factory.mktemp("ur5")
    r = run(
        "import-urdf",
        UR5_URDF,
        "--tip",
        "tool0",
        "--wire-point-mm=-50,0,40",
        "--language",
        "urscript",
        "-o",
        d / "robot.toml",
    )
    return d, r.output


def test_ur5_import_writes_what_plan_and_gen_need(ur5):
    d, out = ur5
    doc = tomllib.loads((d / "robot.toml").read_text(encoding="utf-8"))
    assert doc["controller"] == {"language": "urscript"}
    assert doc["encoder"]["interface"] == "pulse"
    assert doc["encoder"]["counter_bits"] == 32
    assert doc["urdf"]["wire_point_mm"] == [-50.0, 0.0, 40.0]
    assert doc["cell"] == {"floor_z_mm": 0.0, "margin_mm": 10.0}
    assert "joint_speed_confirmed" not in doc["kinematics"]  # 180 °/s each: the data sheet's
    np.testing.assert_allclose(doc["kinematics"]["joint_speed_deg_s"], [180.0] * 6)
    np.testing.assert_allclose(doc["kinematics"]["joint_min_deg"], [-360, -360, -180, *[-360] * 3])
    # no meshes beside the fixture: every radius from the capsule lengths, and said so
    lengths = [0.0, 425.0, math.hypot(392.25, 109.15), 94.65, 82.3]
    assert doc["geometry"]["link_radius_mm"] == radii_by_length(lengths)
    assert "link radii 51, 64, 62, 51, 51 mm: all from link lengths" in out
    for link in ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link"):
        assert f"{link}'s mesh package://ur_description/meshes/ur5/collision/" in (
            d / "robot.toml"
        ).read_text(encoding="utf-8")
    # the wire point off the axis makes th6 observable: the paper's choice of 10 parameters
    assert doc["calibration"]["parameters"] == [
        "th2", "th3", "th4", "th5", "th6", "a2", "a3", "d4", "d5", "d6",
    ]  # fmt: skip
    assert "th6 is not proposed" not in out


def test_ur5_dh_is_universal_robots_published_table(ur5):
    d, _ = ur5
    robot = load_robot(d / "robot.toml")
    dh = robot.dh_deg()
    assert dh[0, 3] == pytest.approx(UR5_DATASHEET_DH["d1"], abs=1e-9)
    assert abs(dh[2, 1]) == pytest.approx(UR5_DATASHEET_DH["a2"], abs=1e-9)
    assert abs(dh[3, 1]) == pytest.approx(UR5_DATASHEET_DH["a3"], abs=1e-9)
    assert dh[3, 3] == pytest.approx(UR5_DATASHEET_DH["d4"], abs=1e-9)
    assert dh[4, 3] == pytest.approx(UR5_DATASHEET_DH["d5"], abs=1e-9)


@settings(max_examples=25, deadline=None)
@given(q=st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6))
def test_ur5_wire_point_moves_as_in_the_urdf(ur5, q):
    """The tool point is tool0's point (−50, 0, 40) mm, checked by an independent evaluator."""
    d, _ = ur5
    robot = load_robot(d / "robot.toml")
    q = np.array(q)
    T = urdf_fk(UR5_URDF, "base_link", "tool0", q)
    expected = T[:3, :3] @ np.array([-50.0, 0.0, 40.0]) + T[:3, 3]
    got = tool_position(robot.nominal, q[None])[0]
    np.testing.assert_allclose(got, expected, rtol=0, atol=TOL_MM)


@pytest.mark.slow
def test_ur5_urdf_to_urscript_programs_in_two_commands(ur5, tmp_path):
    d, _ = ur5
    run("plan", d / "robot.toml", "-o", tmp_path / "plan.toml")
    robot = load_robot(d / "robot.toml")
    plan = load_plan(tmp_path / "plan.toml", robot)
    assert sorted(s.parameter for s in plan.steps) == sorted(robot.parameters)  # all planned
    assert_inside_the_ur5_cell(plan)
    r = run(
        "gen",
        d / "robot.toml",
        tmp_path / "plan.toml",
        "-o",
        tmp_path / "out",
        "--host",
        "192.168.1.10",
        "--port",
        "50000",
    )
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["wc_check.script", "wc_mount.script", "wc_run.script"], r.output
    r = run("lint", tmp_path / "out" / "wc_run.script")
    assert "no problems" in r.output


UR5_LINKS = ("forearm_link", "wrist_1_link", "wrist_2_link", "wrist_3_link", "tool0")
"""The URDF links whose origins can come near the table (the shoulder's stay 89 mm up)."""


def assert_inside_the_ur5_cell(plan) -> None:
    """θ0, vias, points and every move between them, sampled every degree: the elbow within
    ±175° and every link origin and the wire point at least 40 mm (the smallest capsule
    radius) above the mounting plane, by the URDF's own joints (not wirecal's DH model)."""
    targets = [np.asarray(plan.theta0_deg, float)]
    for s in plan.steps:
        targets += [*s.via_deg, *s.points_deg, np.asarray(plan.theta0_deg, float)]
    lowest = np.inf
    for a, b in itertools.pairwise(targets):
        n = int(np.ceil(np.max(np.abs(b - a)))) + 1
        for t in np.linspace(0.0, 1.0, n):
            q = a + t * (b - a)
            assert abs(q[2]) <= 175.0 + 1e-9, q
            qr = np.radians(q)
            for link in UR5_LINKS:
                lowest = min(lowest, urdf_fk(UR5_URDF, "base_link", link, qr)[2, 3])
            T = urdf_fk(UR5_URDF, "base_link", "tool0", qr)
            lowest = min(lowest, (T[:3, :3] @ np.array([-50.0, 0.0, 40.0]) + T[:3, 3])[2])
    assert lowest >= 40.0


# --- the Viper s650 ---------------------------------------------------------------------------


@pytest.fixture(scope="module")
def viper(tmp_path_factory):
    d = tmp_path_factory.mktemp("viper")
    r = run("import-urdf", VIPER_URDF, "--tip", "link_6", "--wire-point-mm=-60,0,50", "-o",
            d / "robot.toml")  # fmt: skip
    return d, r.output


def test_viper_import_defaults_to_v_plus_with_its_belt_encoder(viper):
    d, out = viper
    doc = tomllib.loads((d / "robot.toml").read_text(encoding="utf-8"))
    assert doc["controller"] == {"language": "vplus"}
    assert (doc["encoder"]["interface"], doc["encoder"]["counter_bits"]) == ("belt", 24)
    assert doc["tool"]["point_mm"] == [-60.0, 0.0, 50.0]  # link_6 is the flange frame here
    assert doc["calibration"]["parameters"] == [
        "th2",
        "th3",
        "th4",
        "th5",
        "th6",
        "a1",
        "a2",
        "a3",
        "d4",
        "d6",
    ]  # fmt: skip  (the paper's ten)
    assert "warning" not in out  # 5.7–10.5 rad/s: real speeds


@pytest.mark.slow
def test_viper_urdf_to_v_plus_module_and_placeholder_speeds_refused(viper, tmp_path):
    d, _ = viper
    run("plan", d / "robot.toml", "-o", tmp_path / "plan.toml")
    run("gen", d / "robot.toml", tmp_path / "plan.toml", "-o", tmp_path / "out")
    assert (tmp_path / "out" / "WIRECAL.V2").is_file()
    # the same arm from a URDF with a template's 1 rad/s on every joint
    urdf = tmp_path / "placeholder.urdf"
    text = VIPER_URDF.read_text(encoding="utf-8")
    for v in ("5.72468", "5.235", "6.544", "10.47"):
        text = text.replace(f'velocity="{v}"', 'velocity="1.0"')
    urdf.write_text(text, encoding="utf-8")
    flagged = tmp_path / "flagged.toml"
    r = run("import-urdf", urdf, "--tip", "link_6", "--wire-point-mm=-60,0,50", "-o", flagged)
    assert "warning: ACTION NEEDED: every joint's speed is 1 rad/s" in r.output
    assert "joint_speed_confirmed = false" in flagged.read_text(encoding="utf-8")
    r = run("gen", flagged, tmp_path / "plan.toml", "-o", tmp_path / "refused", ok=False)
    assert r.exit_code == 2
    assert "kinematics.joint_speed_confirmed = false" in r.output
    assert not (tmp_path / "refused").exists()
    # the data sheet's speeds on the command line: confirmed, and gen writes the module
    r = run("import-urdf", urdf, "--tip", "link_6", "--wire-point-mm=-60,0,50", "-o", flagged,
            "--joint-speed-deg-s", VIPER_SPEEDS, "--force")  # fmt: skip
    assert "warning" not in r.output
    np.testing.assert_allclose(
        load_robot(flagged).joint_speed_deg_s, [328, 300, 375, 375, 375, 600]
    )
    run("gen", flagged, tmp_path / "plan.toml", "-o", tmp_path / "confirmed")
    assert (tmp_path / "confirmed" / "WIRECAL.V2").is_file()


# --- link radii from geometry -----------------------------------------------------------------

# a planar arm along x: joint axes all z, joints 400 and 300 mm apart, the tip 200 mm further
PLANAR = [
    ("j1", "revolute", "base", "l1", "0 0 0", "0 0 0", "0 0 1"),
    ("j2", "revolute", "l1", "l2", "0.4 0 0", "0 0 0", "0 0 1"),
    ("j3", "revolute", "l2", "l3", "0.3 0 0", "0 0 0", "0 0 1"),
    ("tip", "fixed", "l3", "wire", "0.2 0 0", "0 0 0", ""),
]


def _with_geometry(text: str, link: str, xml: str) -> str:
    return text.replace(f'<link name="{link}"/>', f'<link name="{link}">{xml}</link>')


def _collision(geometry: str, xyz: str = "0 0 0", rpy: str = "0 0 0") -> str:
    return (
        f'<collision><origin xyz="{xyz}" rpy="{rpy}"/><geometry>{geometry}</geometry></collision>'
    )


def _radii(tmp_path: Path, text: str) -> tuple[list[float], str]:
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(text, encoding="utf-8")
    r = run("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml", "--force")
    doc = tomllib.loads((tmp_path / "r.toml").read_text(encoding="utf-8"))
    return doc["geometry"]["link_radius_mm"], r.output


def test_radii_contain_boxes_cylinders_and_spheres(tmp_path):
    text = make_urdf(PLANAR)
    # link 1: a 400 × 60 × 80 mm box along its segment: corners 50 mm off the axis
    text = _with_geometry(text, "l1", _collision('<box size="0.4 0.06 0.08"/>', "0.2 0 0"))
    # link 2: a cylinder of radius 30 mm along x, and a sphere of radius 45 mm at its end
    text = _with_geometry(
        text,
        "l2",
        _collision('<cylinder radius="0.03" length="0.3"/>', "0.15 0 0", "0 1.5707963267948966 0")
        + _collision('<sphere radius="0.045"/>', "0.3 0 0"),
    )
    radii, out = _radii(tmp_path, text)
    assert radii == [50.0, 45.0]
    assert "link radii 50, 45 mm: all from the URDF's collision geometry" in out


def test_a_mesh_is_read_from_its_stl_and_an_absent_one_falls_back_to_lengths(tmp_path):
    stl = tmp_path / "meshes" / "l1.stl"
    stl.parent.mkdir()
    # ASCII STL in metres, scaled ×2 by the URDF: its farthest vertex 2 × 35 = 70 mm off axis
    stl.write_text(
        "solid l1\nfacet normal 0 0 1\nouter loop\nvertex 0.05 0.035 0\nvertex 0.1 0 0\n"
        "vertex 0.1 0 0.01\nendloop\nendfacet\nendsolid l1\n",
        encoding="ascii",
    )
    text = make_urdf(PLANAR)
    text = _with_geometry(text, "l1", _collision('<mesh filename="meshes/l1.stl" scale="2 2 2"/>'))
    text = _with_geometry(text, "l2", _collision('<mesh filename="package://arm/meshes/l2.stl"/>'))
    radii, out = _radii(tmp_path, text)
    assert radii[0] == 70.0
    assert radii[1] == radii_by_length([400.0, 300.0])[1]
    assert "link(s) 2 from link lengths" in out
    written = (tmp_path / "r.toml").read_text(encoding="utf-8")
    assert "link 2: l2's mesh package://arm/meshes/l2.stl is not there" in written
    # the same mesh as a binary STL, found as package://arm/… from a package folder "arm"
    pkg = tmp_path / "arm"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    tri = np.array([[0, 0, 0], [0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.055]], "<f4")
    (pkg / "meshes" / "l2.stl").write_bytes(
        b"\0" * 80 + (1).to_bytes(4, "little") + tri.tobytes() + b"\0\0"
    )
    (pkg / "urdf" / "arm.urdf").write_text(text.replace("meshes/l1.stl", "../meshes/l1.stl"))
    (pkg / "meshes" / "l1.stl").write_text(stl.read_text())
    r = run("import-urdf", pkg / "urdf" / "arm.urdf", "--tip", "wire", "-o", tmp_path / "p.toml")
    doc = tomllib.loads((tmp_path / "p.toml").read_text(encoding="utf-8"))
    assert doc["geometry"]["link_radius_mm"] == [70.0, 55.0], r.output


# --- [cell], options and the robot file's new keys ----------------------------------------------


def test_cell_floor_is_the_root_links_origin_in_frame_0(tmp_path):
    # the arm's base 500 mm above the root link "world"
    joints = [("mount", "fixed", "world", "base", "0 0 0.5", "0 0 0", ""), *PLANAR]
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(make_urdf(joints), encoding="utf-8")
    run("import-urdf", urdf, "--tip", "wire", "--base", "base", "-o", tmp_path / "r.toml")
    text = (tmp_path / "r.toml").read_text(encoding="utf-8")
    assert "# frame 0 is the base link's frame" in text
    assert tomllib.loads(text)["cell"]["floor_z_mm"] == -500.0
    # a moving joint between the root and the base: no fixed floor, no [cell], and a note
    joints[0] = ("slide", "revolute", "world", "base", "0 0 0.5", "0 0 0", "1 0 0")
    urdf.write_text(make_urdf(joints), encoding="utf-8")
    r = run("import-urdf", urdf, "--tip", "wire", "--base", "base", "-o", tmp_path / "s.toml")
    assert "no [cell]: joint 'slide' moves the base link" in r.output
    assert "cell" not in tomllib.loads((tmp_path / "s.toml").read_text(encoding="utf-8"))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--wire-point-mm", "1,2"], "give three numbers X,Y,Z (mm)"),
        (["--wire-point-mm=1,2,nan"], "give three numbers X,Y,Z (mm)"),
        (["--joint-speed-deg-s", "100,200"], "give 3 positive speeds (deg/s)"),
        (["--joint-speed-deg-s", "100,x,3"], "one speed per joint (deg/s)"),
        (["--language", "vplus", "--interface", "pulse"], "--interface pulse is not read"),
    ],
)
def test_bad_options_are_refused_writing_nothing(tmp_path, args, message):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(make_urdf(PLANAR), encoding="utf-8")
    r = run("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml", *args, ok=False)
    assert r.exit_code == 2
    assert message in r.output
    assert not (tmp_path / "r.toml").exists()


def _robot_doc() -> dict:
    return tomllib.loads((Path(__file__).parents[1] / "examples/ur5e/robot.toml").read_text())


@pytest.mark.parametrize(
    ("table", "key", "value", "message"),
    [
        ("kinematics", "joint_speed_confirmed", "no", "give true or false"),
        ("cell", "floor_z_mm", "x", "cell.floor_z_mm"),
        ("cell", "margin_mm", -1.0, "cell.margin_mm"),
        ("cell", "body_min_deg", [200.0] * 6, "joint 3: 175 is not above body_min_deg"),
        ("cell", "colour", 1, "colour"),
        ("urdf", "wire_point_mm", [1.0, 2.0], "urdf.wire_point_mm"),
    ],
)
def test_new_robot_file_keys_are_checked(table, key, value, message):
    doc = _robot_doc()
    doc.setdefault(table, {})[key] = value
    if table == "urdf":
        doc["urdf"].update(source="x.urdf", base_link="b", tip_link="t")
    with pytest.raises(Exception, match=message.replace("[", r"\[")):
        robot_from_dict(doc, "r.toml")


def test_cell_keys_in_the_agreed_schema_are_accepted():
    doc = _robot_doc()
    doc["cell"] = {
        "floor_z_mm": -12.5,
        "margin_mm": 10.0,
        "body_min_deg": [-350.0, -180, -170, -350, -350, -350],
        "body_max_deg": [350.0, 0, 170, 350, 350, 350],
    }
    doc["kinematics"]["joint_speed_confirmed"] = False
    robot = robot_from_dict(doc, "r.toml")
    assert not robot.joint_speed_confirmed
    assert "joint_speed_confirmed = false" in str(robot.speed_problem())


def test_geometry_off_the_dh_line_gives_a_wide_capsule_and_a_warning(tmp_path):
    # link 1's body 200 mm beside its DH line (a box 400 × 60 × 80 mm centred at y = 200 mm)
    text = make_urdf(PLANAR)
    text = _with_geometry(text, "l1", _collision('<box size="0.4 0.06 0.08"/>', "0.2 0.2 0"))
    radii, out = _radii(tmp_path, text)
    assert radii[0] == math.ceil(math.hypot(230, 40))  # the far corners: contained
    assert "warning: link(s) 1 (234 mm): the capsules containing the URDF's geometry" in out


def test_calibrated_ur5_urdf_with_the_wire_point_reproduces_the_patched_model(ur5, tmp_path):
    """export-urdf keeps --wire-point-mm: the calibrated URDF's tool0 carries the wire point
    where the patched model has it, d6 and th6 (the wire point's parameters) included."""
    d, _ = ur5
    robot = load_robot(d / "robot.toml")
    offsets = {"th2": 0.05, "a2": 0.3, "d4": -0.2, "th6": 0.1, "d6": 0.25}
    patch = tmp_path / "p.toml"
    estimate = Estimate("joint", tuple(offsets), np.array(list(offsets.values())), 0.01)
    write_patch(patch, robot, estimate, plan_fingerprint="0" * 64, log_path="run.csv",
                log_sha256="0" * 64, version="test")  # fmt: skip
    out = tmp_path / "cal.urdf"
    run("export-urdf", d / "robot.toml", patch, "-o", out)
    model = robot.model(offsets)
    q = np.random.default_rng(3).uniform(-3, 3, (40, 6))
    wire = np.array([-50.0, 0.0, 40.0])
    got = []
    for x in q:
        T = urdf_fk(out, "base_link", "tool0", x)
        got.append(T[:3, :3] @ wire + T[:3, 3])
    np.testing.assert_allclose(np.array(got), tool_position(model, q), atol=TOL_MM)
    # and without a patch the export leaves the arm as it was
    same = tmp_path / "same.urdf"
    run("export-urdf", d / "robot.toml", "-o", same)
    for x in q[:10]:
        np.testing.assert_allclose(
            urdf_fk(same, "base_link", "tool0", x), urdf_fk(UR5_URDF, "base_link", "tool0", x),
            atol=TOL_MM,
        )  # fmt: skip


coordinate = st.floats(-10.0, 10.0, allow_nan=False, width=32)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=3, max_size=30))
def test_stl_vertices_read_back_from_binary_and_ascii(vertices):
    """Both STL encodings of the same triangles give the same vertices (float32 exact)."""
    v = np.array(vertices[: len(vertices) // 3 * 3], dtype="<f4")
    facets = np.zeros(len(v) // 3, dtype=[("f", "<f4", (12,)), ("a", "<u2")])
    facets["f"][:, 3:] = v.reshape(-1, 9)
    binary = b"solid but binary".ljust(80) + len(facets).to_bytes(4, "little") + facets.tobytes()
    ascii_ = "solid t\n" + "".join(
        "facet normal 0 0 0\nouter loop\n"
        + "".join(f"vertex {x!r} {y!r} {z!r}\n" for x, y, z in v[i : i + 3].tolist())
        + "endloop\nendfacet\n"
        for i in range(0, len(v), 3)
    )
    with tempfile.TemporaryDirectory() as d:
        for name, data in (("b.stl", binary), ("a.stl", ascii_.encode())):
            path = Path(d) / name
            path.write_bytes(data)
            np.testing.assert_array_equal(stl_vertices(path), v.astype(float))


def test_a_broken_stl_is_an_error_naming_it(tmp_path):
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"solid x\nvertex 1 2\nendsolid\n")
    with pytest.raises(WirecalError, match=r"bad\.stl: an ASCII STL vertex is not three numbers"):
        stl_vertices(bad)
    bad.write_bytes(b"solid x\nendsolid\n")
    with pytest.raises(WirecalError, match=r"bad\.stl: no vertices"):
        stl_vertices(bad)
    bad.write_bytes(b"solid x\nvertex 1 2 nan\nendsolid\n")
    with pytest.raises(WirecalError, match=r"bad\.stl: a vertex is not finite"):
        stl_vertices(bad)


@given(st.integers(1, 20), st.integers(2, 8))
def test_equal_whole_rad_s_speeds_are_placeholders(rad_s, n):
    assert placeholder_speeds(np.full(n, math.degrees(rad_s))) is not None


@given(st.lists(st.floats(60.0, 1000.0), min_size=2, max_size=8))
def test_plausible_speeds_are_not_flagged(speeds):
    speeds = np.array(speeds)
    whole = np.isclose(np.radians(speeds), np.round(np.radians(speeds)), rtol=0, atol=1e-9)
    if np.all(speeds == speeds[0]) and whole[0]:
        assert placeholder_speeds(speeds) is not None
    else:
        assert placeholder_speeds(speeds) is None
    slow = speeds.copy()
    slow[-1] = 59.0
    assert "slower than 60 °/s" in str(placeholder_speeds(slow))


@given(st.lists(st.floats(allow_nan=False, allow_infinity=False), min_size=1, max_size=7))
def test_the_comma_separated_numbers_read_back(values):
    """--wire-point-mm and --joint-speed-deg-s: repr'd floats come back exactly; a count
    other than the one asked for, or a word, is a usage error."""
    text = ",".join(repr(v) for v in values)
    assert _numbers(None, "numbers")(None, None, text) == tuple(values)
    if len(values) != 3:
        with pytest.raises(click.BadParameter, match="give X"):
            _numbers(3, "X")(None, None, text)
    with pytest.raises(click.BadParameter):
        _numbers(None, "numbers")(None, None, text + ",x")


def _urdf_link_centres_mm(path: Path, q: np.ndarray) -> tuple[dict[str, tuple], np.ndarray]:
    """Each chain link's <inertial> (mass, centre in the base link, mm) and tool0, by hand."""
    import xml.etree.ElementTree as ET

    from scipy.spatial.transform import Rotation

    root = ET.parse(path).getroot()
    joints = {j.get("name"): j for j in root.iter("joint")}
    by_child = {j.find("child").get("link"): j for j in joints.values()}
    links, link = [], "tool0"
    while link in by_child:
        links.append(link)
        link = by_child[link].find("parent").get("link")
    T, out, k = np.eye(4), {}, 0
    for child in reversed(links):
        j = by_child[child]
        o = j.find("origin")
        step = np.eye(4)
        step[:3, :3] = Rotation.from_euler(
            "xyz", [float(v) for v in o.get("rpy").split()]
        ).as_matrix()
        step[:3, 3] = [1000.0 * float(v) for v in o.get("xyz").split()]
        T = T @ step
        if j.get("type") == "revolute":
            turn = np.eye(4)
            axis = np.array([float(v) for v in j.find("axis").get("xyz").split()])
            turn[:3, :3] = Rotation.from_rotvec(axis * q[k]).as_matrix()
            T, k = T @ turn, k + 1
        el = next(e for e in root.iter("link") if e.get("name") == child)
        inertial = el.find("inertial")
        if inertial is not None:
            xyz = np.array([1000.0 * float(v) for v in inertial.find("origin").get("xyz").split()])
            out[child] = (float(inertial.find("mass").get("value")), T[:3, :3] @ xyz + T[:3, 3])
    return out, T[:3, :3] @ np.array([-50.0, 0.0, 40.0]) + T[:3, 3]  # the wire point


def test_import_reads_the_links_inertials_into_gravity(ur5):
    # the robot file's masses are the URDF's, and each centre lies where the URDF's own chain
    # puts it: its distance to the wire point (-50, 0, 40 in tool0) agrees at random joints
    robot = load_robot(ur5[0] / "robot.toml")
    assert robot.masses is not None
    assert not robot.masses.assumed
    np.testing.assert_allclose(robot.masses.link_mass_kg, [3.7, 8.393, 2.275, 1.219, 1.219, 0.1879])
    for q in np.random.default_rng(2).uniform(-np.pi, np.pi, (4, 6)):
        centres, wire = _urdf_link_centres_mm(UR5_URDF, q)
        f = frames(robot.nominal, q[None])
        here_wire = tool_position(robot.nominal, q[None])[0]
        for k, name in enumerate(
            [
                "shoulder_link",
                "upper_arm_link",
                "forearm_link",
                "wrist_1_link",
                "wrist_2_link",
                "wrist_3_link",
            ]
        ):
            R = np.stack([f.x[0, k + 1], np.cross(f.z[0, k + 1], f.x[0, k + 1]), f.z[0, k + 1]], 1)
            here = f.o[0, k + 1] + R @ robot.masses.link_com_mm[k]
            want = np.linalg.norm(centres[name][1] - wire)
            assert np.linalg.norm(here - here_wire) == pytest.approx(want, abs=1e-6), name


def test_import_refuses_a_negative_link_mass_naming_the_link(tmp_path):
    bad = tmp_path / "ur5.urdf"
    bad.write_text(UR5_URDF.read_text().replace('<mass value="8.393"/>', '<mass value="-1"/>'))
    r = CliRunner().invoke(
        main, ["import-urdf", str(bad), "--tip", "tool0", "-o", str(tmp_path / "r.toml")]
    )
    assert r.exit_code != 0
    assert "link 'upper_arm_link': <inertial>: <mass value> is not a mass" in r.output
    assert not (tmp_path / "r.toml").exists()
