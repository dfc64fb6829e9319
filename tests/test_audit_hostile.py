"""Issue 41's fresh hostile-input audit: each case (AU…) beside its valid neighbour.

docs/development.md lists the cases; each test here failed before its fix.
"""

from __future__ import annotations

import re

from click.testing import CliRunner

from wirecal.cli.main import main

from .conftest import VIPER

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
