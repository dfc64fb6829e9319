"""Paste what the terminal shows: a whole console capture (progress lines, prompts, blank
lines, rows broken by a narrow terminal) reads like the log file, through ``solve -`` too;
the lines set aside are counted, and a join never makes a row that was not there."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.gen.vplus.program import GenOptions
from wirecal.solver.errors import WirecalError

from .conftest import ROOT, VIPER
from .twin_runs import measure_in_twin, measure_ur_in_twin

UR5 = ROOT / "examples" / "ur5e"

TRUTH = {"th2": 0.3, "th3": -0.2, "d4": 0.4, "a2": -0.3, "th6": 0.1}


def fold(lines: list[str], width: int) -> list[str]:
    """What a terminal of ``width`` columns shows: every longer line broken every width."""
    return [line[k : k + width] for line in lines for k in range(0, max(len(line), 1), width)]


def solve_json(robot: str, plan: str, log: str, stdin: str | None = None) -> dict:
    r = CliRunner().invoke(main, ["solve", robot, plan, log, "--json"], input=stdin)
    assert r.exit_code == 0, r.output
    return json.loads(r.stdout)


def parameters(result: dict) -> dict:
    return {m: result["methods"][m]["parameters"] for m in ("stepwise", "joint")}


@pytest.fixture(scope="module")
def vplus_run(viper, paper_plan, tmp_path_factory):
    disk = tmp_path_factory.mktemp("disk")
    r = measure_in_twin(viper, paper_plan, TRUTH, disk, seed=4, options=GenOptions(echo_log=True))
    assert r.run.status == "completed"
    return r.world.console, disk / "WCLOG.CSV"


@pytest.fixture(scope="module")
def ur_run(tmp_path_factory):
    ur5 = load_robot(UR5 / "robot.toml")
    r = measure_ur_in_twin(
        ur5, load_plan(UR5 / "plan.toml", ur5), TRUTH, tmp_path_factory.mktemp("ur"), seed=3
    )
    assert r.received.complete
    return r.programs.mount.console + r.programs.run.console, r.log


@pytest.mark.slow
@pytest.mark.parametrize("which", ["vplus", "ur"])
def test_the_whole_console_solves_like_the_log_file(which, request):
    """wc.run's console (V+ --echo-log) and the UR log tab, raw and folded at 80
    columns, pasted into 'solve -': the same parameters as the file, lines set aside
    counted and broken rows joined."""
    console, log = request.getfixturevalue(f"{which}_run")
    folder = VIPER if which == "vplus" else UR5
    robot = str(folder / "robot.toml")
    plan = str(folder / ("paper_plan.toml" if which == "vplus" else "plan.toml"))
    from_file = solve_json(robot, plan, str(log))
    assert any(len(line) > 80 for line in console)  # rows a terminal breaks
    for lines in (console, fold(console, 80)):
        pasted = solve_json(robot, plan, "-", "\n".join(lines) + "\n")
        assert parameters(pasted) == parameters(from_file)
        assert pasted["notes"][0].startswith("<stdin>: set aside ")
    assert pasted["notes"][1].startswith("<stdin>: joined ")


def test_the_console_as_it_was_before_the_hash_prefix(log_text):
    """Older programs typed their progress as plain text between the rows ('Step 1 of 10
    …', '  point 1: counts …'): set aside, counted, shown; the rows read as the file."""
    out = []
    for line in log_text.splitlines():
        out.append(line)
        if line.startswith("point,"):
            out.append(f"  point {line.split(',')[2]}: counts -3564192 + -0.1, sp. 2")
    out.insert(6, "Step 1 of 10: th6, 6 points")
    got = parse_log("\n".join(out) + "\n", "paste")
    clean = parse_log(log_text, "run.csv")
    assert [r.counts for r in got.readings] == [r.counts for r in clean.readings]
    n = sum(line.startswith("point,") for line in log_text.splitlines())
    assert got.notes == (
        f"paste: set aside {n + 1} line(s) that are not log rows (terminal text): line 7 "
        "'Step 1 of 10: th6, 6 points', line 10 'point 1: counts -3564192 + -0.1, sp. 2', "
        "line 12 'point 2: counts -3564192 + -0.1, sp. 2', …",
    )


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    return simulate_log(viper, paper_plan, TRUTH, seed=7, counter_start=-449000.0)


@settings(max_examples=60, deadline=None)
@given(
    width=st.integers(16, 120),
    junk=st.lists(
        st.sampled_from(["> 1", "", "Step 3 of 10", "*** ok", ".", "ex wc.run", "#   note"]),
        max_size=30,
    ),
    seed=st.integers(0, 2**16),
)
def test_rows_broken_at_any_width_read_as_written(log_text, width, junk, seed):
    """Rows folded at any width from 16 columns, human lines sprinkled between them:
    the same readings, in order, as the file."""
    lines = log_text.splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("kind,")) + 1
    body = fold(lines[head:], width)
    rng = np.random.default_rng(seed)
    for text in junk:  # between two whole rows only: a terminal never types inside one
        starts = [k for k, line in enumerate(body) if line.startswith(("zero", "point"))]
        body.insert(int(rng.choice(starts)), text)
    got = parse_log("\n".join(lines[:head] + body) + "\n", "paste")
    clean = parse_log(log_text, "run.csv")
    assert [(r.kind, r.step, r.index, r.counts, r.t_s, r.settle_s) for r in got.readings] == [
        (r.kind, r.step, r.index, r.counts, r.t_s, r.settle_s) for r in clean.readings
    ]


HEADER = (
    "# wirecal-log 2\n# robot: r\n# plan: p\n# mm_per_count: 0.025488\n"
    "kind,step,index,j1,j2,j3,j4,j5,j6,counts,samples,spread,t_s,settle_s\n"
)
ROW = "zero,1,0,0.0000,-90.0000,210.0000,-90.0000,0.0000,-90.0000,-3566604.9000,10,2,0.580,0.080"


def test_a_break_inside_the_last_field_without_width_evidence_is_refused():
    """'…,0.08' + '0': both a readable row and its continuation; no other broken row
    tells the terminal's width, so the reader refuses instead of guessing."""
    text = HEADER + ROW[:-1] + "\n" + ROW[-1:] + "\n"
    with pytest.raises(WirecalError) as info:
        parse_log(text, "p")
    assert info.value.problems == [
        "p:7: '0' may be the end of the row on line 6, broken by the terminal: join the two "
        "lines or delete this one"
    ]


def test_a_break_inside_the_last_field_is_joined_at_the_terminals_width():
    """The same break, when the other broken rows show the terminal's width (the row's
    first piece is as long): joined, the full settle_s read."""
    width = len(ROW) - 1
    other = ROW.replace("zero,1,0,", "point,1,1,").replace("0.580", "10.580")
    lines = [*fold([ROW], width), *fold([other], width)]
    assert lines[1] == "0"
    assert len(lines) == 4
    log = parse_log(HEADER + "\n".join(lines) + "\n", "p")
    assert [r.settle_s for r in log.readings] == [0.08, 0.08]
    assert [r.t_s for r in log.readings] == [0.58, 10.58]


def test_pieces_that_are_rows_of_their_own_are_never_joined():
    """A row cut mid-write followed by the next whole row: no join can make a row of
    them; the cut row stays an error (a lost reading is never set aside)."""
    text = HEADER + ROW[:40] + "\n" + ROW.replace("zero,1,0", "zero,2,0") + "\n"
    with pytest.raises(WirecalError, match=r"^p:6: has 7 fields; expected 14$"):
        parse_log(text, "p")


def test_a_capture_of_two_runs_is_refused():
    text = HEADER + ROW + "\n" + HEADER + ROW + "\n"
    with pytest.raises(WirecalError, match="p:7: a second log begins here"):
        parse_log(text, "p")


def test_quotes_in_terminal_text_are_fine_in_quoted_rows_not():
    """Operator text may quote ('LOAD "WIRECAL.V2"'); a quoted row is still refused."""
    text = HEADER + ROW + '\nLOAD "WIRECAL.V2"\n'
    assert len(parse_log(text, "p").readings) == 1
    quoted = ",".join(f'"{c}"' for c in ROW.split(","))
    with pytest.raises(WirecalError, match=r"p:7: fields are in double quotes on 1 line"):
        parse_log(HEADER + ROW + "\n" + quoted + "\n", "p")
