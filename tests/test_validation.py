"""The validation procedures: setup files, the design of their runs, their logs (strict
readers) and their analyses."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.validation_files import load_setup, read_validation_log
from wirecal.solver import pose
from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.ik.solutions import solve
from wirecal.solver.kinematics import tool_position
from wirecal.solver.validation.analysis import config_discrepancy, plane_residuals
from wirecal.solver.validation.design import CONFIGS, config_poses, plate_grid

from .conftest import VIPER

SETUP = VIPER / "validation.toml"


@pytest.fixture(scope="module")
def setup():
    return load_setup(SETUP)


def test_config_poses_reachable_four_ways_and_deterministic(viper, setup):
    small = dataclasses.replace(setup, poses=8)
    poses = config_poses(viper, small)
    assert poses.shape == (8, 6)
    np.testing.assert_array_equal(poses, config_poses(viper, small))
    model = viper.nominal
    for p in poses:
        sols = [
            s
            for s in solve(viper, *pose.matrix(*p), margin_deg=1.0)
            if s.within_limits and s.config[0] == "righty"
        ]
        assert {s.config[1:] for s in sols} == set(CONFIGS)
        d = np.linalg.norm(
            tool_position(model, np.array([s.q for s in sols])) - setup.encoder_mm, axis=1
        )
        assert np.all(d < viper.encoder.range_mm - 50)


def test_plate_grid(viper, setup):
    index, points, targets = plate_grid(viper, setup)
    assert len(index) == 209
    assert sorted(index) == [(i, j) for i in range(1, 20) for j in range(1, 12)]
    assert index[:2] == [(1, 1), (2, 1)]
    assert index[18:21] == [(19, 1), (19, 2), (18, 2)]  # every other row reversed
    assert index[-1] == (19, 11)
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    np.testing.assert_allclose(steps.max(), 25.0)  # every point neighbours the one before
    np.testing.assert_allclose(points[-1], setup.plate_origin_mm + np.array([400, 250, 0]))
    np.testing.assert_allclose(targets[:, 2], setup.plate_origin_mm[2] + 100 + 20)
    assert np.all(targets[:, 4] == 180)  # tool pointing down


def test_unreachable_plate_is_a_clear_error(viper, setup):
    far = dataclasses.replace(setup, plate_origin_mm=np.array([900.0, -125, -300]))
    with pytest.raises(WirecalError) as info:
        plate_grid(viper, far)
    assert (
        "plate: grid point (1, 1) at [900.0, -125.0, -300.0] is out of reach"
        in info.value.problems[0]
    )
    assert info.value.problems[-1].startswith("… and ")


def test_a_plate_point_beyond_a_joint_limit_is_not_called_out_of_reach(viper, setup):
    """Issue 35: a joint limit was reported as "out of reach". With joint 1 limited to
    -10 deg, the plate's first point (220, -125) needs j1 = atan2(-125, 220) = -29.6 deg."""
    lo = viper.joint_min_deg.copy()
    lo[0] = -10.0
    with pytest.raises(WirecalError) as info:
        plate_grid(dataclasses.replace(viper, joint_min_deg=lo), setup)
    first = info.value.problems[0]
    assert "grid point (1, 1) at [220.0, -125.0, -300.0] is reachable" in first
    assert "out of reach" not in first
    expected_deg = np.degrees(np.arctan2(-125.0, 220.0))
    shown_deg = float(re.search(r"only with joint 1 at (-?[\d.]+) deg", first).group(1))
    assert abs(shown_deg - expected_deg) < 0.1  # the printed angle is rounded to 0.1 deg
    assert "beyond its limits -10 … 170 deg less the margin 1" in first
    assert "check the robot file's joint limits" in first


def test_setup_file_errors(tmp_path):
    bad = tmp_path / "v.toml"
    bad.write_text(
        "[configuration]\nencoder_mm = [1, 2]\nposes = 0\n[plate]\n"
        "grid = [1, 11]\norigin_mm = [0, 0, 0]\n"
    )
    with pytest.raises(WirecalError) as info:
        load_setup(bad)
    text = "\n".join(info.value.problems)
    assert "configuration.encoder_mm: has 2 values; expected 3 (x, y, z)" in text
    assert "configuration.poses: is 0; give a whole number between 1 and 100000" in text
    assert "plate.grid: needs at least 2 × 2 points" in text


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "encoder_mm = [850.0, 0.0, -150.0]",
            "encoder_mm = [0.85, 0.0, -0.15]",
            "configuration.encoder_mm: [0.85, 0, -0.15]",
        ),
        (
            "probe_mm = [0.0, 0.0, 100.0]",
            "probe_mm = [0.0, 0.0, 0.1]",
            "plate.probe_mm: [0, 0, 0.1]",
        ),
        (
            "origin_mm = [220.0, -125.0, -300.0]",
            "origin_mm = [0.22, -0.125, -0.3]",
            "plate.origin_mm: [0.22, -0.125, -0.3]",
        ),
        ("size_mm = [400.0, 250.0]", "size_mm = [0.4, 0.25]", "plate.size_mm: [0.4, 0.25]"),
    ],
    ids=["encoder", "probe", "origin", "size"],
)
def test_ud04_a_setup_in_metres_is_named(tmp_path, old, new, message):
    """UD04's neighbour in the validation setup: encoder_mm in metres was taken as mm and gen
    wrote the configuration run for an encoder at the robot's base without a word; the
    probe, the plate's corner and size in metres were refused 206 times as collisions or
    out of reach, the unit not named."""
    text = SETUP.read_text()
    assert old in text
    bad = tmp_path / "v.toml"
    bad.write_text(text.replace(old, new))
    with pytest.raises(WirecalError) as info:
        load_setup(bad)
    assert info.value.problems == [
        f"{bad}: {message}: every value under 1 mm: that looks like metres; give it in mm"
    ]


HEADER = (
    "# wirecal-validation 1\n# kind: {kind}\n# robot: Adept Viper s650\n# setup: x\n"
    "# mm_per_count: 0.025488\n"
)


def _config_log(tmp_path, rows, name="c.csv"):
    p = tmp_path / name
    p.write_text(
        HEADER.format(kind="configuration")
        + "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread\n"
        + "".join(f"{k},{c},0,0,0,0,0,0,{n},10,1\n" for k, c, n in rows)
    )
    return p


def test_config_discrepancy_with_a_wrapping_counter(tmp_path):
    rows = [
        (1, 1, 8388600),
        (1, 2, -8388606),
        (1, 3, 8388605),
        (1, 4, 8388607),
        (2, 1, 100),
        (2, 2, 110),
        (2, 3, 90),
        (2, 4, 100),
    ]
    log = read_validation_log(_config_log(tmp_path, rows), "configuration")
    s = config_discrepancy(log, Counter(24))
    np.testing.assert_allclose(s.values, [10 * 0.025488, 20 * 0.025488])


def test_config_discrepancy_wraps_at_the_robots_counter_width(tmp_path):
    """A 16-bit counter wraps at ±32768: read with 16 bits the pose spans 10 counts; a
    24-bit reading would see 7 − (−65 526) = 65 533."""
    rows = [(1, 1, 32760), (1, 2, -32766), (1, 3, 32765), (1, 4, 32767)]
    log = read_validation_log(_config_log(tmp_path, rows), "configuration")
    np.testing.assert_allclose(config_discrepancy(log, Counter(16)).values, [10 * 0.025488])
    np.testing.assert_allclose(config_discrepancy(log, Counter(24)).values, [65533 * 0.025488])


def test_validate_command_needs_the_robot_for_a_configuration_log(tmp_path):
    rows = [(1, 1, 100), (1, 2, 110), (1, 3, 90), (1, 4, 100)]
    path = str(_config_log(tmp_path, rows))
    r = CliRunner().invoke(main, ["validate", "configuration", path, "--json"])
    assert r.exit_code != 0
    assert "give the robot file: wirecal validate ROBOT.toml configuration" in r.output
    r = CliRunner().invoke(
        main, ["validate", "configuration", path, "--robot", str(VIPER / "robot.toml"), "--json"]
    )
    assert r.exit_code == 0, r.output
    assert json.loads(r.output)["before"]["max_mm"] == pytest.approx(20 * 0.025488)


def test_config_log_missing_a_configuration(tmp_path):
    log = read_validation_log(
        _config_log(tmp_path, [(1, 1, 5), (1, 2, 5), (1, 3, 5)]), "configuration"
    )
    with pytest.raises(WirecalError, match=r"poses \[1\] lack one of the four"):
        config_discrepancy(log, Counter(24))


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("time,value\n", "the column line must be"),
        (
            "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread\n1,1,0,0,0,0,0,0,x,10,1\n",
            "c.csv:7: a field is not a number",
        ),
        (
            "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread\n1,9,0,0,0,0,0,0,1,10,1\n",
            "c.csv:7: config 9 is not 1–4",
        ),
        (
            "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread\n1,1,0,0,0,0,0,0,1,10,1\n"
            "1,1,0,0,0,0,0,0,1,10,1\n",
            "c.csv:8: duplicate reading of pose 1, config 1",
        ),
        (
            "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread\n1,1,0,0,0\n",
            "c.csv:7: has 5 fields; expected 11",
        ),
    ],
)
def test_malformed_validation_logs(tmp_path, body, message):
    p = tmp_path / "c.csv"
    p.write_text(HEADER.format(kind="configuration") + body)
    with pytest.raises(WirecalError) as info:
        read_validation_log(p, "configuration")
    assert any(message in x for x in info.value.problems), info.value.problems


def test_foreign_and_wrong_kind_logs(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("# wirecal-log 1\n")
    with pytest.raises(WirecalError, match="not a wirecal validation log"):
        read_validation_log(p, "plane")
    p = _config_log(tmp_path, [(1, 1, 5)])
    with pytest.raises(WirecalError, match="a 'configuration' log where a 'plane' log"):
        read_validation_log(p, "plane")


def test_plane_fit_residuals(tmp_path):
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 400, (60, 2))
    z = 0.01 * xy[:, 0] - 0.002 * xy[:, 1] - 300 + np.r_[np.zeros(59), 0.05]
    p = tmp_path / "p.csv"
    p.write_text(
        HEADER.format(kind="plane")
        + "row,col,x,y,z\n"
        + "".join(
            f"{k},1,{x},{y},{zz}\n" for k, ((x, y), zz) in enumerate(zip(xy, z, strict=True), 1)
        )
    )
    stats, coef = plane_residuals(read_validation_log(p, "plane"))
    np.testing.assert_allclose(coef, [0.01, -0.002, -300], atol=0.01)  # one 0.05 outlier
    assert stats.max == pytest.approx(stats.values[-1])
    assert stats.max > 0.04


@pytest.mark.parametrize("base", [0, -3361716, 8388607])
def test_an_encoder_that_did_not_count_is_refused(tmp_path, base):
    """All counts equal (or within a few counts) over poses across the workspace: not a
    perfect robot but a dead encoder; never "after 0.0000, reduction 100 %"."""
    rows = [(k, c, base + (k + c) % 3) for k in range(1, 51) for c in range(1, 5)]
    path = _config_log(tmp_path, rows)
    with pytest.raises(WirecalError, match=r"c\.csv: .* the encoder did not count"):
        config_discrepancy(read_validation_log(path, "configuration"), Counter(24))
    r = CliRunner().invoke(
        main, ["validate", "configuration", str(path), "--robot", str(VIPER / "robot.toml")]
    )
    assert r.exit_code == 2, r.output
    assert "did not count" in r.output
    assert "reduction" not in r.output


def test_a_small_but_real_travel_is_read(tmp_path):
    """Poses whose lengths differ by 2 mm (over the 1 mm bound) are analysed as usual."""
    step = round(2.0 / 0.025488)
    rows = [(k, c, k * step + c % 2) for k in (1, 2) for c in range(1, 5)]
    s = config_discrepancy(
        read_validation_log(_config_log(tmp_path, rows), "configuration"), Counter(24)
    )
    np.testing.assert_allclose(s.values, [0.025488, 0.025488])
