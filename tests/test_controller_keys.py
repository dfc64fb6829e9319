"""The robot file's ``[controller]`` table and the encoder keys per language; UR deltas."""

from __future__ import annotations

import copy
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats.patch_companion import read_companion
from wirecal.formats.robot_file import robot_file_text, robot_from_dict
from wirecal.lang.registry import language
from wirecal.lang.urscript.calibration import ur_deltas
from wirecal.solver.errors import WirecalError
from wirecal.solver.robot import Controller

from .conftest import ROOT

UR5 = tomllib.loads((ROOT / "examples" / "ur5e" / "robot.toml").read_text())
VIPER = tomllib.loads((ROOT / "examples" / "viper_s650" / "robot.toml").read_text())


def _ur(edit=None):
    data = copy.deepcopy(UR5)
    if edit:
        edit(data)
    return data


def _problems(data) -> list[str]:
    with pytest.raises(WirecalError) as info:
        robot_from_dict(data, "r.toml")
    return info.value.problems


def test_v_plus_when_absent():
    robot = robot_from_dict(copy.deepcopy(VIPER), "r.toml")
    assert robot.controller == Controller("vplus", None, None)
    assert robot.encoder.interface == "belt"


def test_ur5e_example():
    robot = robot_from_dict(_ur(), "r.toml")
    assert robot.controller == Controller("urscript", "192.168.1.10", 50000, software="5.20")
    assert robot.encoder.interface == "pulse"
    assert robot.encoder.channel == 0
    assert robot.encoder.pulse_inputs == (8, 9)
    assert robot.encoder.counter_bits == 32


def test_urscript_defaults_to_the_pulse_decoder():
    def edit(d):
        for key in ("interface", "channel", "pulse_inputs"):
            d["encoder"].pop(key)

    robot = robot_from_dict(_ur(edit), "r.toml")
    assert (robot.encoder.interface, robot.encoder.channel) == ("pulse", 0)
    assert robot.encoder.pulse_inputs == (8, 9)


MESSAGES = {
    "unknown language": (
        lambda d: d["controller"].__setitem__("language", "krl"),
        'r.toml: controller.language: is "krl"; give ',
    ),
    "unknown key": (
        lambda d: d["controller"].__setitem__("ip", "1.2.3.4"),
        "r.toml: controller.ip: unknown key",
    ),
    "port 0": (lambda d: d["controller"].__setitem__("port", 0), "r.toml: controller.port:"),
    "port as text": (
        lambda d: d["controller"].__setitem__("port", "50000"),
        "r.toml: controller.port:",
    ),
    "host with a space": (
        lambda d: d["controller"].__setitem__("host", "my pc"),
        "r.toml: controller.host: is 'my pc'; give an address or host name",
    ),
    "belt on a UR": (
        lambda d: d["encoder"].__setitem__("interface", "belt"),
        "r.toml: encoder.interface: is 'belt', which the Universal Robots URScript programs "
        "cannot read; give 'pulse'",
    ),
    "pulse on V+": (
        lambda d: d["controller"].__setitem__("language", "vplus"),
        "r.toml: encoder.interface: is 'pulse', which the Adept/Omron V+ and eV+ programs",
    ),
    "input outside 8-11": (
        lambda d: d["encoder"].__setitem__("pulse_inputs", [0, 1]),
        "r.toml: encoder.pulse_inputs:",
    ),
    "same input twice": (
        lambda d: d["encoder"].__setitem__("pulse_inputs", [9, 9]),
        "r.toml: encoder.pulse_inputs: A and B are both input 9; give two inputs",
    ),
    "encoder index 2": (
        lambda d: d["encoder"].__setitem__("channel", 2),
        "r.toml: encoder.channel:",
    ),
}


@pytest.mark.parametrize("case", sorted(MESSAGES))
def test_message(case):
    edit, message = MESSAGES[case]
    problems = _problems(_ur(edit))
    assert any(message in p for p in problems), problems


def test_pulse_inputs_only_for_the_pulse_decoder():
    data = copy.deepcopy(VIPER)
    data["encoder"]["pulse_inputs"] = [8, 9]
    problems = _problems(data)
    assert any('is for interface = "pulse" (URScript) only' in p for p in problems), problems


def test_interface_checked_against_the_language_when_another_controller_key_is_wrong():
    def edit(d):
        d["controller"]["host"] = "my pc"
        d["encoder"]["interface"] = "belt"

    problems = _problems(_ur(edit))
    assert any("controller.host: is 'my pc'" in p for p in problems), problems
    assert any("encoder.interface: is 'belt', which the Universal Robots" in p for p in problems)


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(
    port=st.one_of(st.integers(-10, 70_000), st.floats(allow_nan=True), st.text(max_size=5)),
    host=st.text(max_size=12),
)
def test_port_and_host_accepted_exactly_when_valid(port, host):
    def edit(d):
        d["controller"]["port"] = port
        d["controller"]["host"] = host

    valid_port = isinstance(port, int) and not isinstance(port, bool) and 1 <= port <= 65535
    valid_host = bool(host) and all(33 <= ord(c) <= 126 and c != '"' for c in host)
    if valid_port and valid_host:
        robot = robot_from_dict(_ur(edit), "r.toml")
        assert robot.controller == Controller("urscript", host, port, software="5.20")
    else:
        problems = _problems(_ur(edit))
        assert all(p.startswith("r.toml: controller.") for p in problems), problems


@settings(max_examples=30, deadline=None)
@given(
    language=st.sampled_from(["vplus", "urscript"]),
    host=st.one_of(st.none(), st.from_regex(r"[a-z0-9.\-]{1,20}", fullmatch=True)),
    port=st.one_of(st.none(), st.integers(1, 65535)),
    inputs=st.lists(st.integers(8, 11), min_size=2, max_size=2, unique=True),
)
def test_written_back_by_robot_file_text(language, host, port, inputs):
    data = copy.deepcopy(UR5 if language == "urscript" else VIPER)
    data["controller"] = {"language": language}
    if host is not None:
        data["controller"]["host"] = host
    if port is not None:
        data["controller"]["port"] = port
    if language == "urscript":
        data["encoder"]["pulse_inputs"] = inputs
    robot = robot_from_dict(data, "r.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    again = robot_from_dict(tomllib.loads(text), "again.toml")
    assert again.controller == robot.controller
    assert again.encoder == robot.encoder


# -- UR's standard-DH deltas beside a patch -------------------------------------------------


def test_solve_writes_ur_deltas_that_read_back(tmp_path):
    from click.testing import CliRunner

    from wirecal.cli.main import main
    from wirecal.formats.patch import read_patch
    from wirecal.formats.robot_file import load_robot

    ur5 = ROOT / "examples" / "ur5e"
    runner = CliRunner()
    log, patch = tmp_path / "run.csv", tmp_path / "patch.toml"
    robot_file, plan_file = ur5 / "robot.toml", ur5 / "plan.toml"
    sim = ["simulate", str(robot_file), str(plan_file), "-o", str(log), "--random", "1"]
    r = runner.invoke(main, sim)
    assert r.exit_code == 0, r.output
    args = ["solve", str(robot_file), str(plan_file), str(log), "-o", str(patch)]
    r = runner.invoke(main, [*args, "--method", "joint"])
    assert r.exit_code == 0, r.output
    conf = tmp_path / "patch.ur_calibration.conf"
    assert "patch.ur_calibration.conf" in r.output
    robot = load_robot(ur5 / "robot.toml")
    offsets = read_patch(patch).offsets_for(robot)
    deltas = read_companion(conf, language("urscript"))
    expected = ur_deltas(robot, offsets)
    for key, values in expected.items():
        np.testing.assert_allclose(deltas[key], values, rtol=0, atol=1e-15)
    # the mapping, by hand: th2 → delta_theta[1] (rad), a2 → delta_a[1] (m), d6 → delta_d[5]
    assert deltas["delta_theta"][1] == pytest.approx(np.radians(offsets["th2"]), abs=1e-12)
    assert deltas["delta_a"][1] == pytest.approx(offsets["a2"] / 1000, abs=1e-12)
    assert deltas["delta_d"][5] == pytest.approx(offsets["d6"] / 1000, abs=1e-12)
    assert not np.any(deltas["delta_alpha"])


def test_v_plus_solve_writes_no_ur_deltas(tmp_path):
    from wirecal.formats.patch import companion_paths
    from wirecal.formats.robot_file import load_robot

    viper = load_robot(ROOT / "examples" / "viper_s650" / "robot.toml")
    assert [p.name for p in companion_paths(viper, tmp_path / "p.toml")] == ["p.spec.txt"]


def test_ur_calibration_reader_refuses_a_short_vector(tmp_path):
    bad = tmp_path / "c.conf"
    bad.write_text(
        "[mounting]\ndelta_theta = [0, 0]\ndelta_a = [0, 0, 0, 0, 0, 0]\n"
        "delta_d = [0, 0, 0, 0, 0, 0]\ndelta_alpha = [0, 0, 0, 0, 0, 0]\n"
    )
    with pytest.raises(WirecalError, match=r"mounting\.delta_theta: has 2 values; expected 6"):
        read_companion(bad, language("urscript"))
