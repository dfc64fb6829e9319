"""Robot description files: the shipped example, and one test per validation message."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.robot_file import load_robot, robot_file_text, robot_from_dict
from wirecal.solver.errors import WirecalError

from .conftest import VIPER

BASE = tomllib.loads((VIPER / "robot.toml").read_text())


def test_viper_example(viper):
    assert viper.name == "Adept Viper s650"
    assert viper.n_joints == 6
    np.testing.assert_allclose(viper.dh_deg()[:, 1], [0, 75, 270, -90, 0, 0])
    np.testing.assert_allclose(viper.dh_deg()[:, 3], [0, 0, 0, 295, 0, 80])
    np.testing.assert_allclose(viper.dh_deg()[:, 0], [0, -90, 0, 90, -90, 90])
    assert viper.parameters == ("th2", "th3", "th4", "th5", "th6", "a1", "a2", "a3", "d4", "d6")
    np.testing.assert_allclose(viper.tool_point, [-60, 0, 50])
    assert viper.encoder.mm_per_count == 0.025488
    assert viper.encoder.range_mm == 1250
    assert viper.encoder.counter_bits == 24
    assert viper.encoder.max_wire_speed_mm_s == 1000
    assert viper.encoder.max_wire_accel_mm_s2 == 49000
    np.testing.assert_allclose(viper.joint_min_deg, [-170, -190, -29, -190, -120, -360])
    np.testing.assert_allclose(viper.joint_max_deg, [170, 45, 256, 190, 120, 360])
    np.testing.assert_allclose(viper.joint_speed_deg_s, [328, 300, 375, 375, 375, 600])
    assert viper.nominal_value("a1") == 75
    assert viper.nominal_value("d6") == 80


def _mutate(edit):
    data = copy.deepcopy(BASE)
    edit(data)
    return data


CASES = {
    "missing name": (lambda d: d.pop("name"), "r.toml: name: is missing"),
    "missing dh": (lambda d: d["kinematics"].pop("dh"), "r.toml: kinematics.dh: is missing"),
    "short dh row": (
        lambda d: d["kinematics"]["dh"][2].pop(),
        "r.toml: kinematics.dh[3]: has 3 values; expected 4 "
        "[alpha_deg, a_mm, theta_offset_deg, d_mm]",
    ),
    "nan in dh": (
        lambda d: d["kinematics"]["dh"][1].__setitem__(1, float("nan")),
        "r.toml: kinematics.dh[2]: value 2 is nan; give a number within ±10000 mm",
    ),
    "limits wrong length": (
        lambda d: d["kinematics"]["joint_min_deg"].pop(),
        "r.toml: kinematics.joint_min_deg: has 5 values; expected 6",
    ),
    "min above max": (
        lambda d: d["kinematics"]["joint_min_deg"].__setitem__(2, 300.0),
        "r.toml: kinematics.joint_min_deg: joint 3: min 300 is not below max 256",
    ),
    "nan limit": (
        lambda d: d["kinematics"]["joint_max_deg"].__setitem__(0, float("nan")),
        "r.toml: kinematics.joint_max_deg: value 1 is nan; give a number within ±3600 deg",
    ),
    "unknown parameter": (
        lambda d: d["calibration"]["parameters"].append("th7"),
        "r.toml: calibration.parameters: unknown parameter 'th7'",
    ),
    "duplicate parameter": (
        lambda d: d["calibration"]["parameters"].append("th2"),
        "r.toml: calibration.parameters: 'th2' is listed twice",
    ),
    "radian twists": (
        lambda d: [row.__setitem__(0, np.radians(row[0])) for row in d["kinematics"]["dh"]],
        "looks like radians; give degrees",
    ),
    "radian limits": (
        lambda d: (
            d["kinematics"].__setitem__("joint_min_deg", [-3.0] * 6),
            d["kinematics"].__setitem__("joint_max_deg", [3.0] * 6),
        ),
        "r.toml: kinematics.joint_max_deg: joint 6: limits [-3, 3] are within ±2π: they look "
        "like radians (that would be [-171.9, 171.9] deg); give degrees",
    ),
    "convention": (
        lambda d: d["kinematics"].__setitem__("convention", "standard"),
        'is "standard"; give "craig" (modified DH, the one supported)',
    ),
    "typo key": (
        lambda d: d["encoder"].__setitem__("rnage_mm", 1.0),
        "r.toml: encoder.rnage_mm: unknown key (did you mean 'range_mm'?)",
    ),
    "zero scale": (
        lambda d: d["encoder"].__setitem__("mm_per_count", 0.0),
        "r.toml: encoder.mm_per_count: must not be zero",
    ),
    "bits": (
        lambda d: d["encoder"].__setitem__("counter_bits", 24.5),
        "r.toml: encoder.counter_bits: is 24.5; give a whole number between 8 and 64",
    ),
    "narrow counter": (
        lambda d: d["encoder"].__setitem__("counter_bits", 16),
        "r.toml: encoder.counter_bits: a signed 16-bit counter tells lengths apart up to 32768 "
        "counts (835.191 mm at 0.025488 mm/count); range_mm 1250 is 49043 counts: wire "
        "lengths a counter turn apart would read the same",
    ),
    "tool length": (
        lambda d: d["tool"].__setitem__("point_mm", [1.0, 2.0]),
        "r.toml: tool.point_mm: has 2 values; expected 3 (x, y, z)",
    ),
    "negative speed": (
        lambda d: d["kinematics"]["joint_speed_deg_s"].__setitem__(4, -1.0),
        "r.toml: kinematics.joint_speed_deg_s: value 5 is -1.0; give a number > 0 and "
        "≤ 10000 deg/s",
    ),
    "radian theta offsets": (
        lambda d: d["kinematics"]["dh"][1].__setitem__(2, -1.5708),
        "r.toml: kinematics.dh: θ offsets (column 3) holds values like 1.5708: that looks like "
        "radians; give degrees (1.5708 rad = 90°)",
    ),
    "one joint in radians": (
        lambda d: (
            d["kinematics"]["joint_min_deg"].__setitem__(2, -0.5),
            d["kinematics"]["joint_max_deg"].__setitem__(2, 4.47),
        ),
        "r.toml: kinematics.joint_max_deg: joint 3: limits [-0.5, 4.47] are within ±2π: they "
        "look like radians (that would be [-28.65, 256.1] deg); give degrees",
    ),
    "narrow joint range": (
        lambda d: (
            d["kinematics"]["joint_min_deg"].__setitem__(4, 100.0),
            d["kinematics"]["joint_max_deg"].__setitem__(4, 108.0),
        ),
        "r.toml: kinematics.joint_max_deg: joint 5: range [100, 108] spans 8 deg, no more than "
        "10 deg: no room for plan points 5 deg inside both limits; check the limits",
    ),
    "lengths in metres": (
        lambda d: [
            row.__setitem__(k, row[k] / 1000) for row in d["kinematics"]["dh"] for k in (1, 3)
        ],
        "r.toml: kinematics.dh: the links add up to 0.81 mm (Σ|a| + Σ|d|), less than the widest "
        "link radius (70 mm): the lengths look like metres; give a and d in mm",
    ),
    "everything in metres": (
        lambda d: (
            [row.__setitem__(k, row[k] / 1000) for row in d["kinematics"]["dh"] for k in (1, 3)],
            d["geometry"].__setitem__("link_radius_mm", [0.07, 0.055, 0.045, 0.04, 0.035]),
        ),
        "r.toml: kinematics.dh: the links add up to 0.81 mm (Σ|a| + Σ|d|), less than 1 % of "
        "the encoder's range_mm (1250): the lengths look like metres",
    ),
    "8-bit counter": (
        lambda d: d["encoder"].__setitem__("counter_bits", 8),
        "r.toml: encoder.counter_bits: a signed 8-bit counter tells lengths apart up to 128 "
        "counts (3.26246 mm at 0.025488 mm/count); range_mm 1250 is 49043 counts: wire lengths "
        "a counter turn apart would read the same; give the width of the controller's counter "
        "(24 for a V+ belt encoder) or a smaller range_mm, and check mm_per_count",
    ),
    "huge dh value": (
        lambda d: d["kinematics"]["dh"][2].__setitem__(1, 1e300),
        "r.toml: kinematics.dh[3]: value 2 is 1e+300; give a number within ±10000 mm",
    ),
    "huge twist": (
        lambda d: d["kinematics"]["dh"][3].__setitem__(0, 900.0),
        "r.toml: kinematics.dh[4]: value 1 is 900.0; give a number within ±360 deg",
    ),
    "huge range": (
        lambda d: d["encoder"].__setitem__("range_mm", 1e300),
        "r.toml: encoder.range_mm: is 1e+300; give a number > 0 and ≤ 100000 mm",
    ),
    "tiny scale": (
        lambda d: d["encoder"].__setitem__("mm_per_count", 1e-300),
        "r.toml: encoder.mm_per_count: is 1e-300 mm: range_mm 1250 would be 1.25e+303 "
        "counts, more than a 64-bit counter holds; give the encoder's resolution in mm per "
        "count",  # issue 35 R15: the cause named, not the counter's width
    ),
    "boolean is not a number": (
        lambda d: d["tool"].__setitem__("point_mm", [-60.0, True, 50.0]),
        "r.toml: tool.point_mm: value 2 is true; give a number within ±10000 mm",
    ),
    "boolean is not an integer": (
        lambda d: d["encoder"].__setitem__("counter_bits", True),
        "r.toml: encoder.counter_bits: is true; give a whole number between 8 and 64",
    ),
    "float is not an integer": (
        lambda d: d["encoder"].__setitem__("channel", 1.0),
        "r.toml: encoder.channel: is 1.0; give a whole number between 0 and 16 (no decimal point)",
    ),
    "interface": (
        lambda d: d["encoder"].__setitem__("interface", "usb"),
        'r.toml: encoder.interface: is "usb"; give "belt" (Adept/Omron V+ and eV+: '
        'DEFBELT/BELT) or "device" (Adept/Omron V+ and eV+: DEVICE) or "group" (ABB RAPID '
        "(IRC5, RobotWare 6): the counter mapped to a group input signal, read with "
        'GInputDnum as a dnum (up to 32 bits: unconfirmed)) or "pulse" (Universal '
        "Robots URScript: the controller's pulse decoder)",
    ),
    "missing table": (
        lambda d: d.pop("encoder"),
        "r.toml: encoder: is missing; add the table [encoder]",
    ),
    "negative radius": (
        lambda d: d["geometry"]["link_radius_mm"].__setitem__(0, -1.0),
        "r.toml: geometry.link_radius_mm: value 1 is -1.0; give a number between 0 and 10000 mm",
    ),
    "negative wire speed": (
        lambda d: d["encoder"].__setitem__("max_wire_speed_mm_s", -1.0),
        "r.toml: encoder.max_wire_speed_mm_s: is -1.0; give a number > 0 and ≤ 20000 mm/s",
    ),
    "boolean wire acceleration": (
        lambda d: d["encoder"].__setitem__("max_wire_accel_mm_s2", True),
        "r.toml: encoder.max_wire_accel_mm_s2: is true; give a number > 0 and ≤ 1e+06 mm/s²",
    ),
    "wire acceleration beyond 100 g": (
        lambda d: d["encoder"].__setitem__("max_wire_accel_mm_s2", 2e6),
        "r.toml: encoder.max_wire_accel_mm_s2: is 2000000.0; give a number > 0 and ≤ 1e+06 mm/s²",
    ),
    "empty parameters": (
        lambda d: d["calibration"].__setitem__("parameters", []),
        "r.toml: calibration.parameters: is empty",
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_validation_message(case):
    edit, message = CASES[case]
    with pytest.raises(WirecalError) as info:
        robot_from_dict(_mutate(edit), "r.toml")
    assert any(message in p for p in info.value.problems), info.value.problems


def test_all_problems_reported_at_once():
    def edit(d):
        d.pop("name")
        d["encoder"]["range_mm"] = -1.0
        d["calibration"]["parameters"] = ["bogus"]

    with pytest.raises(WirecalError) as info:
        robot_from_dict(_mutate(edit), "r.toml")
    assert len(info.value.problems) == 3


def test_unreadable_and_malformed_files(tmp_path):
    with pytest.raises(WirecalError, match="cannot read robot file"):
        load_robot(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = \n")
    with pytest.raises(WirecalError, match=r"bad\.toml: not valid TOML"):
        load_robot(bad)
    binary = tmp_path / "robot.bin"
    binary.write_bytes(b'name = "x"\n\xff\xfe')
    with pytest.raises(
        WirecalError,
        match=r"robot\.bin: not UTF-8 text \(byte 11\); is this a "
        r"robot file\?",
    ):
        load_robot(binary)


@pytest.mark.parametrize(
    "path", sorted(VIPER.parent.glob("*/robot.toml")), ids=lambda p: p.parent.name
)
def test_shipped_arms_load_unchanged(path):
    robot = load_robot(path)
    assert robot.n_joints == 6
    # a V+ belt counter is 24 bits; the URScript programs log the raw int32 count; the
    # RAPID module reads a 32-bit group input
    bits = {"vplus": 24, "urscript": 32, "rapid": 32}[robot.controller.language]
    assert robot.encoder.counter_bits == bits


ACCEPTED = {
    "17-bit counter covers 1250 mm": lambda d: d["encoder"].__setitem__("counter_bits", 17),
    "an 11 deg joint range": lambda d: (
        d["kinematics"]["joint_min_deg"].__setitem__(4, 100.0),
        d["kinematics"]["joint_max_deg"].__setitem__(4, 111.0),
    ),
    "a 7 deg theta offset": lambda d: d["kinematics"]["dh"][1].__setitem__(2, 7.0),
    "a 90 deg theta offset": lambda d: d["kinematics"]["dh"][1].__setitem__(2, -90.0),
    "a small arm in mm": lambda d: [
        row.__setitem__(k, row[k] / 10) for row in d["kinematics"]["dh"] for k in (1, 3)
    ],
    "no geometry": lambda d: d.pop("geometry"),
    "a 10 m link": lambda d: d["kinematics"]["dh"][2].__setitem__(1, 10_000.0),
}


@pytest.mark.parametrize("case", sorted(ACCEPTED))
def test_plausible_values_accepted(case):
    robot_from_dict(_mutate(ACCEPTED[case]), "r.toml")


def test_other_wirecal_file_named(tmp_path):
    with pytest.raises(WirecalError) as info:
        load_robot(VIPER / "paper_plan.toml")
    assert info.value.problems == [
        f"{VIPER / 'paper_plan.toml'}: is a plan file (θ0 and point sets), not a robot file "
        "(DH table, limits, encoder)"
    ]


def _robot_file(tmp_path, edit):
    data = (VIPER / "robot.toml").read_text()
    path = tmp_path / "robot.toml"
    path.write_text(edit(data))
    return str(path)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda t: t.replace("-120.0, -360.0]", "100.0, -360.0]").replace(
                "120.0,  360.0]", "108.0,  360.0]"
            ),
            "joint 5: range [100, 108] spans 8 deg, no more than 10 deg",
        ),
        (lambda t: t.replace("270.0,  0.0,   0.0]", "1e300,  0.0,   0.0]"), "value 2 is 1e+300"),
        (lambda t: t.replace("counter_bits = 24", "counter_bits = 8"), "signed 8-bit counter"),
    ],
)
@pytest.mark.parametrize("command", ["plan", "simulate"])
def test_cli_refuses_implausible_robot(tmp_path, edit, message, command):
    """Each case once ended in a traceback or a result blamed on something else."""
    robot = _robot_file(tmp_path, edit)
    args = {
        "plan": ["plan", robot, "-o", str(tmp_path / "p.toml")],
        "simulate": [
            "simulate",
            robot,
            str(VIPER / "paper_plan.toml"),
            "-o",
            str(tmp_path / "s.csv"),
        ],
    }[command]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert f"error: {robot}: " in r.output
    assert message in r.output
    assert "Traceback" not in r.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["robot.toml"]


@pytest.mark.parametrize("limits", [True, False])
def test_wire_limits_are_optional_and_written_back(viper, limits):
    """The encoder's wire limits read back from robot_file_text; without them the file
    has no such keys and the robot has no limits."""
    data = copy.deepcopy(BASE)
    if not limits:
        del data["encoder"]["max_wire_speed_mm_s"], data["encoder"]["max_wire_accel_mm_s2"]
    robot = robot_from_dict(data, "r.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    again = robot_from_dict(tomllib.loads(text), "again.toml")
    assert again.encoder == robot.encoder
    assert ("max_wire_speed_mm_s = 1000.0" in text) is limits
    assert (again.encoder.max_wire_accel_mm_s2 == 49000.0) is limits


def test_body_limits_of_unequal_lengths_beside_a_broken_dh_are_a_message():
    """With the dh unreadable the joint count is unknown: body_min/max of 5 and 6 values
    were compared element-wise (a traceback, found by the fuzz test); now the dh is named."""
    data = tomllib.loads((VIPER / "robot.toml").read_text())
    data["kinematics"]["dh"][0] = [0.0, 0.0, 89.159]
    data["cell"] = {"body_min_deg": [-1.0] * 5, "body_max_deg": [1.0] * 6}
    with pytest.raises(WirecalError) as info:
        robot_from_dict(data, "r.toml")
    assert any("kinematics.dh" in p for p in info.value.problems), info.value.problems
