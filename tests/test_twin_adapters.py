"""The twin's language adapters over one World (issue 23 item 1)."""

from __future__ import annotations

import numpy as np
import pytest

from wirecal.formats.log import load_measurements, parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.gen.rapid.program import MODULE_FILE
from wirecal.gen.rapid.program import module_text as rapid_module
from wirecal.gen.urscript.program import scripts
from wirecal.gen.vplus.program import MODULE_NAME
from wirecal.lang.urscript.parser import BUILTINS, parse_program
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve
from wirecal.twin.adapters import adapter
from wirecal.twin.urscript.controller import URController
from wirecal.twin.urscript.interp import Interpreter
from wirecal.twin.world import Faults, World

from .conftest import TABLE5


@pytest.fixture(scope="module")
def ur5():
    return load_robot("examples/ur5e/robot.toml")


@pytest.fixture(scope="module")
def ur5_plan(ur5):
    return load_plan("examples/ur5e/plan.toml", ur5)


@pytest.fixture(scope="module")
def irb():
    return load_robot("examples/abb_irb120/robot.toml")


@pytest.fixture(scope="module")
def irb_plan(irb):
    return load_plan("examples/abb_irb120/plan.toml", irb)


def test_each_example_finds_its_adapter_by_its_language(viper, ur5, irb):
    for robot in (viper, ur5, irb):
        language = robot.controller.language
        assert adapter(language).key == language


def test_an_unknown_language_has_no_adapter():
    with pytest.raises(WirecalError, match="'cobol'"):
        adapter("cobol")


def ur_controller(robot, tmp_path, **world) -> URController:
    theta0 = np.array([0.0, -90.0, 90.0, -90.0, -90.0, 0.0])
    return URController(World(robot, {}, theta0, tmp_path, noise_mm=0.0, **world))


def test_the_ur_controller_offers_urscript_functions_only(ur5, tmp_path):
    """The interpreter calls whatever public method the controller has by the script's
    name: the UR cell inherited V+'s (move, prompt, wire_counts…); the controller's public
    methods are now URScript functions of the manual's table, close_all aside."""
    ctl = ur_controller(ur5, tmp_path)
    public = {n for n in dir(ctl) if not n.startswith("_") and callable(getattr(ctl, n))}
    assert public - set(BUILTINS) == {"close_all"}
    assert {"movej", "encoder_get_tick_count", "socket_send_line", "sync"} <= public


def test_one_faults_type_serves_urscript_too(ur5, tmp_path):
    """The encoder failure V+ reports as -1013 stops a URScript program at its read."""
    ctl = ur_controller(ur5, tmp_path, faults=Faults(encoder_fails_at_read=2))
    ctl.encoder_enable_pulse_decode(0, 1, 8, 9)
    text = "def t():\n  a = encoder_get_tick_count(0)\n  b = encoder_get_tick_count(0)\nend\n"
    out = Interpreter(parse_program(text, "t.script"), ctl).execute()
    assert (out.status, out.line) == ("error", 3)
    assert "the encoder failed at read 2" in out.message


def test_ur_measure_without_a_receiver_is_incomplete(ur5, ur5_plan, tmp_path):
    run = adapter(ur5.controller.language).measure(
        ur5, ur5_plan, {}, tmp_path, scripts(ur5, ur5_plan), seed=1
    )
    assert not run.complete
    assert run.stopped
    assert run.world.moves == 0  # wc_run stops before its first move: no PC
    assert not run.log.exists()


@pytest.mark.slow
def test_vplus_adapter_measures_the_whole_plan(viper, paper_plan, viper_module, tmp_path):
    """V+'s adapter: the module's run logs the whole plan in the file wc.run opened."""
    programs = {MODULE_NAME: viper_module}
    run = adapter(viper.controller.language).measure(
        viper, paper_plan, TABLE5, tmp_path / "disk", programs, seed=2
    )
    assert (run.complete, run.stopped) == (True, None)
    assert run.log == tmp_path / "disk" / "WCLOG.CSV"
    assert load_measurements(run.log, paper_plan, viper).missing == ()


def lengths_case(robot, plan, seed):
    """A simulated log's lengths (noise-free) and the PC reference's estimates on it."""
    rng = np.random.default_rng([seed, 78])
    truth = dict(zip(robot.parameters, rng.uniform(-2.0, 2.0, len(robot.parameters)), strict=True))
    log = simulate_log(robot, plan, truth, seed=seed, noise_mm=0.0)
    m = check_log(parse_log(log, f"seed{seed}.csv"), plan, robot)
    return m.distance_mm, solve(robot, plan, m, corrections=False).estimates


def worst_difference(estimates, reference) -> float:
    return max(
        abs(offsets[n] - v)
        for method, offsets in estimates.items()
        for n, v in reference[method].as_dict().items()
    )


@pytest.mark.slow
def test_controller_solvers_on_lengths_agree_with_the_reference(
    viper, paper_plan, viper_module, ur5, ur5_plan, irb, irb_plan, tmp_path
):
    """Each adapter's controller_solve on the plan points' wire lengths (the zero readings
    on a counter about to wrap) agrees with the PC reference on the same lengths."""
    for robot, plan, programs, methods in (
        (viper, paper_plan, {MODULE_NAME: viper_module}, {"stepwise", "joint"}),
        (ur5, ur5_plan, scripts(ur5, ur5_plan), {"stepwise"}),
        (irb, irb_plan, {MODULE_FILE: rapid_module(irb, irb_plan)}, {"stepwise"}),
    ):
        lengths, reference = lengths_case(robot, plan, seed=1)
        language = robot.controller.language
        estimates = adapter(language).controller_solve(
            robot, plan, lengths, tmp_path / language, programs
        )
        assert set(estimates) == methods
        assert worst_difference(estimates, reference) < 1e-5


def test_programs_missing_or_extra_are_named(
    viper, paper_plan, ur5, ur5_plan, irb, irb_plan, tmp_path
):
    with pytest.raises(WirecalError, match="expected the one module file"):
        adapter(viper.controller.language).measure(
            viper, paper_plan, {}, tmp_path, {"A.V2": "", "B.V2": ""}
        )
    with pytest.raises(WirecalError, match=r"wc_mount\.script is missing"):
        adapter(ur5.controller.language).measure(ur5, ur5_plan, {}, tmp_path, {"wc_run.script": ""})
    with pytest.raises(WirecalError, match=r"WIRECAL\.mod is missing"):
        adapter(irb.controller.language).measure(irb, irb_plan, {}, tmp_path, {"X.mod": ""})


def test_rapid_adapter_enforces_the_wire_speed(irb, irb_plan, tmp_path):
    """The RAPID controller calls the World's wire check: a wire limit below the plan's
    moves stops wc_run at its first move, naming the limit."""
    from dataclasses import replace

    slow_wire = replace(irb, encoder=replace(irb.encoder, max_wire_speed_mm_s=1.0))
    programs = {MODULE_FILE: rapid_module(irb, irb_plan)}
    run = adapter(irb.controller.language).measure(slow_wire, irb_plan, {}, tmp_path, programs)
    assert not run.complete
    assert "max_wire_speed_mm_s 1" in str(run.stopped)
