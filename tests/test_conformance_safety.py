"""The conformance suite's safety section, run for every registered language and a toy one.

Every language's generation runs one pre-flight no generator can skip
(:meth:`wirecal.gen.backends.Generator.programs`), and every language's twin one move
protocol (:meth:`wirecal.twin.world.World.move`). What each must show, from its first
example: ``gen`` refuses the example's colliding plan (``colliding_plan.toml`` beside its
plan, which names the pair in a ``# collides:`` line), and the same programs rendered
with the pre-flight bypassed stop in the twin at that move, naming the pair; a point
beyond the controller's limit stops the run; a point within the margin of a limit is
refused; a wire beyond the encoder's range is refused, and stops the run when bypassed; a
move beyond the wire's speed or acceleration limit stops the run, naming the limit;
the patch companion, where there is one, round-trips. The toy language
(:mod:`tests.toy_language`), registered only here, gets all of it from the shared code.

Mutations these tests kill (docs/development.md lists them): the pre-flight's
``check_cell`` or ``check_limits`` call removed; ``World.move``'s collision, limit or wire
check removed; a controller's mapping of a refusal dropped; a language's runs with the
wire's limits off.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from wirecal.app.languages import registered
from wirecal.formats.patch_companion import read_companion
from wirecal.formats.plan_file import load_plan
from wirecal.gen.backends import Generator
from wirecal.gen.request import GenRequest
from wirecal.lang.registry import languages
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import RANGE_EXCEEDED
from wirecal.twin.machine import Outcome
from wirecal.twin.run_moves import move_of_step
from wirecal.twin.world import Faults

from .conftest import ROOT
from .test_conformance import GOLDEN, examples
from .toy_language import KEY as TOY
from .toy_language import ToyGenerator, registered_toy

KEYS = [*sorted(languages()), TOY]
COLLIDING = "colliding_plan.toml"
SHORT_RANGE_MM = 100.0
"""An encoder range every example plan exceeds (its longest wires are 300-600 mm)."""
SLOW_WIRE = 1.0
"""A wire speed (mm/s) and acceleration (mm/s²) every example plan's first point exceeds."""


@dataclass(frozen=True)
class Case:
    """A language's example for the safety tests: its robot, plan and colliding plan."""

    key: str
    robot: Robot
    plan: Plan
    colliding: Plan
    pair: str  # the colliding pair, as the colliding plan's "# collides:" line names it


def _pair(path: Path) -> str:
    lines = path.read_text(encoding="utf-8").splitlines()
    return next(x.removeprefix("# collides: ") for x in lines if x.startswith("# collides: "))


@pytest.fixture(scope="module", autouse=True)
def _toy():
    with registered_toy():
        yield


@pytest.fixture(scope="module", params=KEYS)
def case(request) -> Case:
    """The first example of each language; the toy borrows V+'s with its own language."""
    key = request.param
    ex = examples("vplus" if key == TOY else key)[0]
    robot = ex.robot
    if key == TOY:
        robot = replace(robot, controller=replace(robot.controller, language=TOY, software=None))
    path = ROOT / "examples" / ex.name / COLLIDING
    return Case(key, robot, ex.plan, load_plan(path, robot), _pair(path))


def _outcome(run) -> Outcome:
    """The program that ended the run: the measurement program, else the mounting one."""
    return run.run or run.mount


def _one_step(plan: Plan, *points: np.ndarray) -> Plan:
    """The colliding plan's θ0 with one step through ``points`` (deg)."""
    step = replace(plan.steps[0], points_deg=np.array(points, float))
    return replace(plan, steps=(step,))


def test_every_example_carries_a_colliding_plan_naming_the_pair():
    for golden in sorted(p for p in GOLDEN.iterdir() if p.is_dir()):
        path = ROOT / "examples" / golden.name / COLLIDING
        assert path.is_file(), f"{golden.name}: no {COLLIDING} beside its plan"
        assert _pair(path), path


def test_gen_refuses_the_colliding_plan_naming_the_pair(case):
    gen = registered(case.robot).generator
    with pytest.raises(WirecalError) as info:
        gen.programs(case.robot, case.colliding, GenRequest())
    found = [p for p in info.value.problems if "step 1 (th2) point 2: the arm collides" in p]
    assert found, info.value.problems
    assert case.pair in found[0]


def test_bypassed_preflight_programs_stop_in_the_twin_naming_the_pair(case, tmp_path):
    reg = registered(case.robot)
    programs = reg.generator.render(case.robot, case.colliding, GenRequest())
    run = reg.measure(case.robot, case.colliding, {}, tmp_path, programs, seed=3)
    out = _outcome(run)
    assert not run.complete
    assert out.status == "error", out
    assert f"move {move_of_step(case.colliding, 1, 2)} to (" in out.message
    assert case.pair in out.message


def test_a_point_beyond_the_controllers_limit_stops(case, tmp_path):
    """Joint 6 turned 20 and 30 deg from θ0; the controller's own limit (a fault: tighter
    than the robot file's) 10 deg from θ0: the first of the points stops the run."""
    theta0 = case.colliding.theta0_deg
    turned = [theta0 + np.r_[0, 0, 0, 0, 0, d] for d in (20.0, 30.0)]
    plan = _one_step(case.colliding, *turned)
    reg = registered(case.robot)
    programs = reg.generator.programs(case.robot, plan, GenRequest())
    limit = (*case.robot.joint_max_deg[:5], theta0[5] + 10.0)
    faults = Faults(joint_max_deg=limit)
    run = reg.measure(case.robot, plan, {}, tmp_path, programs, seed=3, faults=faults)
    out = _outcome(run)
    assert not run.complete
    assert out.status == "error", out
    assert "joint 6" in out.message.lower()
    assert run.world.moves == move_of_step(plan, 1, 1) - 1  # stopped before that move


def test_a_point_within_the_margin_is_refused(case):
    theta0 = case.colliding.theta0_deg
    near = theta0.copy()
    near[0] = case.robot.joint_max_deg[0] - 0.5  # inside the limit, within the 1 deg margin
    plan = _one_step(case.colliding, theta0 + np.r_[0, 0, 0, 0, 0, 20.0], near)
    with pytest.raises(WirecalError) as info:
        registered(case.robot).generator.programs(case.robot, plan, GenRequest())
    expected = "step 1 (th2) point 2: joint 1 = "
    found = [p for p in info.value.problems if expected in p]
    assert found, info.value.problems
    assert "is within 1 deg of its limits" in found[0]


def test_the_wire_beyond_the_encoders_range_is_refused_and_stops_the_run(case, tmp_path):
    short = replace(case.robot, encoder=replace(case.robot.encoder, range_mm=SHORT_RANGE_MM))
    reg = registered(short)
    with pytest.raises(WirecalError) as info:
        reg.generator.programs(short, case.plan, GenRequest())
    assert any(f"range_mm {SHORT_RANGE_MM:g}" in p for p in info.value.problems), info.value
    programs = reg.generator.render(short, case.plan, GenRequest())
    run = reg.measure(short, case.plan, {}, tmp_path, programs, seed=3)
    out = _outcome(run)
    assert not run.complete
    assert RANGE_EXCEEDED in out.message
    assert f"beyond the encoder's range_mm {SHORT_RANGE_MM:g}" in out.message


@pytest.mark.parametrize("limit", ["max_wire_speed_mm_s", "max_wire_accel_mm_s2"])
def test_a_move_beyond_the_wires_limits_stops_naming_the_limit(case, limit, tmp_path):
    """The programs generated for the robot file's wire run on an encoder whose wire may
    run at only 1 mm/s (or accelerate at 1 mm/s²): the first move to a point stops the
    run before it moves, naming the limit."""
    reg = registered(case.robot)
    programs = reg.generator.programs(case.robot, case.plan, GenRequest())
    slow = replace(case.robot, encoder=replace(case.robot.encoder, **{limit: SLOW_WIRE}))
    run = reg.measure(slow, case.plan, {}, tmp_path, programs, seed=3)
    out = _outcome(run)
    assert not run.complete
    assert out.status == "error", out
    assert f"beyond the encoder's {limit} {SLOW_WIRE:g}" in out.message
    assert run.world.moves == move_of_step(case.plan, 1, 1) - 1


def _numbers(value) -> list[float]:
    """Every number in a parsed TOML value."""
    if isinstance(value, dict):
        return [x for v in value.values() for x in _numbers(v)]
    if isinstance(value, list):
        return [x for v in value for x in _numbers(v)]
    return [float(value)] if isinstance(value, int | float) and not isinstance(value, bool) else []


def test_the_patch_companion_round_trips(case, tmp_path):
    """Zero offsets write only zeros; one offset (0.1 deg on the step's joint) a non-zero
    value; the text parses as TOML, and its declared per-joint vectors read back."""
    lang = registered(case.robot).language
    if lang.patch_companion is None:
        assert lang.patch_section(case.robot, {}) is None
        return
    zero = lang.patch_section(case.robot, {})
    moved = lang.patch_section(case.robot, {"th2": 0.1})
    assert zero is not None
    assert moved is not None
    assert not any(_numbers(tomllib.loads(zero)))
    assert any(_numbers(tomllib.loads(moved)))
    assert lang.patch_section(case.robot, {"th2": 0.1}) == moved
    if lang.companion_vectors is not None:
        path = tmp_path / f"patch{lang.patch_companion}"
        path.write_text(moved, encoding="utf-8")
        back = read_companion(path, lang, case.robot.n_joints)
        _, keys = lang.companion_vectors
        assert tuple(back) == keys
        assert np.any([np.any(v) for v in back.values()])
        assert all(v.shape == (case.robot.n_joints,) for v in back.values())


def test_a_generator_cannot_replace_programs_and_skip_a_duty():
    assert "programs" not in vars(ToyGenerator)
    with pytest.raises(TypeError, match="renders only"):

        class Skipping(Generator):
            def programs(self, robot, plan, request):  # type: ignore[misc]
                return {}
