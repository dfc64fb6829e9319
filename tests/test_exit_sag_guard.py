"""A guide pulley or an eyelet's rounded edge with the gravity sag: never a NaN with exit 0.

The exit is modelled where the unsagged arm stands at θ0 (as the twin mounts it), and the
wire bends over a circle touching it there: the sagged θ0 point (0.04 mm from the exit on
the Viper's paper plan, 172 deg off a vertical axis) lies inside that circle, where no wire
reaches. The error budget's sag term then has no value; solve refuses (exit status 2) and
names the key, instead of printing ``nan`` budgets and an "unbounded" tool error with exit
status 0. The twin refuses a reading it has no wire for.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.solver.budget import Budget
from wirecal.solver.errors import WirecalError
from wirecal.solver.simulate import sag_lengths_mm
from wirecal.twin.world import World

from .conftest import VIPER

PULLEY = 'exit = "pulley"\naxis = [0.0, 0.0, 1.0]\npulley_radius_mm = 10.0'
EYELET = 'exit = "eyelet"\naxis = [0.0, 0.0, 1.0]\nmax_exit_deg = 90.0\nexit_edge_radius_mm = 0.2'


def _robot_file(tmp_path: Path, exit_lines: str, sag: float | None = None) -> Path:
    """The Viper's robot file with another exit (and a declared sag), the paper plan beside."""
    text = (VIPER / "robot.toml").read_text(encoding="utf-8")
    assert 'exit = "point"' in text
    assert "gravity_sag_deg_per_m =" not in text
    text = text.replace('exit = "point"', exit_lines)
    if sag is not None:
        text = text.replace("[calibration]", f"[calibration]\ngravity_sag_deg_per_m = {sag}")
    path = tmp_path / "robot.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _cli(*args: str) -> tuple[int, str]:
    result = CliRunner().invoke(main, list(args))
    return result.exit_code, result.output


def test_solve_refuses_a_pulley_under_the_sag_and_gives_finite_figures_without(tmp_path):
    """The reported reproduction, through the CLI: before, exit 0 with ``nan`` budgets."""
    plan = str(VIPER / "paper_plan.toml")
    robot = _robot_file(tmp_path, PULLEY)
    log = str(tmp_path / "run.log")
    assert _cli("simulate", str(robot), plan, "-o", log)[0] == 0
    code, out = _cli("solve", str(robot), plan, log)
    assert code == 2
    assert "gravity_sag_deg_per_m = 0.01" in out
    assert "the tool point at θ0 0.0405 mm from the exit, 172 deg off its axis" in out
    assert "swivel guide pulley, radius 10 mm" in out
    assert "nan" not in out.lower()
    robot = _robot_file(tmp_path, PULLEY, sag=0.0)
    code, out = _cli("solve", str(robot), plan, log)
    assert code == 0, out
    assert "nan" not in out.lower()
    assert "unbounded" not in out
    for label in ("gravity sag", "total", "95 % bound"):
        row = re.search(rf"^{label} +(\S+) +(\S+)", out, re.MULTILINE)
        assert row is not None, label
        figures = [float(x) for x in row.groups()]
        assert all(math.isfinite(x) and x >= 0 for x in figures), (label, figures)
    sag = re.search(r"^gravity sag +(\S+) +(\S+)", out, re.MULTILINE)
    assert sag is not None
    assert sag.groups() == ("0.0000", "0.0000")  # none declared


def test_the_sag_term_names_an_eyelet_edge(tmp_path):
    """A 0.2 mm eyelet edge: the sagged θ0 point is inside its circle too (0.0016 mm² of
    ‖v‖² against 2ρs = 0.0022 mm²)."""
    robot = load_robot(_robot_file(tmp_path, EYELET))
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    with pytest.raises(WirecalError, match=r"eyelet, axis \(0, 0, 1\).*edge radius 0\.2 mm"):
        sag_lengths_mm(robot, plan)
    robot = load_robot(_robot_file(tmp_path, EYELET, sag=0.0))
    assert not np.any(sag_lengths_mm(robot, plan))


@pytest.mark.parametrize("figure", ["term", "total", "worst", "bound", "compensated"])
def test_a_budget_with_a_figure_not_a_number_is_refused(figure):
    nan = float("nan")
    values = {"term": 0.1, "total": 0.2, "worst": 0.3, "bound": 0.4, "compensated": 0.5}
    values[figure] = nan if figure != "bound" else math.inf
    with pytest.raises(WirecalError, match="the error budget has no value"):
        Budget(
            {"noise": values["term"]},
            values["total"],
            values["worst"],
            (),
            values["bound"],
            values["compensated"],
        )
    values[figure] = 1.0
    Budget({"noise": values["term"]}, values["total"], values["worst"], (), values["bound"])


def test_the_twin_refuses_a_reading_with_no_wire(tmp_path):
    """The arm a hair off θ0 sideways: inside the pulley's circle, a clear error, not the
    ValueError of a NaN count."""
    robot = load_robot(_robot_file(tmp_path, PULLEY))
    theta0 = load_plan(VIPER / "paper_plan.toml", robot).theta0_deg
    world = World(robot, {}, np.asarray(theta0), tmp_path / "disk")
    assert world.read_count() == 0  # at the exit: no wire out
    world.actual = np.asarray(theta0) + np.array([0.01, 0, 0, 0, 0, 0])
    with pytest.raises(WirecalError, match=r"the twin: the arm at joints .* no wire reaches"):
        world.read_count()
