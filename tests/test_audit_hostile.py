"""Issue 41's fresh hostile-input audit: each case (AU…) beside its valid neighbour.

docs/development.md lists the cases; each test here failed before its fix.
"""

from __future__ import annotations

import re

from click.testing import CliRunner

from wirecal.cli.main import main

from .conftest import DATA, VIPER

ROBOT = VIPER / "robot.toml"
PLAN = VIPER / "paper_plan.toml"
THETA0 = "theta0_deg = [0, -90, 210, -90, 0, -90]"


def _run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def _plan(tmp_path, theta0: str):
    text = PLAN.read_text(encoding="utf-8")
    assert THETA0 in text
    path = tmp_path / "plan.toml"
    path.write_text(text.replace(THETA0, f"theta0_deg = {theta0}"), encoding="utf-8")
    return path


def test_au01_theta0_alone_in_radians_is_refused(tmp_path):
    """θ0 in radians, the points in degrees: psi and gen took it (exit 0), the encoder
    mounted at the zero pose and every point leaking."""
    plan = _plan(tmp_path, "[0, -1.5708, 3.6652, -1.5708, 0, -1.5708]")
    r = _run("psi", ROBOT, plan)
    assert r.exit_code == 2, r.output
    assert re.search(
        r"theta0_deg: θ0 is within ±2π while the points are not: θ0 looks like radians "
        r"\(in degrees \[0, -90, 210, -90, 0, -90\]",
        r.output,
    ), r.output


def test_au01_theta0_near_the_zero_pose_in_degrees_is_read(tmp_path):
    """The neighbour: a θ0 at the zero pose, or a few degrees from it (the points
    nearer it than its values times 57.3), is degrees."""
    for theta0 in ("[0, 0, 0, 0, 0, 0]", "[0, 0, 0, 0, 5, 0]", "[0, 0, 0, 0, 0.1, 0]"):
        r = _run("psi", ROBOT, _plan(tmp_path, theta0))
        assert r.exit_code == 0, r.output
        assert "radians" not in r.output


def test_au04_a_nan_range_margin_is_refused_where_it_is_given():
    """psi --range-margin nan printed a warning and exited 0 with the range check off
    (--strict: exit 1, "a check failed"); now click refuses it, status 2, as --tol nan."""
    for command in (["psi", ROBOT, PLAN], ["gen", ROBOT, PLAN, "-o", "out"]):
        r = _run(*command, "--range-margin", "nan")
        assert r.exit_code == 2, r.output
        assert "'--range-margin': 'nan' is not a finite number" in r.output


def test_au04_a_range_margin_is_read():
    r = _run("psi", ROBOT, PLAN, "--range-margin", "5", "--strict")
    assert r.exit_code == 0, r.output


def test_au05_import_urdf_refuses_a_non_finite_encoder_option_by_its_name(tmp_path):
    """--parallel-tol-deg nan, --range-mm nan were blamed on the robot file being written
    ('urdf.parallel_tol_deg: is nan'); the option is named now."""
    urdf = DATA / "twisted_arm.urdf"
    for option in ("--parallel-tol-deg", "--range-mm", "--mm-per-count"):
        r = _run("import-urdf", urdf, "-o", tmp_path / "r.toml", option, "nan")
        assert r.exit_code == 2, r.output
        assert f"'{option}': 'nan' is not a finite number" in r.output
