"""Modified → standard DH and UR calibration deltas: exact by forward kinematics."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats.fileio import Outputs
from wirecal.formats.robot_file import load_robot
from wirecal.lang.registry import language
from wirecal.lang.urscript.calibration import calibration_text, ur_deltas
from wirecal.solver import params as P
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import frames, tool_position
from wirecal.solver.standard_dh import flange_pose, from_modified, to_modified
from wirecal.solver.standard_dh import tool_position as std_tool_position

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
UR5 = load_robot(EXAMPLES / "ur5e" / "robot.toml")

# Universal Robots' published UR5e DH (standard convention), mm and degrees, typed here
# from the data sheet values quoted in examples/ur5e/robot.toml — not computed by the code.
UR5_PUBLISHED = {
    "d": [162.5, 0, 0, 133.3, 99.7, 99.6],
    "a": [0, -425.0, -392.2, 0, 0, 0],
    "alpha_deg": [90, 0, 0, 90, -90, 0],
}


def _modified_pose(model, q):
    f = frames(model, q)
    T = np.zeros((len(q), 4, 4))
    T[:, :3, :3], T[:, :3, 3], T[:, 3, 3] = f.R_last, f.o[:, -1], 1.0
    return T


def test_ur5_nominal_is_urs_published_table():
    std = from_modified(UR5)
    np.testing.assert_allclose(std.table[:, 1], UR5_PUBLISHED["d"], atol=1e-12)
    np.testing.assert_allclose(std.table[:, 2], UR5_PUBLISHED["a"], atol=1e-12)
    np.testing.assert_allclose(np.degrees(std.table[:, 3]), UR5_PUBLISHED["alpha_deg"], atol=1e-12)
    assert std.base_alpha == 0.0
    assert std.base_a_mm == 0.0


def test_home_pose_by_hand():
    # UR5e at q = 0 in standard DH: x = a2 + a3 = -817.2, y = -(d4 + d6) = -232.9,
    # z = d1 - d5 = 62.8 (flange), worked out on paper from the published table.
    T = flange_pose(from_modified(UR5), np.zeros((1, 6)))
    np.testing.assert_allclose(T[0, :3, 3], [-817.2, -232.9, 162.5 - 99.7], atol=1e-9)


names = list(P.all_names(6, with_tool=True))
offsets_st = st.dictionaries(
    st.sampled_from(names), st.floats(-2.0, 2.0, allow_nan=False), max_size=len(names)
)
q_st = st.lists(st.floats(-math.pi, math.pi), min_size=6, max_size=6)


@settings(max_examples=60, deadline=None)
@given(offsets=offsets_st, qs=st.lists(q_st, min_size=1, max_size=8))
def test_standard_matches_modified_to_1e_9_mm(offsets, qs):
    model = UR5.model(offsets)
    q = np.array(qs)
    std = from_modified(model)
    np.testing.assert_allclose(std_tool_position(std, q), tool_position(model, q), atol=1e-9)
    np.testing.assert_allclose(flange_pose(std, q), _modified_pose(model, q), atol=1e-9)
    back = to_modified(std)
    np.testing.assert_array_equal(back.dh, model.dh)


def test_deltas_map_names_one_to_one_in_si_units():
    d = ur_deltas(UR5, {"th2": 0.1, "a2": 0.5, "d4": -0.3, "al3": 0.02})
    np.testing.assert_allclose(d["delta_theta"], [0, math.radians(0.1), 0, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(d["delta_a"], [0, 0.0005, 0, 0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(d["delta_d"], [0, 0, 0, -0.0003, 0, 0], atol=1e-15)
    np.testing.assert_allclose(d["delta_alpha"], [0, 0, math.radians(0.02), 0, 0, 0], atol=1e-15)


def test_deltas_reproduce_the_calibrated_model():
    offsets = {"th3": -0.05, "a3": 0.4, "d5": 0.2, "al4": 0.01, "th6": 0.3}
    d = ur_deltas(UR5, offsets)
    std = from_modified(UR5)
    table = std.table.copy()
    table[:, 0] += d["delta_theta"]
    table[:, 1] += d["delta_d"] * 1e3
    table[:, 2] += d["delta_a"] * 1e3
    table[:, 3] += d["delta_alpha"]
    rebuilt = type(std)(table, std.base_alpha, std.base_a_mm, std.tool_point)
    q = np.random.default_rng(3).uniform(-3, 3, (50, 6))
    np.testing.assert_allclose(
        std_tool_position(rebuilt, q),
        tool_position(UR5.model(offsets), q),
        atol=1e-9,
    )


@pytest.mark.parametrize("name", ["a0", "al0", "tool_x", "bogus"])
def test_parameters_outside_urs_deltas_are_refused(name):
    with pytest.raises(WirecalError, match=name):
        ur_deltas(UR5, {name: 0.1})


def test_calibration_text_parses_and_says_unconfirmed(tmp_path):
    text = calibration_text(UR5, {"d4": 0.25})
    assert "UNCONFIRMED" in text
    data = tomllib.loads(text)["mounting"]
    assert data["delta_d"] == pytest.approx([0, 0, 0, 0.00025, 0, 0], abs=1e-15)
    assert data["delta_theta"] == [0.0] * 6
    out_path = tmp_path / "calibration.conf"
    with Outputs([out_path]) as out:
        out.put(out_path, language("urscript").patch_section(UR5, {"d4": 0.25}))
    assert out_path.read_text() == text
