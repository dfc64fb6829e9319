"""The RAPID module in the twin: wc_run's log read by the PC, wc_solve against the PC.

The module is run by the RAPID interpreter (num in 32 bits, dnum in 64) on the twin's
World; expectations come from the truth the cell was given and from the Python reference
solver (double precision) on the same log, never from the code under test.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from wirecal.formats.controller_result import parse_result, result_in_log
from wirecal.formats.log import parse_log, read_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.gen.rapid.program import MODULE_FILE, module_text
from wirecal.lang.rapid.module import signal_name
from wirecal.lang.rapid.parser import parse_module
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve
from wirecal.twin.rapid.adapter import ADAPTER
from wirecal.twin.rapid.controller import IrcController
from wirecal.twin.rapid.interp import load_module
from wirecal.twin.rapid.solver_run import ROUTINE, RUN
from wirecal.twin.world import Faults, World

ROOT = Path(__file__).resolve().parent.parent
IRB = ROOT / "examples" / "abb_irb120"
AGREEMENT = 1e-5  # deg/mm: the pinned bound (measured: 3.0e-6 over 12 truths)


@pytest.fixture(scope="module")
def irb():
    robot = load_robot(IRB / "robot.toml")
    return robot, load_plan(IRB / "plan.toml", robot)


@pytest.fixture(scope="module")
def programs(irb):
    return {MODULE_FILE: module_text(*irb)}


def _truth(robot, seed: int, size: float) -> dict[str, float]:
    rng = np.random.default_rng([seed, 77])
    values = rng.uniform(-size, size, len(robot.parameters))
    return dict(zip(robot.parameters, values, strict=True))


@pytest.fixture(scope="module")
def measured(irb, programs, tmp_path_factory):
    """One run of wc_mount and wc_run, the counter starting just below its wrap."""
    robot, plan = irb
    truth = _truth(robot, 5, 0.5)
    folder = tmp_path_factory.mktemp("rapid_run")
    run = ADAPTER.measure(
        robot, plan, truth, folder, programs, seed=1, counter_start=2**31 - 30_000
    )
    return truth, run


def test_run_writes_the_log_the_pc_solves(irb, measured):
    """The file wc_run wrote is a complete log; the PC's estimates find the truth."""
    robot, plan = irb
    truth, run = measured
    assert run.complete, run.stopped
    log = read_log(run.log)
    counts = [r.counts for r in log.readings]
    assert min(counts) < 0 < max(counts)  # the signed 32-bit count wrapped during the run
    m = check_log(log, plan, robot)
    assert not np.isnan(m.distance_mm).any()
    est = solve(robot, plan, m, corrections=False).estimates["stepwise"].as_dict()
    for name, value in truth.items():
        assert est[name] == pytest.approx(value, abs=0.05), name


def test_controller_result_in_the_log_agrees(irb, measured):
    """wc_solve at the end of wc_run wrote the stepwise offsets the PC computes."""
    robot, plan = irb
    _, run = measured
    text = run.log.read_text(encoding="ascii")
    result = result_in_log(text)
    assert result is not None
    on_controller = parse_result(result, "WIRECAL.LOG")
    m = check_log(parse_log(text, "WIRECAL.LOG"), plan, robot)
    ref = solve(robot, plan, m, corrections=False).estimates["stepwise"].as_dict()
    assert set(on_controller) == set(ref)
    for name, value in ref.items():
        assert on_controller[name] == pytest.approx(value, abs=AGREEMENT), name


def test_controller_runs_on_the_log_repeat_wc_run_s_own_solve(irb, programs, measured, tmp_path):
    """wc_solve rerun on the log's readings (``solve --method controller``), the count
    wrapped during the run, gives what wc_solve wrote at the end of wc_run."""
    robot, plan = irb
    _, run = measured
    text = run.log.read_text(encoding="ascii")
    in_log = parse_result(result_in_log(text) or "", "WIRECAL.LOG")
    m = check_log(parse_log(text, "WIRECAL.LOG"), plan, robot)
    runs = ADAPTER.controller_runs(robot, plan, m, tmp_path, programs)
    assert list(runs) == ["stepwise"]
    got = runs["stepwise"]
    assert got.program == "wc_solve"
    assert set(got.offsets) == set(in_log)
    for name, value in in_log.items():
        assert got.offsets[name] == pytest.approx(value, abs=1e-6), name
    assert set(got.operations) == {"add", "mul", "div", "sqrt"}


def test_flexpendant_paste_reads_as_the_file(irb, measured):
    """The FlexPendant's lines, pasted (rows in two pieces, prompts between), give the
    same readings as the file."""
    _, run = measured
    pasted = "\n".join(run.controller.flexpendant)
    from_paste = parse_log(pasted, "pasted")
    from_file = read_log(run.log)
    assert len(from_paste.readings) == len(from_file.readings)
    for a, b in zip(from_paste.readings, from_file.readings, strict=True):
        assert (a.kind, a.step, a.index) == (b.kind, b.step, b.index)
        assert a.counts == b.counts
        assert np.array_equal(a.joints_deg, b.joints_deg)


def test_slip_stops_the_run(irb, programs, tmp_path):
    """A wire slip in step 1 makes step 2's zero reading jump: wc_meas stops the run."""
    robot, plan = irb
    run = ADAPTER.measure(
        robot, plan, {}, tmp_path, programs, faults=Faults(slip_at_move=3, slip_mm=0.5)
    )
    assert not run.complete
    assert "jumped" in run.log.read_text(encoding="ascii")


def test_the_twins_routine_parsed_apart_is_the_joined_module_parsed(irb, programs, tmp_path):
    """wc_solve's run parses the module and the twin's routine apart: the same module, at
    the same line numbers, as the routine written before ENDMODULE and the text parsed; the
    joined module is kept for the next run (the routine is the same for every log)."""
    robot, plan = irb
    text = programs[MODULE_FILE]
    end = text.rindex("ENDMODULE")
    joined = parse_module(text[:end] + ROUTINE + text[end:])
    controller = IrcController(World(robot, {}, plan.theta0_deg, tmp_path), signal_name(robot))
    apart = load_module(text, MODULE_FILE, controller, appended=ROUTINE)
    assert apart.module == joined
    assert apart.module.routines[-1].name == RUN
    assert load_module(text, MODULE_FILE, controller, appended=ROUTINE).module is apart.module


def _agreement(robot, plan, programs, folder: Path, seed: int) -> float:
    truth = _truth(robot, seed, 4.5)
    log = simulate_log(robot, plan, truth, seed=seed)
    m = check_log(parse_log(log, f"seed{seed}.csv"), plan, robot)
    ref = solve(robot, plan, m, corrections=False).estimates["stepwise"].as_dict()
    got = ADAPTER.controller_solve(robot, plan, m.distance_mm, folder, programs)["stepwise"]
    assert set(got) == set(ref)
    return max(abs(got[n] - v) for n, v in ref.items())


@pytest.mark.parametrize("seed", [0, 1])
def test_wc_solve_agrees_with_the_reference(irb, programs, tmp_path, seed):
    assert _agreement(*irb, programs, tmp_path, seed) <= AGREEMENT


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(2, 12))
def test_wc_solve_agrees_more_truths(irb, programs, tmp_path, seed):
    assert _agreement(*irb, programs, tmp_path, seed) <= AGREEMENT


def _solve_cli(log: Path):
    from click.testing import CliRunner

    from wirecal.cli.main import main

    args = ["solve", str(IRB / "robot.toml"), str(IRB / "plan.toml"), str(log)]
    return CliRunner().invoke(main, args)


def test_disk_full_stops_the_run_and_solve_names_the_missing_points(irb, programs, tmp_path):
    run = ADAPTER.measure(*irb, {}, tmp_path, programs, faults=Faults(disk_full_after_lines=20))
    assert not run.complete
    assert "disk is full" in str(run.stopped)
    assert len(run.log.read_text(encoding="ascii").splitlines()) == 20
    result = _solve_cli(run.log)
    assert result.exit_code == 2
    assert "the log is incomplete" in result.output


def test_a_failed_encoder_freezes_the_count_and_solve_refuses(irb, programs, tmp_path):
    """The group input holds its last value: the run completes, the PC's gate refuses."""
    run = ADAPTER.measure(*irb, {}, tmp_path, programs, faults=Faults(encoder_fails_at_read=200))
    assert run.complete
    counts = {r.counts for r in read_log(run.log).readings[-20:]}
    assert len(counts) == 1  # frozen
    result = _solve_cli(run.log)
    assert result.exit_code != 0
    assert "not plausible" in result.output


def test_wc_check_shows_the_live_count(irb, programs, tmp_path):
    """wc_check prints 60 readings, 0.5 s apart, relative to the first (still wire: 0)."""
    from wirecal.lang.rapid.module import signal_name
    from wirecal.twin.rapid.controller import IrcController
    from wirecal.twin.rapid.interp import run_module

    robot, plan = irb
    world = World(robot, {}, plan.theta0_deg, tmp_path, noise_mm=0.0)
    controller = IrcController(world, signal_name(robot))
    outcome = run_module(programs[MODULE_FILE], MODULE_FILE, controller, entry="wc_check")
    assert outcome.status == "completed", outcome.message
    shown = [line for line in controller.flexpendant if line.startswith("counts ")]
    assert len(shown) == 60
    assert world.clock == pytest.approx(30.0)
    assert all(abs(float(line.split()[1])) <= 2 for line in shown)  # ±1-count jitter


def test_moves_slowed_for_the_wire_complete_where_the_run_speed_stops(irb, tmp_path):
    """An encoder whose wire may accelerate at only 10 m/s²: the module at the run's one
    speed is stopped by the twin's wire check; the generator's slower speeddata for the
    moves that need it let the run complete."""
    from dataclasses import replace

    robot, plan = irb
    tight = replace(robot, encoder=replace(robot.encoder, max_wire_accel_mm_s2=10_000.0))
    one_speed = {MODULE_FILE: module_text(robot, plan)}
    stopped = ADAPTER.measure(tight, plan, {}, tmp_path / "one", one_speed, seed=1)
    assert not stopped.complete
    assert "max_wire_accel_mm_s2 10000" in str(stopped.stopped)
    slowed = {MODULE_FILE: module_text(tight, plan)}
    run = ADAPTER.measure(tight, plan, {}, tmp_path / "slowed", slowed, seed=1)
    assert (run.complete, run.stopped) == (True, None)


def test_a_stop_names_its_line_once(irb, tmp_path):
    """A move beyond a joint's range stops the program; the reason reads as the V+ and
    URScript ones do: the program, how it ended, the line, then what stopped it."""
    from wirecal.lang.rapid.module import signal_name
    from wirecal.twin.rapid.controller import IrcController
    from wirecal.twin.rapid.interp import run_module
    from wirecal.twin.world import stop_reason

    robot, plan = irb
    text = "\n".join(
        [
            "MODULE T",
            "PERS tooldata t := [TRUE, [[0, 0, 0], [1, 0, 0, 0]],",
            "  [0.1, [0, 0, 0], [1, 0, 0, 0], 0, 0, 0]];",
            "PROC main()",
            "  MoveAbsJ [[0, 200, 0, 0, 0, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]], v100, fine, t;",
            "ENDPROC",
            "ENDMODULE",
        ]
    )  # t: the robot file's 0.1 kg tool, so the move's load is declared
    controller = IrcController(World(robot, {}, plan.theta0_deg, tmp_path), signal_name(robot))
    outcome = run_module(text, "t.mod", controller)
    assert stop_reason(outcome, None) == (
        "main error at line 5: MoveAbsJ: joint 2 out of range (200 deg)"
    )
    assert controller.stopped == "line 5: MoveAbsJ: joint 2 out of range (200 deg)"


def test_cli_solve_method_controller_runs_wc_solve(tmp_path, monkeypatch):
    """`wirecal simulate --controller` (the module run in the twin), then `wirecal solve
    --method controller`: wc_solve on the log's readings agrees with the Python reference
    and reports the interpreter's operation count."""
    import json

    from click.testing import CliRunner

    from wirecal.cli.main import main

    monkeypatch.chdir(tmp_path)
    files = [str(IRB / "robot.toml"), str(IRB / "plan.toml")]
    r = CliRunner().invoke(main, ["simulate", *files, "-o", "run.csv", "--controller"])
    assert r.exit_code == 0, r.output
    r = CliRunner().invoke(main, ["solve", *files, "run.csv", "--method", "controller", "--json"])
    assert r.exit_code == 0, r.output
    ctl = json.loads(r.output)["methods"]["controller"]
    assert set(ctl) == {"parameters", "parameters_operations", "parameters_max_difference"}
    assert ctl["parameters_max_difference"] <= AGREEMENT
    truth = tomllib.loads((tmp_path / "run.truth.toml").read_text())["errors"]
    assert ctl["parameters"]["th2"] == pytest.approx(truth["th2"], abs=0.05)
    # wc_solve: 9 steps × 5 Gauss–Newton iterations over 45 points, each a forward
    # kinematics of some hundred operations: between 1e5 and 1e6
    assert 100_000 < ctl["parameters_operations"] < 1_000_000
