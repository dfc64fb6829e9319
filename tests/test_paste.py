"""The paste path: a log pasted from a terminal or an editor (BOM, indentation, trailing
whitespace, CRLF) reads like the file the controller wrote, through standard input too;
quoted fields, counts beyond the counter and counts a spreadsheet rounded are refused with
one message each. The same reader serves the validation logs and the controller result."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.controller_result import read_result
from wirecal.formats.log import parse_log
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.validation_files import read_validation_log
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log

from .conftest import VIPER

ROBOT = str(VIPER / "robot.toml")
PLAN = str(VIPER / "paper_plan.toml")
TRUTH = {"th2": 0.3, "th3": -0.2, "d4": 0.4, "a2": -0.3, "th6": 0.1}


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    return simulate_log(viper, paper_plan, TRUTH, seed=7, counter_start=-449000.0)


def with_counts(text: str, value) -> str:
    out = []
    for line in text.splitlines():
        if line.startswith(("zero,", "point,")):
            cells = line.split(",")
            cells[9] = value(float(cells[9]))
            line = ",".join(cells)
        out.append(line)
    return "\n".join(out) + "\n"


def problems_of(text):
    with pytest.raises(WirecalError) as info:
        parse_log(text, "run.csv")
    return info.value.problems


@settings(max_examples=40, deadline=None)
@given(
    bom=st.booleans(),
    blank=st.integers(0, 2),
    newline=st.sampled_from(["\n", "\r\n", "\r"]),
    pads=st.lists(
        st.tuples(st.sampled_from(["", " ", "  ", "\t", "    "]), st.sampled_from(["", " ", "\t"])),
        min_size=1,
    ),
)
def test_pasted_text_reads_like_the_file(log_text, bom, blank, newline, pads):
    clean = parse_log(log_text, "run.csv")
    lines = log_text.splitlines()
    pasted = newline.join(
        f"{pads[k % len(pads)][0]}{line}{pads[k % len(pads)][1]}" for k, line in enumerate(lines)
    )
    pasted = ("\ufeff" if bom else "") + newline * blank + pasted + newline
    got = parse_log(pasted, "run.csv")
    assert (got.robot, got.plan, got.mm_per_count) == (clean.robot, clean.plan, clean.mm_per_count)
    assert [r.line - blank for r in got.readings] == [r.line for r in clean.readings]
    np.testing.assert_array_equal(
        [r.counts for r in got.readings], [r.counts for r in clean.readings]
    )
    assert got.notes == ()


def test_solve_reads_standard_input(tmp_path, log_text):
    pasted = "\ufeff" + "".join(f"   {line}  \r\n" for line in log_text.splitlines())
    log = tmp_path / "run.csv"
    log.write_text(log_text)

    def solve(*args, input=None):
        r = CliRunner().invoke(main, ["solve", ROBOT, PLAN, *args, "--json"], input=input)
        assert r.exit_code == 0, r.output
        return json.loads(r.stdout)

    from_stdin = solve("-", input=pasted.encode("utf-8"))
    from_file = solve(str(log))
    assert from_stdin["log"] == "<stdin>"
    joint = from_file["methods"]["joint"]["parameters"]
    assert from_stdin["methods"]["joint"]["parameters"] == joint
    patch = tmp_path / "patch.toml"
    r = CliRunner().invoke(main, ["solve", ROBOT, PLAN, "-", "-o", str(patch)], input=pasted)
    assert r.exit_code == 0, r.output
    assert 'log = "<stdin>"' in patch.read_text()


def test_quoted_fields_get_one_message(log_text):
    quoted = "\n".join(
        ",".join(f'"{c}"' for c in line.split(",")) if line[:1] in "zp" else line
        for line in log_text.splitlines()
    )
    got = problems_of(quoted + "\n")
    n = len([line for line in log_text.splitlines() if line[:1] in "zp"])
    assert got == [
        f"run.csv:7: fields are in double quotes on {n} line(s): a spreadsheet re-saved the "
        "file; use the file as written, or save it as plain CSV without quotes"
    ]


def test_counts_with_five_significant_digits_are_refused(log_text):
    got = problems_of(with_counts(log_text, lambda c: f"{c:.4E}"))
    assert len(got) == 1
    assert got[0].startswith("run.csv:7: counts '-4.4")
    assert "keeps 5 significant digits of the 6 the count needs" in got[0]
    assert got[0].endswith("re-saved by a spreadsheet; use the file the controller wrote")


def test_counts_rounded_to_hundreds_are_refused(log_text):
    got = problems_of(with_counts(log_text, lambda c: f"{round(c, -2):.0f}"))
    assert got == [
        "run.csv:7: every count ends in 0: the counts were rounded (a spreadsheet re-save "
        "with fewer significant digits?); use the file the controller wrote"
    ]


def test_whole_counts_that_are_exact_are_accepted(log_text):
    """Integer counts are fine (a controller may log them so) unless all end in 0."""
    log = parse_log(with_counts(log_text, lambda c: f"{c:.0f}"), "run.csv")
    assert len(log.readings) == 69 + 10 + 1  # points, the steps' zeros, the closing zero


def test_counts_beyond_the_counter_are_refused(viper, paper_plan, log_text):
    first_point = next(
        k for k, line in enumerate(log_text.splitlines(), 1) if line.startswith("point,1,1,")
    )
    text = "\n".join(
        line.replace(line.split(",")[9], "9000000.0000") if k == first_point else line
        for k, line in enumerate(log_text.splitlines(), 1)
    )
    with pytest.raises(WirecalError) as info:
        check_log(parse_log(text + "\n", "run.csv"), paper_plan, viper)
    assert info.value.problems[0] == (
        f"run.csv:{first_point}: counts 9000000.0000 exceed the 24-bit counter (±8388608): not "
        f"a count of this encoder; check counter_bits in {viper.source} and that the log "
        "column holds the raw counter value"
    )


def test_validation_log_and_controller_result_share_the_tolerance(tmp_path):
    v = tmp_path / "v.csv"
    v.write_bytes(
        "\ufeff# wirecal-validation 1\r\n  # kind: plane\r\n# robot: r\r\n# setup: s\r\n"
        "row,col,x,y,z  \r\n 1,1,0,0,1\r\n1,2,1,0,1\r\n2,1,0,1,1\r\n".encode()
    )
    log = read_validation_log(v, "plane")
    assert log.rows.shape == (3, 5)
    r = tmp_path / "r.csv"
    r.write_text("# wirecal-controller-result 1\r\n# method: joint\r\nparameter,unit,offset\r\n")
    with r.open("a") as f:
        f.write("  th2,deg,0.125\r\na1,mm,-0.5")  # the last line without its newline
    assert read_result(r) == {"th2": 0.125, "a1": -0.5}
    r.write_text('# wirecal-controller-result 1\nparameter,unit,offset\n"th2","deg","0.1"\n')
    with pytest.raises(WirecalError, match=r"r\.csv:3: fields are in double quotes on 1 line"):
        read_result(r)


@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_mangled_logs_give_messages_never_a_traceback(log_text, data):
    """Cut, splice and garble a log: the reader either reads it or says where it is wrong."""
    text = log_text
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, len(text)))
        cut = data.draw(st.integers(0, 40))
        junk = data.draw(st.text(alphabet=st.sampled_from(',"#\r\n\ufeff \t-+.eE09x:'), max_size=6))
        text = text[:at] + junk + text[at + cut :]
    problems = _problems(text)
    assert problems is None or problems
    assert all(p.startswith("run.csv") for p in problems or ())


@pytest.mark.slow  # the controller solver runs in the twin (about 20 s)
def test_controller_comparison_from_standard_input(log_text):
    """The log is read once: the controller comparison needs no second read of a pipe."""
    r = CliRunner().invoke(
        main, ["solve", ROBOT, PLAN, "-", "--method", "controller"], input=log_text
    )
    assert r.exit_code == 0, r.output
    assert "largest difference from the Python reference" in r.output


def _problems(text: str) -> list[str] | None:
    """The problems parse_log reports for ``text``, or None when it reads it."""
    try:
        parse_log(text, "run.csv")
    except WirecalError as exc:
        return exc.problems
    return None
