"""URScript moves within the wire's limits: each movej its own v and a where the encoder's
wire speed or acceleration asks for less than the run's, and a twin that enforces them.

Mutations these tests kill: the per-move cap removed (every movej at the run's v: the
twin, enforcing the limits, stops the validation run); a not capped at v / 0.5 s; the
twin's wire check ignoring movej's own ramp v/a.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from wirecal.app.languages import registered
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.gen.request import GenRequest
from wirecal.solver.validation.design import distance_plan

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
RUN_V_RAD_S = 0.2 * math.pi
"""The run's v: 20 % (the paper's speed) of the UR joints' 180 deg/s = π rad/s."""
RAMP_S = 0.5
"""The ramp the wire's acceleration is bounded with (run_parameters.MOVE_OVERHEAD_S)."""
MOVEJ = re.compile(r"movej\((\[[^]]*\]), a=([0-9.]+), v=([0-9.]+)\)")


def _validation(name: str):
    """The example's robot, its demo's distance-validation plan and its programs."""
    robot = load_robot(EXAMPLES / name / "robot.toml")
    plan = distance_plan(robot, load_plan(EXAMPLES / name / "plan.toml", robot), seed=1)
    programs = registered(robot).generator.programs(robot, plan, GenRequest(solver=False))
    return robot, plan, programs


@pytest.fixture(scope="module", params=["ur5e", "ur5"])
def validation(request):
    return _validation(request.param)


def _moves(text: str) -> list[tuple[str, float, float]]:
    """Every movej of a program: (target, a, v)."""
    return [(q, float(a), float(v)) for q, a, v in MOVEJ.findall(text)]


def test_moves_the_wire_limits_slow_get_their_own_v_and_a(validation):
    """Some validation moves (e-Series and CB3 legs alike) run slower than the run's v; no
    move faster; every a is v / 0.5 s (below movej's default 1.4 rad/s² at these v),
    rounded down to 6 decimals: the ramp v/a never shorter than 0.5 s."""
    _, _, programs = validation
    moves = _moves(programs["wc_run.script"])
    assert len(moves) > 60
    assert all(v <= RUN_V_RAD_S for _, _, v in moves)
    slower = [v for _, _, v in moves if v < RUN_V_RAD_S - 1e-6]
    assert len(slower) >= 3, slower
    assert all(0 <= v / RAMP_S - a < 1e-6 for _, a, v in moves)


def test_the_twin_enforces_the_limits_and_the_capped_programs_complete(validation, tmp_path):
    robot, plan, programs = validation
    run = registered(robot).measure(robot, plan, {}, tmp_path, programs, seed=3)
    assert run.world.wire_limits
    assert run.complete, run.stopped


def test_a_movej_whose_a_shortens_the_ramp_stops_naming_the_acceleration(tmp_path):
    """Every movej's a twenty times larger (its ramp v/a a twentieth): the twin checks the
    wire with movej's own ramp and stops at a move, before it moves."""
    robot, plan, programs = _validation("ur5e")
    edited = MOVEJ.sub(
        lambda m: f"movej({m[1]}, a={20 * float(m[2]):g}, v={m[3]})", programs["wc_run.script"]
    )
    run = registered(robot).measure(
        robot, plan, {}, tmp_path, {**programs, "wc_run.script": edited}, seed=3
    )
    out = run.run or run.mount
    assert not run.complete
    assert out.status == "error", out
    assert "beyond the encoder's max_wire_accel_mm_s2 49000" in out.message
    stopped = re.search(r"movej: move (\d+) to \(", out.message)
    assert stopped, out.message
    assert run.world.moves == int(stopped[1]) - 1
