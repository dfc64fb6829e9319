"""The UR5e's generated URScript programs in the twin: the run, the wraps, the fault matrix.

Every run goes over a real loopback socket to :func:`wirecal.app.receive.receive` (the
function behind ``wirecal receive``), which keeps the rows of an incomplete run in its
journal and names the missing points.
"""

from __future__ import annotations

import numpy as np
import pytest

from wirecal.app.receive import summary
from wirecal.formats.log import load_measurements, parse_log, read_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors
from wirecal.gen.urscript.program import scripts
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve
from wirecal.twin.machine import Outcome
from wirecal.twin.run_moves import move_of_step
from wirecal.twin.urscript.runs import _why_stopped
from wirecal.twin.world import Faults, World

from .twin_runs import measure_ur_in_twin

HEADER_LINES = 6  # the wirecal-log header and the column line


@pytest.fixture(scope="module")
def ur5():
    return load_robot("examples/ur5e/robot.toml")


@pytest.fixture(scope="module")
def ur5_plan(ur5):
    return load_plan("examples/ur5e/plan.toml", ur5)


@pytest.fixture(scope="module")
def texts(ur5, ur5_plan):
    return scripts(ur5, ur5_plan)


@pytest.fixture(scope="module")
def truth(ur5):
    return random_errors(ur5, 1.0, np.random.default_rng([5, 1]))


def run(ur5, ur5_plan, texts, truth, tmp_path, **kw):
    return measure_ur_in_twin(ur5, ur5_plan, truth, tmp_path, texts=texts, seed=5, **kw)


@pytest.fixture(scope="module")
def completed(ur5, ur5_plan, texts, truth, tmp_path_factory):
    """The run without faults and its folder, run once: the tests taking it only read it."""
    folder = tmp_path_factory.mktemp("completed")
    return folder, run(ur5, ur5_plan, texts, truth, folder)


def test_run_completes_and_the_log_identifies_the_truth(ur5, ur5_plan, truth, completed):
    folder, r = completed
    assert r.programs.mount.status == "completed"
    assert r.programs.run.status == "completed"
    assert r.received.complete
    assert r.log == folder / "run.csv"
    assert not r.received.journal.exists()
    m = load_measurements(r.log, ur5_plan, ur5)
    assert m.complete
    est = solve(ur5, ur5_plan, m).estimates["joint"].as_dict()
    assert max(abs(v - truth.get(k, 0.0)) for k, v in est.items()) < 0.05  # deg, mm
    # the twin's clock: 62 moves at 36 deg/s plus the settle and the readings (the UR5e's
    # plan, designed inside its cell: 384 s, bench/bench_ur5e.py)
    assert 300 < r.programs.world.clock < 600


def test_every_line_sent_is_mirrored_in_the_log_tab(ur5, ur5_plan, completed):
    r = completed[1]
    sent = r.received.text.splitlines()
    tab = r.programs.run.console
    mirrored = [line for line in tab if line in set(sent)]
    assert mirrored == sent
    m = check_log(parse_log("\n".join(mirrored), "<log tab>"), ur5_plan, ur5)
    assert m.complete


@pytest.mark.slow
@pytest.mark.parametrize(
    "start",
    [
        1000.0,  # neither count wraps
        float(65536 * 7 - 20000),  # the filtered count (2^16) wraps during the run
        float(2**31 - 20000),  # the raw int32 count wraps during the run
    ],
)
def test_wrapping_counters_change_nothing(ur5, ur5_plan, texts, truth, tmp_path, start):
    r = run(ur5, ur5_plan, texts, truth, tmp_path, counter_start=start)
    assert r.programs.run.status == "completed"
    m = load_measurements(r.log, ur5_plan, ur5)
    reference = run(ur5, ur5_plan, texts, truth, tmp_path / "ref", counter_start=123.0)
    m0 = load_measurements(reference.log, ur5_plan, ur5)
    # the same readings: only the doubles' rounding of the large counts differs
    np.testing.assert_allclose(m.distance_mm, m0.distance_mm, rtol=0, atol=1e-6)


def test_fault_socket_refused(ur5, ur5_plan, texts, truth, tmp_path):
    r = run(ur5, ur5_plan, texts, truth, tmp_path, pc_listening=False)
    out = r.programs.run
    assert out.status == "stopped"
    assert "*** cannot connect to wirecal receive at 192.168.1.10:50000" in out.console
    assert out.message.startswith("Cannot connect to the PC at 192.168.1.10:50000")
    assert r.programs.world.moves == 0  # stopped before the first move
    assert not r.received.log.exists()


def test_fault_socket_dropped_mid_run(ur5, ur5_plan, texts, truth, tmp_path):
    # the run token's line, then 30 log lines reach the PC
    r = run(ur5, ur5_plan, texts, truth, tmp_path, faults=Faults(socket_drops_after_lines=31))
    out = r.programs.run
    assert out.status == "completed"  # the robot finishes; every row is in the log tab
    lost = "# *** not sent to the PC (connection lost): copy the lines from this log"
    # 6 header lines, 61 rows, wc_solve's 10 step lines and 4 + 10 result lines, "# end"
    assert out.console.count(lost) == 6 + 61 + 10 + 14 + 1 - 30
    assert not r.received.complete
    assert r.received.stopped == "the sender closed the connection before the end marker"
    assert not r.received.log.exists()
    m = load_measurements(r.received.journal, ur5_plan, ur5)
    # 30 lines: 6 header lines, steps 1-5 (a zero row and 2, 4, 2, 5, 2 points: 20 rows),
    # then step 6's zero row and its first 3 of 7 points
    assert m.missing_text() == "step 6 points 4–7; steps 7–10 (all points)"
    assert summary(r.received, ur5, ur5_plan)[-1] == (
        "missing points: step 6 points 4–7; steps 7–10 (all points)"
    )


@pytest.mark.slow
def test_fault_encoder_not_enabled_counts_never_change(ur5, ur5_plan, texts, truth, tmp_path):
    # wired to inputs 10 and 11, the program decodes 8 and 9: the count never changes
    r = run(ur5, ur5_plan, texts, truth, tmp_path, pulse_inputs=(10, 11))
    assert r.programs.run.status == "completed"  # the program does not notice
    log = read_log(r.log)
    assert {row.counts for row in log.readings} == {0.0}
    result = solve(ur5, ur5_plan, check_log(log, ur5_plan, ur5))
    from wirecal.app.gate import gate

    with pytest.raises(WirecalError) as info:
        gate(result, result.recommended)
    assert "every count is the same: the encoder did not count" in info.value.problems[0]
    assert "check it with wc_check before measuring again" in info.value.problems[0]


def test_fault_point_beyond_a_joint_limit(ur5, ur5_plan, texts, truth, tmp_path):
    limits = (355.0, 355.0, 355.0, 0.0, 355.0, 355.0)  # the controller's own j4 limit
    r = run(ur5, ur5_plan, texts, truth, tmp_path, faults=Faults(joint_max_deg=limits))
    out = r.programs.run
    assert out.status == "error"
    assert out.message == "movej: joint 4 target 0.870 deg is beyond its limit [-355, 0] deg"
    m = load_measurements(r.received.journal, ur5_plan, ur5)
    assert m.missing_text() == "steps 4–10 (all points)"  # j4 0.87 at step 4's first point
    assert summary(r.received, ur5, ur5_plan)[-1].endswith("steps 4–10 (all points)")


def test_fault_wire_slip(ur5, ur5_plan, texts, truth, tmp_path):
    slip = Faults(slip_at_move=move_of_step(ur5_plan, 4, 2), slip_mm=0.5)
    r = run(ur5, ur5_plan, texts, truth, tmp_path, faults=slip)
    out = r.programs.run
    assert out.status == "stopped"  # the operator stops at the warning
    assert (
        "# *** the zero reading at theta0 jumped by more than 0.1 mm since the last: slip in step 4"
        in out.console
    )
    assert "the wire slipped or the encoder moved during step 4" in out.message
    with pytest.raises(WirecalError) as info:
        load_measurements(r.received.journal, ur5_plan, ur5)
    assert "remount at θ0 and repeat from step 4" in info.value.problems[0]


@pytest.mark.slow
def test_the_log_carries_the_controller_solvers_result(ur5, ur5_plan, completed, tmp_path):
    """wc_solve runs at the end of wc_run; its result arrives in the log as comment lines
    and agrees with the PC's stepwise estimate; solve --method controller reruns it."""
    from wirecal.app.compare import compare_controller
    from wirecal.formats.controller_result import parse_result, result_in_log

    r = completed[1]
    text = r.log.read_text(encoding="ascii")
    assert text.splitlines()[-1] == "# end"
    result = parse_result(result_in_log(text), "log")
    m = load_measurements(r.log, ur5_plan, ur5)
    ref = solve(ur5, ur5_plan, m).estimates["stepwise"].as_dict()
    assert list(result) == list(ref)
    assert max(abs(result[n] - v) for n, v in ref.items()) <= 1e-5
    assert "# solver: step 10 of 10: d4 identified" in r.programs.run.console  # the last
    ctl = compare_controller(solve(ur5, ur5_plan, m), tmp_path / "ctl")
    # the same program on the log's readings: the count split between base and offset
    # differs (floor of the logged count), hence 32-bit roundings in the last decimal
    assert ctl.stepwise.offsets == pytest.approx(result, abs=5e-6)
    assert ctl.polished is None


@pytest.mark.parametrize(("inputs", "moves"), [((8, 9), True), ((10, 11), False)])
def test_wc_check_shows_the_pulled_wire_only_when_decoded(
    ur5, ur5_plan, texts, tmp_path, inputs, moves
):
    from wirecal.lang.urscript.parser import parse_program
    from wirecal.twin.urscript.controller import URController
    from wirecal.twin.urscript.interp import Interpreter

    world = World(
        ur5, {}, ur5_plan.theta0_deg, tmp_path, noise_mm=0.0,
        pull_mm=lambda t: min(100.0, 10.0 * t),  # 100 mm out over 10 s, then held
    )  # fmt: skip
    cell = URController(world, pulse_inputs=inputs)
    out = Interpreter(parse_program(texts["wc_check.script"], "wc_check.script"), cell).execute()
    assert out.status == "completed"
    last = out.console[-1]  # e.g. "counts 3923   mm 99.9880"
    mm = float(last.split("mm")[-1])
    if moves:
        assert mm == pytest.approx(100.0, abs=0.06)  # ±1 count of jitter, the quantisation
    else:
        assert {line.split("mm")[-1].strip() for line in out.console[1:]} == {"0.0000"}


def test_the_whole_log_tab_pasted_is_a_log(ur5, ur5_plan, completed):
    """wc_run's own progress lines in the log tab are '#' comments: the tab copied whole
    is a wirecal log (the paste path when the socket is lost)."""
    r = completed[1]
    console = r.programs.run.console
    assert any(line.startswith("# Step 1 of ") for line in console)
    m = check_log(parse_log("\n".join(console), "<log tab>"), ur5_plan, ur5)
    assert m.complete


def test_cli_simulate_controller_runs_the_urscript_programs(tmp_path):
    from click.testing import CliRunner

    from wirecal.cli.main import main

    log = tmp_path / "run.csv"
    args = ["simulate", "examples/ur5e/robot.toml", "examples/ur5e/plan.toml", "-o", str(log)]
    r = CliRunner().invoke(
        main, [*args, "--random", "1", "--seed", "4", "--controller", "--slip", "4:0.5"]
    )
    assert r.exit_code == 1, r.output
    assert "the controller program stopped: The zero reading at theta0 jumped" in r.output
    assert "at step 5 zero reading at theta0 (stopped in wc_run line" in r.output
    text = log.read_text()
    assert text.startswith("# wirecal-log 2\n# robot: Universal Robots UR5e\n")
    assert text.splitlines()[-1].startswith("zero,5,0,")  # the rows up to the stop


def test_a_stopped_run_shows_the_programs_own_reason_before_the_receivers():
    """The reason a run stopped is the program's: its error popup's text (a ``stopped``
    outcome's message), or the last line it showed before a ``halt``; the receiver's
    follows. When the programs completed, only the receiver knows why the log is short."""
    mount = Outcome("completed", "wc_mount")
    popup = Outcome("stopped", "wc_run", 24, "Cannot connect to the PC", ["[popup wirecal] …"])
    halted = Outcome("halted", "wc_run", 25, "halt", ["x", "[popup wirecal] Cannot connect"])
    done = Outcome("completed", "wc_run", 900)
    got = "no sender presented the run token within 2 s (--timeout)"
    assert _why_stopped(mount, popup, got) == (
        f"wc_run stopped at line 24: Cannot connect to the PC (wirecal receive: {got})"
    )
    assert _why_stopped(mount, halted, "") == (
        "wc_run halted at line 25: halt after: [popup wirecal] Cannot connect"
    )
    assert _why_stopped(mount, done, got) == got
