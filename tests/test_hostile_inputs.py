"""Every command over hostile inputs: a clear ``error:`` line and exit status 1–3, or a
normal result, never a traceback.

Fixed cases (empty, binary, a folder, a missing file) for every input of every command,
then hypothesis-mutated robot files, plans and logs through the fast commands.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import subprocess
import sys

import click
import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main

from .conftest import DATA, VIPER

ROBOT = VIPER / "robot.toml"
PLAN = VIPER / "paper_plan.toml"
URDF = DATA / "twisted_arm.urdf"
TABLE = VIPER / "simulated_cable_table.csv"
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
HOSTILE = ["nan", "inf", "-inf", "-1", "0", "1e300", "-1e300", "1e-300", '"x"', "[]", "true"]


def outcome_is_clean(r) -> None:
    """Exit 0, or 1–3 with an ``error:`` line; never an exception (a traceback)."""
    if r.exception is not None and not isinstance(r.exception, SystemExit):
        raise AssertionError(f"traceback: {r.exception!r}\n{r.output}") from r.exception
    assert "Traceback" not in r.output
    if r.exit_code != 0:
        assert r.exit_code in (1, 2, 3), r.output
        assert re.search(r"^(error|Error): ", r.output, re.M), r.output


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    path = tmp_path_factory.mktemp("hostile") / "run.csv"
    r = invoke("simulate", ROBOT, PLAN, "-o", path, "--seed", 5)
    assert r.exit_code == 0, r.output
    return path


def _hostile_file(tmp_path, kind):
    path = tmp_path / f"{kind}.in"
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "binary":
        path.write_bytes(bytes(range(256)) * 8)
    elif kind == "folder":
        path.mkdir()
    elif kind == "bom-garbage":
        path.write_bytes(b"\xef\xbb\xbf= = =\n[[[\n")
    return path  # "missing": never created


COMMANDS = {
    # name: (argument list with ROBOT/PLAN/LOG/VLOG/OUT slots, slots hostile inputs go into)
    "psi": (["psi", "ROBOT", "PLAN"], ["ROBOT", "PLAN"]),
    "observe": (["observe", "ROBOT", "PLAN"], ["ROBOT", "PLAN"]),
    "plan": (["plan", "ROBOT", "-o", "OUT"], ["ROBOT"]),
    "gen": (["gen", "ROBOT", "PLAN", "-o", "OUT"], ["ROBOT", "PLAN"]),
    "simulate": (["simulate", "ROBOT", "PLAN", "-o", "OUT"], ["ROBOT", "PLAN"]),
    "solve": (["solve", "ROBOT", "PLAN", "LOG", "-o", "OUT"], ["ROBOT", "PLAN", "LOG"]),
    "report": (["report", "ROBOT", "PLAN", "LOG", "-o", "OUT.html"], ["ROBOT", "PLAN", "LOG"]),
    "receive": (
        ["receive", "--port", "1", "-o", "OUT", "--robot", "ROBOT", "--plan", "PLAN"],
        ["ROBOT", "PLAN"],
    ),
    "validate configuration": (
        ["validate", "configuration", "VLOG", "--robot", "ROBOT"],
        ["VLOG", "ROBOT"],
    ),
    "validate plane": (["validate", "plane", "VLOG"], ["VLOG"]),
    "lint": (["lint", "V2"], ["V2"]),
    "import-urdf": (["import-urdf", "URDF", "--tip", "wire", "-o", "OUT"], ["URDF"]),
    "export-urdf": (["export-urdf", "ROBOT", "-o", "OUT"], ["ROBOT"]),
    "fit": (["fit", "ROBOT", "TABLE", "--holdout", "none", "-o", "OUT"], ["ROBOT", "TABLE"]),
}
CASES = [
    (name, slot, kind)
    for name, (_, slots) in COMMANDS.items()
    for slot in slots
    for kind in ("empty", "binary", "folder", "missing", "bom-garbage")
]


@pytest.mark.parametrize(("name", "slot", "kind"), CASES)
def test_fixed_hostile_inputs(tmp_path, log, name, slot, kind):
    args, _ = COMMANDS[name]
    out = tmp_path / "out"
    values = {"ROBOT": ROBOT, "PLAN": PLAN, "LOG": log, "VLOG": log, "OUT": out, "URDF": URDF}
    values["TABLE"] = TABLE
    values["OUT.html"] = tmp_path / "out.html"
    values[slot] = _hostile_file(tmp_path, kind)
    r = invoke(*(values.get(a, a) for a in args))
    outcome_is_clean(r)
    assert r.exit_code != 0
    assert not out.exists()
    assert not (tmp_path / "out.html").exists()


@pytest.mark.parametrize(
    "args",
    [
        ["demo", "-o", "FILE"],
        ["gen", ROBOT, PLAN, "-o", "FILE"],
        ["simulate", ROBOT, PLAN, "-o", "DIR"],
        ["solve", ROBOT, PLAN, "LOG", "-o", "DIR"],
        ["simulate", ROBOT, PLAN, "-o", "NOFOLDER/x.csv"],
        ["receive", "--port", "1", "-o", "DIR", "--timeout", "0.1"],
        ["receive", "--port", "1", "-o", "NOFOLDER/x.csv", "--timeout", "0.1"],
        ["gen", ROBOT, PLAN, "-o", "OUT", "--patch", "LOG"],
        ["gen", ROBOT, PLAN, "-o", "OUT", "--validation", "FILE"],
        ["simulate", ROBOT, PLAN, "-o", "OUT", "--errors", "LOG"],
        ["report", ROBOT, PLAN, "LOG", "-o", "OUT.html", "--truth", "DIR"],
        ["report", ROBOT, PLAN, "LOG", "-o", "OUT.html", "--plane", "LOG", "LOG"],
    ],
    ids=lambda a: " ".join(str(x) for x in a),
)
def test_hostile_output_and_option_files(tmp_path, log, args):
    (tmp_path / "DIR").mkdir()
    (tmp_path / "FILE").write_text("a file\n")
    values = {"LOG": log}
    args = [values.get(a, tmp_path / a if str(a).isupper() or "/" in str(a) else a) for a in args]
    r = invoke(*args)
    outcome_is_clean(r)
    assert r.exit_code != 0
    assert not (tmp_path / "OUT").exists()
    assert not (tmp_path / "OUT.html").exists()
    assert (tmp_path / "FILE").read_text() == "a file\n"


@st.composite
def mutated(draw, text: str) -> str:
    """The text with one hostile edit: a number replaced, a line dropped or doubled, the
    text cut short, or a stray character inserted."""
    lines = text.splitlines(keepends=True)
    k = draw(st.integers(0, len(lines) - 1))
    how = draw(st.sampled_from(["number", "number", "number", "drop", "double", "cut", "insert"]))
    if how == "number":
        numbers = [m.span() for m in NUMBER.finditer(lines[k])]
        if numbers:
            a, b = draw(st.sampled_from(numbers))
            lines[k] = lines[k][:a] + draw(st.sampled_from(HOSTILE)) + lines[k][b:]
    elif how == "drop":
        del lines[k]
    elif how == "double":
        lines.insert(k, lines[k])
    elif how == "insert":
        pos = draw(st.integers(0, len(lines[k])))
        ch = draw(st.sampled_from([",", '"', "\t", "#", "=", "\x00", "é", "]"]))
        lines[k] = lines[k][:pos] + ch + lines[k][pos:]
    out = "".join(lines)
    if how == "cut":
        out = out[: draw(st.integers(0, len(out)))]
    return out


FUZZ = settings(
    max_examples=int(os.environ.get("WIRECAL_FUZZ_EXAMPLES", "40")),
    deadline=None,
    derandomize="WIRECAL_FUZZ_EXAMPLES" not in os.environ,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


@pytest.mark.slow
@FUZZ
@given(data=st.data())
def test_mutated_robot_file(tmp_path, log, data):
    robot = tmp_path / "robot.toml"
    robot.write_text(data.draw(mutated(ROBOT.read_text())), encoding="utf-8")
    for args in (["psi", robot, PLAN], ["solve", robot, PLAN, log, "--method", "stepwise"]):
        outcome_is_clean(invoke(*args))


@FUZZ
@given(data=st.data())
def test_mutated_urdf(tmp_path, data):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(data.draw(mutated(URDF.read_text())), encoding="utf-8")
    out = tmp_path / "robot.toml"
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", out)
    outcome_is_clean(r)
    if r.exit_code == 0:  # what was written reads back and exports
        outcome_is_clean(invoke("export-urdf", out, "-o", tmp_path / "out.urdf"))
    out.unlink(missing_ok=True)
    (tmp_path / "out.urdf").unlink(missing_ok=True)


@pytest.mark.slow
@FUZZ
@given(data=st.data())
def test_mutated_plan(tmp_path, log, data):
    plan = tmp_path / "plan.toml"
    plan.write_text(data.draw(mutated(PLAN.read_text())), encoding="utf-8")
    for args in (["observe", ROBOT, plan], ["solve", ROBOT, plan, log, "--method", "stepwise"]):
        outcome_is_clean(invoke(*args))


@FUZZ
@given(data=st.data())
def test_mutated_log(tmp_path, log, data):
    bad = tmp_path / "run.csv"
    bad.write_text(data.draw(mutated(log.read_text())), encoding="utf-8")
    outcome_is_clean(invoke("solve", ROBOT, PLAN, bad, "--method", "stepwise"))


@pytest.mark.slow
@FUZZ
@given(data=st.data())
def test_mutated_cable_table(tmp_path, data):
    bad = tmp_path / "table.csv"
    bad.write_text(data.draw(mutated(TABLE.read_text())), encoding="utf-8")
    outcome_is_clean(invoke("fit", ROBOT, bad, "--holdout", "none"))


def test_every_command_is_covered():
    """A new command gets hostile inputs too."""
    covered = {name.split()[0] for name in COMMANDS} | {"demo"}
    commands = set(main.list_commands(click.Context(main)))
    assert commands <= covered, commands - covered


def test_copy_of_example_is_clean(tmp_path):
    """The corpus is hostile because of the edits, not because of the examples."""
    shutil.copy(ROBOT, tmp_path / "robot.toml")
    assert invoke("psi", tmp_path / "robot.toml", PLAN).exit_code == 0


# -- the fault matrix's defect list (issue 22 item 4) ------------------------------------

UR5 = VIPER.parent / "ur5e"


def test_report_controller_for_a_ur_robot(tmp_path):
    """URScript's controller solver has no polish: one controller column, no crash."""
    log_path, html = tmp_path / "ur.csv", tmp_path / "ur.html"
    r = invoke("simulate", UR5 / "robot.toml", UR5 / "plan.toml", "-o", log_path, "--seed", 1)
    assert r.exit_code == 0, r.output
    r = invoke(
        "report", UR5 / "robot.toml", UR5 / "plan.toml", log_path, "-o", html, "--controller"
    )
    outcome_is_clean(r)
    assert r.exit_code == 0, r.output
    text = html.read_text()
    assert "controller (wc_solve)" in text
    assert "wc.solve2" not in text
    # wc_solve agrees with the Python reference to its single-precision floats
    m = re.search(r"differs from the\s+Python reference by ([0-9.e+-]+) \(stepwise\) deg/mm", text)
    assert m is not None
    assert float(m.group(1)) < 1e-3


def _with_gauge(tmp_path):
    """The Viper's robot file with a 500 mm reference gauge, and a simulated log of it."""
    robot = tmp_path / "gauge.toml"
    robot.write_text(
        ROBOT.read_text().replace("[encoder]\n", "[encoder]\nreference_length_mm = 500.0\n")
    )
    log_path = tmp_path / "gauge.csv"
    r = invoke("simulate", robot, PLAN, "-o", log_path, "--seed", 2)
    assert r.exit_code == 0, r.output
    return robot, log_path


def _edit_references(log_path, edit) -> None:
    """Apply ``edit(index, counts, counts of the pair's nest A) → counts`` to each reference row."""
    lines = log_path.read_text().splitlines()
    nest_a = 0.0
    for k, line in enumerate(lines):
        cells = line.split(",")
        if cells[0] == "reference":
            index, counts = int(cells[2]), float(cells[9])
            nest_a = counts if index % 2 else nest_a
            cells[9] = f"{edit(index, counts, nest_a):.4f}"
            lines[k] = ",".join(cells)
    log_path.write_text("\n".join(lines) + "\n")


MM_PER_COUNT = 0.025488
REFERENCE_FAULTS = {
    # nest B read where nest A was: B = A
    "unmoved tip": (
        lambda i, c, a: a,
        r"gauge.csv:7-8: reference pair 1 reads B − A = \+0\.000 mm of a 500 mm gauge "
        r"\(\[encoder\] reference_length_mm\): the tip did not move",
    ),
    # every pair measured B first: B − A ≈ −500 mm
    "swapped nests": (
        lambda i, c, a: c if i % 2 else 2 * a - c,
        r"reference pair 1 reads B − A = -(?:499|500)\.\d+ mm, minus the gauge's length: "
        r"nests A and B were swapped",
    ),
    # the second pair's tip sat 0.3 mm proud of nest B
    "one bad seating": (
        lambda i, c, a: c - 0.3 / MM_PER_COUNT if i == 4 else c,
        r"gauge.csv:9-10: reference pair 2 reads B − A = 499\.\d+ mm, -0\.3\d\d mm from the "
        r"gauge's 500 mm .*a bad seating",
    ),
    # every pair 1 mm long: the certified length (or mm_per_count) is wrong
    "wrong gauge length": (
        lambda i, c, a: c if i % 2 else c + 1.0 / MM_PER_COUNT,
        r"every reference pair reads 50[01]\.\d+ mm against \[encoder\] reference_length_mm = 500",
    ),
}


@pytest.mark.parametrize("fault", REFERENCE_FAULTS)
def test_reference_step_faults_are_named(tmp_path, fault):
    robot, log_path = _with_gauge(tmp_path)
    edit, message = REFERENCE_FAULTS[fault]
    _edit_references(log_path, edit)
    r = invoke("solve", robot, PLAN, log_path)
    outcome_is_clean(r)
    assert r.exit_code == 2, r.output
    assert re.search(message, r.output), r.output


def test_reference_step_clean_log_is_read(tmp_path):
    robot, log_path = _with_gauge(tmp_path)
    r = invoke("solve", robot, PLAN, log_path)
    assert r.exit_code == 0, r.output
    assert "encoder scale from the reference (3 pair(s)" in r.output


def _run_closed_stdin(*args):
    """Run wirecal in a process whose standard input is closed (a shell's ``0<&-``)."""
    code = "from wirecal.cli.main import main; main()"
    return subprocess.run(
        [sys.executable, "-c", code, *map(str, args)],
        preexec_fn=lambda: os.close(0),
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.mark.parametrize(
    "args",
    [["solve", ROBOT, PLAN, "-"], ["lint", "-"]],
    ids=lambda a: " ".join(map(str, a)),
)
def test_closed_standard_input(args):
    r = _run_closed_stdin(*args)
    assert r.returncode == 2, r.stderr
    assert "Traceback" not in r.stderr
    assert "error: <stdin>: standard input is closed" in r.stderr


ZERO = "/dev/zero"
ENDLESS = [  # every reader given an endless file: refused after 16 MiB, not read forever
    ["lint", ZERO],
    ["psi", ZERO, PLAN],
    ["psi", ROBOT, ZERO],
    ["solve", ROBOT, PLAN, ZERO],
    ["validate", "plane", ZERO],
    ["simulate", ROBOT, PLAN, "-o", "OUT", "--errors", ZERO],
    ["gen", ROBOT, PLAN, "-o", "OUT", "--patch", ZERO],
    ["gen", ROBOT, PLAN, "-o", "OUT", "--validation", ZERO],
]


@pytest.mark.skipif(not os.path.exists(ZERO), reason="no /dev/zero")
@pytest.mark.parametrize("args", ENDLESS, ids=lambda a: " ".join(map(str, a)))
def test_endless_input_is_refused(tmp_path, args):
    r = invoke(*(tmp_path / a if a == "OUT" else a for a in args))
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert "/dev/zero: more than 16 MiB: not a" in r.output
    assert not (tmp_path / "OUT").exists()


@pytest.mark.parametrize("slot", ["ROBOT", "PLAN"])
@pytest.mark.parametrize("opening", ["[", "{x = "])
def test_deeply_nested_toml_is_refused(tmp_path, slot, opening):
    """Python's TOML reader recurses per level: 5000 levels are refused before it reads them."""
    closing = "]" if opening == "[" else "}"
    deep = tmp_path / "deep.toml"
    deep.write_text(f"a = {opening * 5000}1{closing * 5000}\n")
    values = {"ROBOT": ROBOT, "PLAN": PLAN, slot: deep}
    r = invoke("psi", values["ROBOT"], values["PLAN"])
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert re.search(r"deep\.toml: arrays and tables nested 500\d deep \(more than 16", r.output)


def test_oversized_plan_step_is_refused(tmp_path):
    big = tmp_path / "big.toml"
    rows = "".join(f"[0, -90, 210, -90, -26, {-180 + k % 300 * 0.1:.1f}],\n" for k in range(1001))
    big.write_text(PLAN.read_text().replace("points_deg = [\n", f"points_deg = [\n{rows}", 1))
    r = invoke("psi", ROBOT, big)
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert "big.toml: step[1].points_deg: has 1007 rows; give at most 1000" in r.output


def test_oversized_robot_is_refused(tmp_path):
    robot = tmp_path / "robot.toml"
    rows = ", ".join(["[0, 0, 0, 100]"] * 13)
    text = re.sub(r"^dh = \[.*?^\]$", f"dh = [{rows}]", ROBOT.read_text(), flags=re.M | re.S)
    robot.write_text(text)
    r = invoke("psi", robot, PLAN)
    outcome_is_clean(r)
    assert "kinematics.dh: has 13 rows; give at most 12" in r.output


def _nested_program(suffix: str, blocks: int, operators: int) -> str:
    """A V+ (.v2) or URScript (.script) program: ``blocks`` nested IFs around a line with a
    chain of ``operators`` additions."""
    expression = "1" + "+1" * operators
    if suffix == ".v2":
        body = ["    IF 1 THEN"] * blocks + [f"    x = {expression}"] + ["    END"] * blocks
        return "\n".join([".PROGRAM t()", *body, ".END"]) + "\n"
    opens = [" " * (k + 1) + "if True:" for k in range(blocks)]
    ends = [" " * (blocks - k) + "end" for k in range(blocks)]
    return "\n".join(["def t():", *opens, " " * (blocks + 1) + f"x = {expression}", *ends, "end"])


@pytest.mark.parametrize("suffix", [".v2", ".script"])
@pytest.mark.parametrize(
    ("blocks", "operators", "message"),
    [
        (330, 1, r":6[56]: (t: )?blocks nested more than 64 deep; wirecal reads at most 64"),
        (2, 1000, r":4: (t: )?the line nests 100\d levels deep .* wirecal reads at most 100"),
    ],
    ids=["330 nested IFs", "1000 chained operators"],
)
def test_lint_refuses_deep_nesting(tmp_path, suffix, blocks, operators, message):
    path = tmp_path / f"deep{suffix}"
    path.write_text(_nested_program(suffix, blocks, operators))
    r = invoke("lint", path)
    outcome_is_clean(r)
    assert r.exit_code == 1, r.output
    assert re.search(re.escape(path.name) + message, r.output), r.output


def _chain_program(suffix: str, expression: str) -> str:
    """A RAPID, V+ or URScript program whose one line sets x to ``expression``."""
    if suffix == ".mod":
        body = ["  PROC main()", "    VAR num a;", "    VAR num x;", f"    x := {expression};"]
        return "\n".join(["MODULE t", *body, "  ENDPROC", "ENDMODULE"]) + "\n"
    if suffix == ".v2":
        return f".PROGRAM t()\n    x = {expression}\n.END\n"
    return f"def t():\n  x = {expression}\nend\n"


RUN = r"more than 10000 operators in a row: wirecal reads at most 10000"


@pytest.mark.parametrize("suffix", [".mod", ".v2", ".script"])
@pytest.mark.parametrize(
    ("expression", "message"),
    [
        ("+".join(["a"] * 800), r"(an expression|the line) nest(ed|s) (more than 100|\d+) levels"),
        ("+".join(["a"] * 20_001), RUN),
        ("+".join(["(a)"] * 20_001), RUN),
        ("(" * 5000 + "a" + ")" * 5000, r"brackets nested more than 100 deep"),
        ("(" * 101 + "a" + ")" * 101, r"brackets nested more than 100 deep"),
    ],
    ids=["800 terms", "20001 terms", "20001 bracketed terms", "5000 brackets", "101 brackets"],
)
def test_ra21_a_chain_of_variables_is_refused_before_it_costs_minutes(
    tmp_path, suffix, expression, message
):
    """RA21: a line of 1.5 M chained '+' terms ended in a RecursionError after 67 s and
    3.2 GB; 800 are enough to nest too deep. The bound on a run of operators skipped runs
    whose operands are variables or bracketed (RAPID: 300 000 variables took 17 s, 0.6 GB;
    100 000 '(a)' 25 s), and V+ and URScript had none (1.5 M terms: 324 s and 57 s, then
    refused; V+'s check of constants was quadratic; 100 000 brackets took 8 s, and
    URScript then found no problem). 20 001 terms stand in for 1.5 M: over the same bound,
    refused before parsing."""
    path = tmp_path / f"chain{suffix}"
    path.write_text(_chain_program(suffix, expression))
    r = invoke("lint", path)
    outcome_is_clean(r)
    assert r.exit_code == 1, r.output
    assert re.search(re.escape(path.name) + r":\d+: (t: )?" + message, r.output), r.output


def test_one_bracket_rule_for_the_three_languages(tmp_path):
    """A short line of 101 nested brackets: URScript's parse tree collapses brackets, so it
    once passed where V+ and RAPID refused; the one rule (lang/syntax.py) refuses it in all
    three, by the same words; 100 brackets pass URScript's lint."""
    for suffix in (".mod", ".v2", ".script"):
        path = tmp_path / f"b{suffix}"
        path.write_text(_chain_program(suffix, "(" * 101 + "1" + ")" * 101))
        r = invoke("lint", path)
        outcome_is_clean(r)
        assert r.exit_code == 1, r.output
        assert "brackets nested more than 100 deep; wirecal reads at most 100" in r.output
    path = tmp_path / "ok.script"
    path.write_text(_chain_program(".script", "(" * 100 + "1" + ")" * 100))
    r = invoke("lint", path)
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("suffix", [".v2", ".script", ".mod"])
def test_nt14_lint_names_a_utf16_program(tmp_path, suffix):
    """NT14's neighbour in lint: a program saved as UTF-16 gave one 'code outside a program'
    per line (3306 for the Viper's module), the encoding not named."""
    program = tmp_path / f"p{suffix}"
    program.write_bytes('.PROGRAM a()\n    TYPE "x"\n.END\n'.encode("utf-16"))
    r = invoke("lint", program)
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert r.output == (
        f"error: {program}: UTF-16 text; save it as UTF-8 (a program file is plain UTF-8 text)\n"
    )


def test_lint_still_reads_latin_1_programs(tmp_path):
    """The valid neighbour: a V+ comment in Latin-1 (a byte above 127, not UTF-8) lints."""
    program = tmp_path / "p.v2"
    program.write_bytes('.PROGRAM a()\n    ; Fa\xe7ade\n    TYPE "x"\n.END\n'.encode("latin-1"))
    r = invoke("lint", program)
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize("suffix", [".v2", ".script"])
def test_lint_reads_nesting_up_to_its_bounds(tmp_path, suffix):
    """63 IFs inside the program (64 blocks with URScript's def) and a 90-operator line."""
    path = tmp_path / f"deep{suffix}"
    path.write_text(_nested_program(suffix, 64 if suffix == ".v2" else 63, 90))
    r = invoke("lint", path)
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize(
    ("option", "message"),
    [
        (["--encoder-scale-ppm", "-1000000"], "--encoder-scale-ppm"),  # 1 + scale = 0
        (["--encoder-scale-ppm", "1e300"], "--encoder-scale-ppm"),
        (["--drift-mm-per-h", "1e300"], "--drift-mm-per-h"),
        (["--random", "1e300"], "--random"),
        (["--noise-mm", "1e300"], "beyond the encoder's range_mm"),
        (["--outliers", "3", "--outlier-mm", "1e308"], "--outlier-mm"),
        (["--outliers", "3", "--outlier-mm", "5000"], "beyond the encoder's range_mm"),
        (["--slip", "4:-1e308"], "give a slip within ±100000 mm"),
        (["--slip", "4:-2000"], "mm long, beyond the encoder's range_mm 1250"),
        (["--controller", "--slip", "4:-1e308"], "give a slip within ±100000 mm"),
    ],
    ids=lambda a: " ".join(a) if isinstance(a, list) else "",
)
def test_simulate_never_writes_nan_counts(tmp_path, option, message):
    """Each of these wrote NaN (or 0) counts with exit status 0."""
    out = tmp_path / "run.csv"
    r = invoke("simulate", ROBOT, PLAN, "-o", out, *option)
    outcome_is_clean(r)
    assert r.exit_code == 2, r.output
    assert message in r.output
    assert not out.exists()


@pytest.mark.filterwarnings("ignore:divide by zero:RuntimeWarning")
def test_simulate_log_refuses_a_reading_that_is_not_finite(viper, paper_plan, table5):
    """The API's own guard, below the command's option bounds: a scale of −100 % reads inf."""
    from wirecal.formats.simulated_log import simulate_log
    from wirecal.solver.errors import WirecalError
    from wirecal.solver.simulate import EncoderTruth

    with pytest.raises(
        WirecalError, match=r"encoder's reading of step 1 zero reading is (inf|nan)"
    ):
        simulate_log(viper, paper_plan, table5, seed=1, encoder=EncoderTruth(scale_ppm=-1e6))


def _with_times(source, target, times) -> None:
    """Copy a log with each reading's t_s replaced by ``times(line number, t_s)``."""
    lines = source.read_text().splitlines()
    for k, line in enumerate(lines):
        cells = line.split(",")
        if cells[0] in ("zero", "point", "unsettled", "reference"):
            cells[12] = f"{times(k + 1, float(cells[12])):.3f}"
            lines[k] = ",".join(cells)
    target.write_text("\n".join(lines) + "\n")


TIMER_FAULTS = {
    "all zero": (lambda n, t: 0.0, r"took 0 s; the robot needs 72 s at full speed.*at zero or in"),
    "milliseconds": (lambda n, t: 1000 * t, r"took 86\d\d\d s; .*timer in milliseconds\?"),
    "huge": (
        lambda n, t: 1e300 if n == 20 else t,
        r"run\.csv:21: t_s [\d.]+ s is before the "
        r"previous reading's 1e\+300 s \(line 20\)",
    ),
    "minutes": (lambda n, t: t / 60, r"took 1\.4\d* s; .*at zero or in minutes\?"),
    "backwards": (
        lambda n, t: 1.0 if n == 20 else t,
        r"run\.csv:20: t_s 1 s is before the previous reading's \d+\.\d+ s \(line 19\)",
    ),
}


@pytest.mark.parametrize("fault", TIMER_FAULTS)
def test_timer_sanity(tmp_path, log, fault):
    """t_s all zero or in the wrong unit passed the drift check (no drift or 1000× too small)."""
    times, message = TIMER_FAULTS[fault]
    bad = tmp_path / "run.csv"
    _with_times(log, bad, times)
    r = invoke("solve", ROBOT, PLAN, bad)
    outcome_is_clean(r)
    assert r.exit_code == 2, r.output
    assert re.search(message, r.output), r.output


def test_a_log_pasted_many_times_gives_a_readable_error(tmp_path, log):
    """Every duplicated row is a problem (thousands here): the command prints the first 40
    and a count, not a screenful per row."""
    lines = log.read_text().splitlines()
    rows = [x for x in lines if x[:1].isalpha() and not x.startswith("kind,")]
    bad = tmp_path / "run.csv"
    bad.write_text("\n".join(lines + rows * 50) + "\n")
    r = invoke("solve", ROBOT, PLAN, bad)
    outcome_is_clean(r)
    assert r.exit_code == 2
    errors = [x for x in r.output.splitlines() if x.startswith("error: ")]
    assert len(errors) == 41
    assert re.fullmatch(r"error: … and \d{4} more problems of the same kinds", errors[-1])


# -- issue 35: the cases of the hostile-input run, by case id ------------------------------
def _without_closing_zero(log) -> str:
    return "".join(x for x in log.read_text().splitlines(True) if not x.startswith("zero,11,"))


@pytest.fixture(scope="module")
def partial_patch(tmp_path_factory, log):
    """A --partial run's patch: step 10 solved without its closing zero reading."""
    folder = tmp_path_factory.mktemp("partial")
    cut = folder / "cut.csv"
    cut.write_text(_without_closing_zero(log))
    patch = folder / "patch.toml"
    r = invoke("solve", ROBOT, PLAN, cut, "--partial", "-o", patch)
    assert r.exit_code == 0, r.output
    return cut, patch


UNCHECKED = "step 10 (a1) unchecked: the closing zero reading at θ0 is missing"


def test_pa02_gen_patch_types_the_unchecked_mark(tmp_path, partial_patch):
    """wc.patch, which types the values for SPEC, was byte-identical with and without the
    mark: now it types the mark (θ spelled out in V+'s ASCII), and gen warns."""
    _, patch = partial_patch
    r = invoke("gen", ROBOT, PLAN, "-o", tmp_path / "out", "--patch", patch)
    assert r.exit_code == 0, r.output
    assert f"warning: {patch}: {UNCHECKED}" in r.output
    module = (tmp_path / "out" / "WIRECAL.V2").read_text()
    wc_patch = module[module.index(".PROGRAM wc.patch()") :]
    typed = " ".join(re.findall(r'TYPE "    (.*)"', wc_patch[: wc_patch.index(".END")]))
    assert UNCHECKED.replace("θ", "theta") in typed
    assert "Measure the step(s) again before entering these values." in typed


def test_pa08_export_urdf_and_report_carry_the_unchecked_mark(tmp_path, partial_patch):
    """export-urdf dropped the mark; report refused the log suggesting --partial, which it
    did not have."""
    cut, patch = partial_patch
    urdf = tmp_path / "cal.urdf"
    r = invoke("export-urdf", ROBOT, patch, "-o", urdf)
    assert r.exit_code == 0, r.output
    assert f"<!-- WARNING: {UNCHECKED}" in urdf.read_text()
    refused = invoke("report", ROBOT, PLAN, cut, "-o", tmp_path / "r.html")
    assert refused.exit_code == 2
    assert "or pass --partial" in refused.output
    assert "--partial" in invoke("report", "--help").output


@pytest.mark.slow
def test_pa08_report_shows_a_partial_run(tmp_path, partial_patch):
    cut, _ = partial_patch
    r = invoke("report", ROBOT, PLAN, cut, "--partial", "-o", tmp_path / "r.html")
    assert r.exit_code == 0, r.output
    assert f"warning: {UNCHECKED}" in r.output
    html = (tmp_path / "r.html").read_text()
    assert f"Warning: {UNCHECKED}" in html
    assert "Measure the unchecked step(s) again (their zero check is missing)" in _next_steps(html)


def _next_steps(html: str) -> str:
    """The report's "What to do next" list as text (tags dropped, lines joined)."""
    start = html.index("<h3>What to do next</h3>")
    text = re.sub(r"<[^>]+>", "", html[start : html.index("</ul>", start)])
    return " ".join(text.split())


def _counts_stuck(text: str) -> str:
    """The log with every reading's counts at one value: the gate refuses it."""
    return re.sub(r"^((?:zero|point),(?:[^,]*,){8})[^,]*", r"\g<1>1234.0000", text, flags=re.M)


@pytest.mark.parametrize(
    ("stuck", "steps"),
    [
        (
            False,
            [
                "Write the patch: wirecal solve ROBOT PLAN LOG -o patch.toml",
                "enter the new values",
                "Validate: run the validation programs again after calibration",
            ],
        ),
        (True, ["Do not enter these values: the plausibility gate refused them."]),
    ],
    ids=["passed", "overridden"],
)
def test_the_report_says_what_to_do_next(tmp_path, log, stuck, steps):
    """The report had no "what to do next" and pointed at "the README" (issue 35): its
    list names the commands to run, or, for a refusal overridden, not to enter the values."""
    run = tmp_path / "run.csv"
    run.write_text(_counts_stuck(log.read_text()) if stuck else log.read_text())
    out = tmp_path / "r.html"
    r = invoke("report", ROBOT, PLAN, run, "-o", out, *(["--accept-implausible"] * stuck))
    assert r.exit_code == 0, r.output
    html = out.read_text()
    shown = _next_steps(html)
    assert [step in shown for step in steps] == [True] * len(steps), shown
    assert ("Write the patch" in shown) is not stuck
    assert "README" not in html


def _plus_1mm(text: str, name: str) -> str:
    """Move a parameter's offset and value together by 1 mm (value = nominal + offset holds)."""
    head, marker, rest = text.partition(f"[parameters.{name}]\n")
    block, sep, tail = rest.partition("\n\n")
    block = re.sub(
        r"^(offset|value) = (\S+)$",
        lambda m: f"{m.group(1)} = {float(m.group(2)) + 1.0!r}",
        block,
        flags=re.M,
    )
    return head + marker + block + sep + tail


PATCH_EDITS = {
    "PA03": (
        lambda t: re.sub(r"^unchecked = .*\n", "", t, flags=re.M),
        "unchecked (the mark of the steps solved without their zero check): deleted since "
        "wirecal wrote the patch",
    ),
    "PA04": (
        lambda t: re.sub(r"^unchecked = .*$", "unchecked = []", t, flags=re.M),
        "unchecked (the mark of the steps solved without their zero check): changed",
    ),
    "PA06": (
        lambda t: re.sub(r"^plausibility = .*\n", "", t, flags=re.M),
        "plausibility (the mark that the plausibility gate was overridden): deleted",
    ),
    "PA07": (lambda t: _plus_1mm(t, "a2"), "parameters.a2: changed since wirecal wrote the patch"),
}


@pytest.fixture(scope="module")
def overridden_patch(tmp_path_factory, partial_patch) -> str:
    """The partial run's patch marked overridden and sealed, as wirecal writes it: gen takes it."""
    from wirecal.formats.patch_digest import seal

    text = partial_patch[1].read_text()
    overridden = seal(
        re.sub(r"^plausibility = .*$", 'plausibility = "overridden: x"', text, count=1, flags=re.M)
    )
    folder = tmp_path_factory.mktemp("sealed")
    sealed = folder / "sealed.toml"  # the same patch as wirecal wrote it is taken
    sealed.write_text(overridden)
    assert invoke("gen", ROBOT, PLAN, "-o", folder / "ok", "--patch", sealed).exit_code == 0
    return overridden


@pytest.mark.parametrize("case", PATCH_EDITS)
def test_an_edited_patch_is_refused_naming_the_edit(tmp_path, overridden_patch, case):
    """The patch had no checksum: each of these edits passed gen --patch with exit 0."""
    overridden = overridden_patch
    edit, message = PATCH_EDITS[case]
    edited = tmp_path / "patch.toml"
    edited.write_text(edit(overridden))
    assert edited.read_text() != overridden
    r = invoke("gen", ROBOT, PLAN, "-o", tmp_path / "out", "--patch", edited)
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert f"error: {edited}: {message}" in r.output
    assert "write it again with wirecal solve" in r.output
    assert not (tmp_path / "out").exists()


def test_a_patch_without_its_digest_is_refused(tmp_path, partial_patch):
    text = partial_patch[1].read_text()
    bare = tmp_path / "patch.toml"
    bare.write_text(text[: text.index("\n[digest]")] + "\n")
    r = invoke("export-urdf", ROBOT, bare, "-o", tmp_path / "cal.urdf")
    assert r.exit_code == 2
    assert f"error: {bare}: digest: missing" in r.output


CAPTURES = {
    "TP02": lambda line: f"\x1b[32m{line}\x1b[0m" if line[:1].isalpha() else line,
    "TP03": lambda line: f"\x1b[1;33m{line}\x1b[0m" if line.startswith("#") else line,
    "TP07": lambda line: line.replace(",", "\t") if line[:1].isalpha() else line,
    "TP07b": lambda line: line.replace(",", ",\t"),
    "TP24": lambda line: f"[2026-11-27 05:18:38.123] {line}",
    "TP24b": lambda line: f"05:18:38 | {line}",
}


@pytest.mark.parametrize("case", CAPTURES)
def test_a_capture_is_read_through_what_terminal_loggers_add(log, case):
    """Colour codes, tabs, timestamp prefixes: 'missing steps 1–10 (all points)' before."""
    from wirecal.formats.log import parse_log

    clean = parse_log(log.read_text(), "run.csv")
    captured = "\n".join(map(CAPTURES[case], log.read_text().splitlines())) + "\n"
    got = parse_log(captured, "terminal")
    assert [(r.kind, r.step, r.index, r.counts) for r in got.readings] == [
        (r.kind, r.step, r.index, r.counts) for r in clean.readings
    ]


@pytest.mark.parametrize("width", [40, 41, 55, 64, 71, 72, 80])
def test_tp09_a_capture_folded_at_any_width_of_40_or_more(log, width):
    """At 71 columns or fewer the 72-character '# plan:' line broke the header."""
    from wirecal.formats.capture import fold
    from wirecal.formats.log import parse_log

    text = log.read_text()
    got = parse_log(fold(text.splitlines(), width), "terminal")
    assert got.plan == parse_log(text, "run.csv").plan
    assert len(got.readings) == text.count("\npoint,") + text.count("\nzero,")


@pytest.mark.parametrize("width", [20, 30, 39])
def test_tp09_a_capture_folded_narrower_than_40_names_the_terminal(tmp_path, log, width):
    """TP09 below the widths read: 'columns are 'af37aaf4…'' did not say that the '# plan:'
    line before it was broken by the terminal, nor what to do."""
    from wirecal.formats.capture import fold

    folded = fold(log.read_text().splitlines(), width)
    r = CliRunner().invoke(main, ["solve", str(ROBOT), str(PLAN), "-"], input=folded)
    assert r.exit_code == 2, r.output
    assert re.search(
        rf"<stdin>:\d+: columns are '[^']+'; the column line must be '[^']+': it looks like "
        rf"the rest of line \d+ \('# [^']+'\), broken by a terminal {width} columns wide; "
        "copy the log again from a terminal at least 40 columns wide",
        r.output,
    ), r.output


def test_tp09_a_wrong_column_line_below_a_short_header_is_not_blamed_on_a_terminal(tmp_path, log):
    """The other direction: a column line with spaces for commas below a short header
    line is not taken for its broken end (the '# plan:' line above is wider)."""
    lines = log.read_text().splitlines()
    k = next(i for i, x in enumerate(lines) if x.startswith("kind,"))
    lines[k : k + 1] = ["# a short comment", lines[k].replace(",", " ")]
    k += 1
    bad = tmp_path / "run.csv"
    bad.write_text("\n".join(lines) + "\n")
    r = invoke("solve", ROBOT, PLAN, bad)
    assert r.exit_code == 2, r.output
    assert f"run.csv:{k + 1}: columns are 'kind step index" in r.output
    assert "broken by a terminal" not in r.output


def test_tp02_a_refused_capture_names_what_it_set_aside(tmp_path, log):
    """Every row unreadable: the refusal said only 'missing steps 1–10'."""
    prefixed = "\n".join(
        f"robot> {x}" if x[:1].isalpha() and not x.startswith("kind") else x
        for x in log.read_text().splitlines()
    )
    r = CliRunner().invoke(main, ["solve", str(ROBOT), str(PLAN), "-"], input=prefixed + "\n")
    assert r.exit_code == 2
    assert "the log is incomplete: missing" in r.output
    assert re.search(r"<stdin>: set aside \d+ line\(s\) that are not log rows", r.output)


@pytest.mark.slow
def test_the_twins_console_can_be_rehearsed(tmp_path):
    """simulate --controller --console: what the operator copies, at 40 columns, solves."""
    console = tmp_path / "console.txt"
    r = invoke(
        "simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv", "--controller", "--console",
        console, "--width", 40,
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    lines = console.read_text().splitlines()
    assert max(map(len, lines)) == 40
    assert "# wirecal-log 2" in lines
    solved = CliRunner().invoke(
        main, ["solve", str(ROBOT), str(PLAN), "-"], input=console.read_text()
    )
    assert solved.exit_code == 0, solved.output
    assert "joined" in solved.output


@pytest.mark.slow
def test_rk28_receive_is_bounded_as_every_other_input(tmp_path):
    """A complete log followed by 100 MiB of comments was published (105 MB, exit 0):
    now the run stops at 16 MiB, nothing is published, and the message says why."""
    import socket
    import threading

    from wirecal.app.receive import journal_path, receive
    from wirecal.formats.fileio import MAX_INPUT_BYTES
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.formats.run_token import run_token, token_line
    from wirecal.formats.simulated_log import simulate_log

    ur5 = load_robot(VIPER.parent / "ur5e" / "robot.toml")
    plan = load_plan(VIPER.parent / "ur5e" / "plan.toml", ur5)
    text = simulate_log(ur5, plan, {}, seed=1, counter_start=1000.0)
    flood = ("# " + "x" * 1000 + "\n") * (MAX_INPUT_BYTES // 1000 + 100)
    ports, out = [], tmp_path / "run.csv"
    result = {}

    def serve():
        result["r"] = receive(0, out, ur5, plan, timeout_s=20, on_listening=ports.append)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    while not ports:
        thread.join(0.05)
    hello = token_line(run_token(ur5, plan.fingerprint())) + "\n"
    with socket.create_connection(("127.0.0.1", ports[0]), timeout=20) as s:
        try:
            s.sendall((hello + text + flood + "# end\n").encode())
        except OSError:
            pass  # the receiver stopped reading and closed: what it should do
    thread.join(30)
    r = result["r"]
    assert not r.complete
    assert not out.exists()
    assert "more than 16 MiB received" in r.stopped
    assert journal_path(out).stat().st_size <= MAX_INPUT_BYTES


def _import_refused(tmp_path, text: str):
    """Import ``text`` as a URDF: refused cleanly (status 2), nothing written; its name and
    the command's output."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(text)
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml")
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert not (tmp_path / "r.toml").exists()
    return urdf, r.output


URDF_UNITS = {
    "ND22": (
        ('rpy="1.5707963267948966 0 0"', 'rpy="-90 0 0"'),
        r"joint '\w+': origin rpy value 1 is -90, beyond ±2π: URDF angles are radians; "
        r"written in degrees\?",
    ),
    "ND24": (
        ('lower="-2.5" upper="2.5"', 'lower="-170" upper="170"'),
        r"joint '\w+': limit lower=-170, beyond ±4π: URDF limits are radians",
    ),
    "ND26": (
        ('xyz="0 0 0.3"', 'xyz="0 0 300"'),
        r"joint '\w+': origin xyz 0 0 300 is beyond 10 m: URDF lengths are metres; written "
        r"in millimetres\?",
    ),
}


@pytest.mark.parametrize("case", URDF_UNITS)
def test_urdf_units_are_checked_naming_joint_and_attribute(tmp_path, case):
    """Degrees imported as radians without a word (ND22); the others blamed the output."""
    (old, new), message = URDF_UNITS[case]
    _, output = _import_refused(tmp_path, URDF.read_text().replace(old, new, 1))
    assert re.search(message, output), output


@pytest.mark.parametrize(("velocity", "joints"), [("180", 1), ("1e308", 1), ("1e308", 6)])
def test_nd24_urdf_speeds_in_deg_s_are_named_by_joint_and_attribute(tmp_path, velocity, joints):
    """ND24's neighbour for <limit velocity>: 180 (deg/s written for rad/s) was blamed on
    the output file ('r.toml: kinematics.joint_speed_deg_s: value 1 is 10313.24…'), 1e308
    on one joint too ('value 1 is inf'), and 1e308 on every joint ended in a traceback
    (OverflowError in the placeholder-speed check)."""
    text = URDF.read_text().replace('velocity="3.0"', f'velocity="{velocity}"', joints)
    urdf, output = _import_refused(tmp_path, text)
    assert output == (
        f"error: {urdf}: joint 'j1': limit velocity={float(velocity):g}, beyond 174.5 rad/s "
        "(10000 deg/s): URDF velocities are rad/s; written in deg/s? Convert them (× π/180) "
        "and import again\n"
    )


def test_a_fast_urdf_joint_in_rad_s_is_imported(tmp_path):
    """The valid neighbour: 17.45 rad/s (1000 deg/s, a fast wrist) imports as 1000 deg/s."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(URDF.read_text().replace('velocity="3.0"', 'velocity="17.453292519943"'))
    out = tmp_path / "r.toml"
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", out)
    assert r.exit_code == 0, r.output
    speeds = re.search(r"^joint_speed_deg_s = \[(.*)\]", out.read_text(), re.M)
    assert speeds is not None
    assert [float(v) for v in speeds.group(1).split(",")] == pytest.approx([1000.0] * 6, abs=1e-6)


def test_nd26_a_robot_file_the_urdf_makes_too_long_names_the_urdf(tmp_path):
    """ND26's neighbour: each origin within the URDF's 10 m, yet 9.99 m and the next joint's
    offsets make a DH d of 10 020 mm, beyond the robot file's 10 000: the refusal named the
    output file ('r.toml: kinematics.dh[1]: value 4 is 10020.0'), which the user cannot fix."""
    urdf, output = _import_refused(tmp_path, URDF.read_text().replace("0 0 0.3", "0 0 9.99", 1))
    out = tmp_path / "r.toml"
    lines = output.splitlines()
    assert lines[0] == (
        f"error: {urdf} (as the robot file {out}): kinematics.dh[1]: value 4 is 10020.0; "
        "give a number within ±10000 mm"
    )
    assert lines[-1] == (
        f"error: {urdf}: the robot file made from it fails the check(s) above: its values "
        "are the URDF's (joint origins in m, limits in rad, velocities in rad/s) and, in "
        "[encoder], the options --mm-per-count, --range-mm and --counter-bits; correct them "
        "and import again"
    )


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ("--range-mm=1e9", "encoder.range_mm: is 1000000000.0; give a number > 0 and ≤ 100000 mm"),
        ("--mm-per-count=1e-300", "encoder.mm_per_count: is 1e-300 mm"),  # R15's message
    ],
)
def test_nd26_an_encoder_option_the_robot_file_refuses_names_the_option(tmp_path, option, message):
    """The import's encoder options pass the robot file's checks too; --mm-per-count 1e-300
    was written as 0.0 (an absolute rounding) and refused as 'must not be zero'."""
    out = tmp_path / "r.toml"
    r = invoke("import-urdf", URDF, "--tip", "wire", option, "-o", out)
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert f"error: {URDF} (as the robot file {out}): {message}" in r.output
    assert "must not be zero" not in r.output
    assert "the options --mm-per-count, --range-mm and --counter-bits" in r.output
    assert not out.exists()


def test_a_fine_encoder_scale_is_written_to_its_digits(tmp_path):
    """The valid neighbour: a 1.234567e-05 mm/count encoder is written as given."""
    out = tmp_path / "r.toml"
    scale = ["--mm-per-count=1.234567e-05", "--counter-bits=32"]
    r = invoke("import-urdf", URDF, "--tip", "wire", *scale, "-o", out)
    assert r.exit_code == 0, r.output
    assert "mm_per_count = 1.234567e-05\n" in out.read_text()


@pytest.mark.parametrize("xyz", ["50 0 0", "1e306 0 0"])
def test_nd21_nd26_an_inertial_origin_in_millimetres_is_named(tmp_path, xyz):
    """ND21's and ND26's neighbour in <inertial>: a centre of mass at 50 m was blamed on
    gravity.link_com_mm beside a second, wrong problem ('give link_mass_kg and link_com_mm
    together'); 1e306 m overflowed (RuntimeWarning) into 'value 1 is inf'."""
    inertial = (
        f'<link name="l2"><inertial><origin xyz="{xyz}"/><mass value="3"/>'
        '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'
    )
    urdf, output = _import_refused(
        tmp_path, URDF.read_text().replace('<link name="l2"/>', inertial)
    )
    shown = " ".join(f"{float(v):g}" for v in xyz.split())
    assert output == (
        f"error: {urdf}: link 'l2': <inertial> origin xyz {shown} is beyond 10 m: URDF "
        "lengths are metres; written in millimetres? Divide them by 1000 and import again\n"
    )


def _with_collision(geometry: str) -> str:
    collision = f'<link name="l2"><collision><geometry>{geometry}</geometry></collision></link>'
    return URDF.read_text().replace('<link name="l2"/>', collision, 1)


@pytest.mark.parametrize(
    ("geometry", "reach"),
    [('<box size="300 300 300"/>', "259.8"), ('<cylinder radius="1e306" length="1"/>', "inf")],
)
def test_nd26_collision_geometry_in_millimetres_is_named(tmp_path, geometry, reach):
    """ND26's neighbour in <collision>: a box of 300 (mm meant, metres read) was dropped as
    'no readable geometry' and link 2 got the length rule's 61 mm radius — a capsule far
    thinner than the body the URDF meant (282 mm when in metres), so plan could route the
    wire through the arm; a radius of 1e306 printed numpy's RuntimeWarnings."""
    urdf, output = _import_refused(tmp_path, _with_collision(geometry))
    assert output == (
        f"error: {urdf}: link 'l2': its geometry reaches {reach} m from the link's origin, "
        "beyond 10 m: URDF lengths are metres; written in millimetres? Divide them by 1000 "
        '(a mesh in mm: scale="0.001 0.001 0.001") and import again\n'
    )


def test_collision_geometry_only_beyond_the_link_ends_is_named(tmp_path):
    """A 0.1 m box (metres, as URDF lengths are) 0.3 m behind link 2's origin, past its
    ends: the import said 'all from link lengths (no readable geometry …)' of geometry it had
    read. Its unit cannot be told from where it lies (housings stand past joints): the
    import names the link and where its geometry is instead."""
    urdf = tmp_path / "arm.urdf"
    collision = (
        '<link name="l2"><collision><origin xyz="-0.3 0 0"/><geometry><box size="0.1 0.1 0.1"/>'
        "</geometry></collision></link>"
    )
    urdf.write_text(URDF.read_text().replace('<link name="l2"/>', collision, 1))
    out = tmp_path / "r.toml"
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", out)
    assert r.exit_code == 0, r.output
    assert (
        "note: link radii 46, 61, 51, 46, 46 mm: all from link lengths (no readable geometry "
        "beside them; link(s) 2: geometry read, but only beyond the link's ends; see "
        "[geometry])" in r.output
    )
    text = out.read_text()
    assert "# link 2: its links' 8 geometry point(s) lie beyond its ends, none beside it" in text
    assert "# link 1: no collision or visual geometry beside it" in text


def test_collision_geometry_in_metres_sets_the_radius(tmp_path):
    """The valid neighbour: the same box in metres is read, and widens link 2."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(_with_collision('<box size="0.3 0.3 0.3"/>'))
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml")
    assert r.exit_code == 0, r.output
    assert "link radii 46, 282, 51, 46, 46 mm" in r.output


def test_nl49_a_reference_reading_with_a_large_spread_is_refused(tmp_path):
    robot, log_path = _with_gauge(tmp_path)
    lines = log_path.read_text().splitlines()
    k = next(i for i, x in enumerate(lines) if x.startswith("reference,"))
    cells = lines[k].split(",")
    cells[11] = str(round(127 / MM_PER_COUNT))  # a 127 mm spread of the samples
    lines[k] = ",".join(cells)
    log_path.write_text("\n".join(lines) + "\n")
    r = invoke("solve", robot, PLAN, log_path)
    outcome_is_clean(r)
    assert r.exit_code == 2
    assert re.search(
        rf"gauge\.csv:{k + 1}: spread of \d+ samples is \d+ counts \(127\.0\d\d mm > 0\.1 mm\): "
        "the wire tip moved in its nest; seat it again and repeat the reference step",
        r.output,
    ), r.output


def test_r40_a_toml_file_with_a_byte_order_mark_is_read(tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_bytes(b"\xef\xbb\xbf" + ROBOT.read_bytes())
    assert invoke("psi", robot, PLAN).exit_code == 0


@pytest.mark.parametrize(
    "args",
    [
        ["simulate", ROBOT, PLAN, "-o", "-"],  # S05
        ["solve", ROBOT, PLAN, "LOG", "-o", "-"],  # NO07
        ["export-urdf", ROBOT, "-o", "-"],
        ["report", ROBOT, PLAN, "LOG", "-o", "-"],
    ],
    ids=lambda a: " ".join(map(str, a[:1])),
)
def test_s05_no07_output_dash_is_refused_not_a_file_named_dash(tmp_path, log, args):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        r = invoke(*[log if a == "LOG" else a for a in args])
    finally:
        os.chdir(cwd)
    assert r.exit_code == 2
    assert "'-' (standard output) cannot take this output" in r.output
    assert list(tmp_path.iterdir()) == []


def test_ng09_help_lists_every_exit_status():
    r = invoke("--help")
    assert "3 the" in r.output
    assert "plausibility gate refused" in " ".join(r.output.split())


def test_ng11_a_closed_pipe_is_not_an_error():
    """'| head -1': 'error: file: Broken pipe', exit 2."""
    code = "from wirecal.cli.main import main; main()"
    p = subprocess.run(
        f"{sys.executable} -c '{code}' psi {ROBOT} {PLAN} | head -1; "
        "echo status=${PIPESTATUS[0]}",
        shell=True,
        executable="/bin/bash",
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert "status=0" in p.stdout, p.stderr
    assert "error" not in p.stderr.lower(), p.stderr


def test_ng12_wrote_counts_the_points_logged(tmp_path):
    r = invoke("simulate", ROBOT, PLAN, "-o", tmp_path / "a.csv", "--stop-after", 40)
    logged = (tmp_path / "a.csv").read_text().count("\npoint,")
    assert logged < 69
    assert f"({logged} points)" in r.output


def test_ng14_no_range_of_none_in_any_help():
    for command in COMMANDS:
        assert "None]" not in invoke(command, "--help").output, command


def test_receive_and_validate_take_positionals_and_the_old_options(tmp_path):
    """Every other command takes ROBOT PLAN as positionals; the options stay as aliases."""
    plane = tmp_path / "plane.csv"
    both = invoke("validate", ROBOT, "plane", plane)
    old = invoke("validate", "plane", plane, "--robot", ROBOT)
    assert both.exit_code == old.exit_code == 2  # the log is missing: read past the shape
    assert "plane.csv" in both.output
    assert "plane.csv" in old.output
    twice = invoke("receive", ROBOT, PLAN, "--robot", PLAN, "-o", tmp_path / "r.csv")
    assert twice.exit_code == 2
    assert "ROBOT given twice" in twice.output
    assert "receive [OPTIONS] [ROBOT] [PLAN]" in invoke("receive", "--help").output


def test_demo_refuses_to_overwrite_before_working(tmp_path):
    """The demo worked 15–20 s before refusing: now at once."""
    import time

    (tmp_path / "report.html").write_text("an earlier report\n")
    t = time.perf_counter()
    r = invoke("demo", "-o", tmp_path)
    assert r.exit_code == 2
    assert "report.html: exists; choose another name or pass --force" in r.output
    assert time.perf_counter() - t < 5  # the programs alone take 15 s and more
    assert (tmp_path / "report.html").read_text() == "an earlier report\n"


WIRECAL = [sys.executable, "-c", "from wirecal.cli.main import main; main()"]


@pytest.mark.slow
@pytest.mark.parametrize("delay_s", [0.4, 0.8, 1.2, 1.6])
def test_sigterm_leaves_no_temporary_file(tmp_path, log, delay_s):
    """SIGTERM during solve -o / export-urdf left empty hidden .tmp files (2 of 8 tries)."""
    import signal
    import time

    runs = [
        [*WIRECAL, "solve", ROBOT, PLAN, log, "-o", tmp_path / "patch.toml"],
        [*WIRECAL, "export-urdf", ROBOT, "-o", tmp_path / "arm.urdf"],
    ]
    for args in runs:
        p = subprocess.Popen(list(map(str, args)), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        time.sleep(delay_s)
        p.send_signal(signal.SIGTERM)
        _, err = p.communicate(timeout=60)
        assert p.returncode in (0, 128 + signal.SIGTERM, -signal.SIGTERM), err
        assert b"Traceback" not in err
        left = [f.name for f in tmp_path.iterdir() if f.name.startswith(".")]
        assert left == [], left
        if p.returncode == 128 + signal.SIGTERM:
            assert b"stopped (SIGTERM); nothing written" in err
            assert not any(tmp_path.iterdir())
        for f in tmp_path.iterdir():
            f.unlink()


@pytest.mark.slow
def test_sigint_stops_the_demo_within_a_second(tmp_path):
    """Ctrl-C took 9.5–11 s to stop the demo (its second process ran on)."""
    import signal
    import time

    p = subprocess.Popen(
        [*WIRECAL, "demo", "-o", str(tmp_path / "demo")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        # Ctrl-C as a terminal sends it, even where this test runs in a background job
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        start_new_session=True,
    )
    assert p.stdout is not None
    for line in p.stdout:  # the progress lines, echoed as they come
        if line.startswith("[2/7]"):  # the second process is at work too
            break
    time.sleep(0.5)
    t = time.perf_counter()
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=30)  # EOF: every process holding the pipes has ended
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGKILL)  # whatever is left of the demo's processes
    stopped_s = time.perf_counter() - t
    assert p.returncode == 128 + signal.SIGINT, err
    assert "Fatal Python error" not in err
    assert "Traceback" not in err
    assert stopped_s < 2.0  # 1 s on a quiet machine; the CI machine is shared
    assert not (tmp_path / "demo").exists()


def test_a_validation_setup_in_another_frame_0_is_refused_clearly(viper):
    """The Viper's validation.toml under a URDF import's frame 0 (floor at z = 0): 209
    floor collisions before; now one line per place below the floor, naming frame 0."""
    from dataclasses import replace

    from wirecal.formats.validation_files import load_setup
    from wirecal.solver.errors import WirecalError
    from wirecal.solver.validation.design import plate_grid

    imported = replace(viper, cell=replace(viper.cell, floor_z_mm=0.0))
    with pytest.raises(WirecalError) as info:
        plate_grid(imported, load_setup(VIPER / "validation.toml"))
    assert len(info.value.problems) == 2
    assert (
        "configuration.encoder_mm: z -150 mm lies below the robot file's floor"
        in (info.value.problems[0])
    )
    assert "measure it again in this robot file's frame 0" in info.value.problems[1]
    plate_grid(viper, load_setup(VIPER / "validation.toml"))  # the shipped pair still fits


def _solve_text(tmp_path, text: str | bytes):
    path = tmp_path / "run.csv"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    r = invoke("solve", ROBOT, PLAN, path)
    outcome_is_clean(r)
    assert r.exit_code == 2
    return r.output


def test_l06_quoted_lines_are_named(tmp_path, log):
    quoted = "\n".join(f'"{x}"' for x in log.read_text().splitlines()) + "\n"
    out = _solve_text(tmp_path, quoted)
    assert "the first line is '\"# wirecal-log 2\"': lines and fields in double quotes" in out


def test_l06_quoted_fields_below_unquoted_comments_are_named(tmp_path, log):
    """L06's neighbour: every field quoted, the '#' lines not (a script's export): 'columns
    are '"kind","step",…'; the column line must be 'kind,step,…'' left the quotes unnamed."""
    lines = log.read_text().splitlines()
    quoted = [x if x.startswith("#") else ",".join(f'"{c}"' for c in x.split(",")) for x in lines]
    out = _solve_text(tmp_path, "\n".join(quoted) + "\n")
    column_line = next(k for k, x in enumerate(lines) if x.startswith("kind,")) + 1
    rows = sum(1 for x in lines if not x.startswith("#"))
    assert out == (
        f"error: {tmp_path / 'run.csv'}:{column_line}: fields are in double quotes on {rows} "
        "line(s): a spreadsheet re-saved the file; use the file as written, or save it as "
        "plain CSV without quotes\n"
    )


def test_a_wrong_column_line_in_quotes_is_still_named_as_columns(tmp_path, log):
    """The other direction: quotes around a column line that is wrong beyond its quotes
    keep the columns message, which shows what the line must be."""
    text = log.read_text()
    line = next(x for x in text.splitlines() if x.startswith("kind,"))
    wrong = ",".join(f'"{c}"' for c in line.replace("counts", "count").split(","))
    out = _solve_text(tmp_path, text.replace(line, wrong, 1))
    assert "the column line must be 'kind,step,index," in out
    assert "fields are in double quotes" not in out


def test_nt14_utf16_is_named(tmp_path, log):
    out = _solve_text(tmp_path, log.read_text().encode("utf-16-le"))
    assert "UTF-16 text; save it as UTF-8 (a wirecal log is plain UTF-8 text)" in out
    assert len(out.splitlines()) == 1


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le"])
@pytest.mark.parametrize("which", ["robot file", "plan file"])
def test_nt14_a_toml_file_in_utf16_is_named(tmp_path, which, encoding):
    """NT14's neighbour: a robot file or plan saved as UTF-16 (Windows' "Unicode") was
    'not UTF-8 text (byte 0)', the encoding not named as it is for a log."""
    source = ROBOT if which == "robot file" else PLAN
    bad = tmp_path / source.name
    bad.write_bytes(source.read_text().encode(encoding))
    args = [bad, PLAN] if which == "robot file" else [ROBOT, bad]
    r = invoke("psi", *args)
    assert r.exit_code == 2, r.output
    assert r.output == (
        f"error: {bad}: UTF-16 text; save it as UTF-8 (a {which} is plain UTF-8 text)\n"
    )


def test_a_toml_file_with_non_ascii_utf8_is_still_read(tmp_path):
    """The valid neighbour of NT14: UTF-8 beyond ASCII (a name with 'ö', a comment with
    'θ₀') reads as before."""
    robot = tmp_path / "robot.toml"
    text = re.sub(
        r'^name = ".*"$', 'name = "Viper s650 (Kärcher)"', ROBOT.read_text(), count=1, flags=re.M
    )
    robot.write_text("# θ₀ and Ψ, µm\n" + text, encoding="utf-8")
    plan = tmp_path / "plan.toml"
    plan.write_text(
        re.sub(
            r'^robot = ".*"$',
            'robot = "Viper s650 (Kärcher)"',
            PLAN.read_text(),
            count=1,
            flags=re.M,
        ),
        encoding="utf-8",
    )
    r = invoke("psi", robot, plan)
    assert r.exit_code == 0, r.output


def test_nl34_a_version_1_header_over_version_2_rows_is_one_problem(tmp_path, log):
    text = log.read_text().replace("# wirecal-log 2", "# wirecal-log 1", 1)
    text = text.replace(",t_s,settle_s\n", "\n", 1)
    out = _solve_text(tmp_path, text)
    assert re.search(r"\d+ rows have 14 fields where the column line names 12", out), out
    assert "has 14 fields" not in out


def test_nl34_a_version_1_first_line_over_a_version_2_column_line_is_named(tmp_path, log):
    """Only the first line says version 1: 'the column line must be …' (version 1's) sent
    the user to change the column line of a version 2 log instead of its first line."""
    text = log.read_text().replace("# wirecal-log 2", "# wirecal-log 1", 1)
    out = _solve_text(tmp_path, text)
    assert (
        "that is version 2's column line below a first line of version 1; make them agree "
        "(the first line '# wirecal-log 2' if the rows are version 2's)"
    ) in " ".join(out.split()), out


@pytest.mark.parametrize("command", ["psi", "solve"], ids=["R15", "R15b"])
def test_r15_a_tiny_mm_per_count_is_named_as_the_cause(tmp_path, log, command):
    """R15b: solve with a log refused the robot file with R15's 300-digit count too."""
    robot = tmp_path / "r.toml"
    robot.write_text(re.sub(r"mm_per_count = \S+", "mm_per_count = 1e-300", ROBOT.read_text()))
    r = invoke(command, robot, PLAN, *([log] if command == "solve" else []))
    assert r.exit_code == 2
    assert "encoder.mm_per_count: is 1e-300 mm" in r.output
    assert len(max(r.output.splitlines(), key=len)) < 300  # no 300-digit count


def test_nx19_max_exit_deg_in_radians_is_named(tmp_path):
    robot = tmp_path / "r.toml"
    robot.write_text(
        ROBOT.read_text().replace(
            'exit = "point"\n',
            'exit = "eyelet"\naxis = [0.0, 0.0, 1.0]\nmax_exit_deg = 1.5708\n'
            "exit_edge_radius_mm = 1.0\n",
        )
    )
    r = invoke("psi", robot, PLAN)
    assert r.exit_code == 2
    assert "encoder.max_exit_deg: is 1.5708: that is 90 deg in radians; give degrees" in r.output


def _plan_in_radians(scale: float) -> str:
    """The paper plan with every angle (θ0, points, vias) times ``scale``."""
    vector = re.compile(r"\[(-?[\d.]+(?:, -?[\d.]+){5})\]")
    return vector.sub(
        lambda m: "[" + ", ".join(f"{float(v) * scale:.6f}" for v in m.group(1).split(",")) + "]",
        PLAN.read_text(),
    )


def test_nx19_a_plan_in_radians_is_named_once(tmp_path):
    """NX19's neighbour for plans: a plan typed in radians was refused point by point as
    'the wire length there is 0.938 mm (below 1 mm): the point (nearly) coincides with
    θ0', radians not named."""
    plan = tmp_path / "plan.toml"
    plan.write_text(_plan_in_radians(np.pi / 180))
    r = invoke("psi", ROBOT, plan)
    assert r.exit_code == 2
    assert r.output == (
        f"error: {plan}: theta0_deg: θ0 and every point of the plan are within ±2π: they look "
        "like radians (θ0 would be [0, -90, 210, -90, 0, -90] deg); give degrees\n"
    )


def test_a_plan_in_degrees_near_zero_is_not_called_radians(tmp_path):
    """The valid neighbour: the plan in degrees still loads; one point within ±2π of zero
    on every joint (a small move) is a point, not radians."""
    plan = tmp_path / "plan.toml"
    plan.write_text(_plan_in_radians(1.0))
    assert invoke("psi", ROBOT, plan).exit_code == 0


VIPER_RAD_S = "joint_speed_deg_s = [5.72, 5.24, 6.54, 6.54, 6.54, 10.47]"
"""The Viper s650's speeds (328, 300, 375, 375, 375, 600 °/s) written in rad/s."""


def test_gen_refuses_joint_speeds_in_rad_s_until_confirmed(tmp_path):
    """A new case beside NX19 and CL24 (units of the robot file): speeds typed in rad/s were
    taken as deg/s without a word, and gen wrote every move at SPEED 100 — the shipped file
    needs SPEED 12.6 … 99.2 to keep the wire within its speed limit: the real wire would run
    up to 8 times faster than the encoder allows. gen now refuses, naming the key and both
    ways out; psi and plan (estimates only) still run."""
    robot = tmp_path / "robot.toml"
    robot.write_text(
        re.sub(r"^joint_speed_deg_s = .*$", VIPER_RAD_S, ROBOT.read_text(), flags=re.M)
    )
    assert invoke("psi", robot, PLAN).exit_code == 0
    r = invoke("gen", robot, PLAN, "-o", tmp_path / "out")
    assert r.exit_code == 2, r.output
    assert (
        f"error: {robot}: kinematics.joint_speed_deg_s: joint(s) 1 (5.72 °/s), 2 (5.24 °/s), "
        "3 (6.54 °/s), 4 (6.54 °/s), 5 (6.54 °/s), 6 (10.47 °/s) are slower than 60 °/s, "
        "implausible for an industrial arm: rad/s written as deg/s? gen times every move "
        "from these speeds, and speeds below the real ones let the wire run faster than the "
        "encoder allows; give the data sheet's maximum joint speeds in deg/s, or set "
        "joint_speed_confirmed = true if they are right"
    ) in " ".join(r.output.split()), r.output
    assert not (tmp_path / "out").exists()


def test_slow_joint_speeds_confirmed_are_used(tmp_path):
    """The valid neighbour: a heavy arm's slow joints, confirmed, generate (slower moves)."""
    robot = tmp_path / "robot.toml"
    slow = "joint_speed_deg_s = [45.0, 40.0, 50.0, 90.0, 90.0, 120.0]\njoint_speed_confirmed = true"
    robot.write_text(re.sub(r"^joint_speed_deg_s = .*$", slow, ROBOT.read_text(), flags=re.M))
    r = invoke("gen", robot, PLAN, "-o", tmp_path / "out")
    assert r.exit_code == 0, r.output
    module = (tmp_path / "out" / "WIRECAL.V2").read_text()
    speeds = [float(v) for v in re.findall(r"^\s*SPEED ([\d.]+) ALWAYS", module, re.M)]
    assert len(speeds) > 50
    assert max(speeds) <= 100


def test_slow_speeds_given_to_import_urdf_are_written_confirmed(tmp_path):
    """The speeds given with --joint-speed-deg-s are the user's: slow ones are written with
    joint_speed_confirmed = true, so that gen does not ask again."""
    from wirecal.formats.robot_file import load_robot

    out = tmp_path / "r.toml"
    speeds = "--joint-speed-deg-s=45,40,50,90,90,120"
    r = invoke("import-urdf", URDF, "--tip", "wire", speeds, "-o", out)
    assert r.exit_code == 0, r.output
    assert "\njoint_speed_confirmed = true\n" in out.read_text()
    assert load_robot(out).speed_problem() is None


@pytest.mark.parametrize("point", ["[0.0, 0.0, 0.0]", "[0.0, 0.0, 1.5]"])
def test_a_tool_point_at_or_near_the_flange_centre_is_read(tmp_path, point):
    """The valid neighbours: a wire at the flange's centre, or 1.5 mm from it."""
    robot = tmp_path / "robot.toml"
    text = re.sub(r"^point_mm = .*$", f"point_mm = {point}", ROBOT.read_text(), flags=re.M)
    robot.write_text(text)
    r = invoke("psi", robot, PLAN)
    outcome_is_clean(r)
    assert "metres" not in r.output


@pytest.mark.slow  # two Viper plans: 3.8 s of CPU alone
def test_plan_says_when_points_is_fewer_than_the_steps_keep(tmp_path):
    """A new case beside C17 (plan's options): --points 5 wrote a plan of 20 points without
    a word (each of the Viper's 10 steps keeps at least 2); --points 25 is honoured."""
    r = invoke("plan", ROBOT, "--points", 5, "-o", tmp_path / "p.toml")
    assert r.exit_code == 0, r.output
    assert (
        "note: --points 5: each of the plan's 10 steps keeps at least 2 points, so it has 20"
    ) in r.output
    r = invoke("plan", ROBOT, "--points", 25, "-o", tmp_path / "q.toml")
    assert r.exit_code == 0, r.output
    assert "note: --points" not in r.output
    assert "(25 points, 0 via points)" in r.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--width", 40], "--width folds the twin's console: give --console FILE too"),
        (["--outlier-mm", 5], "--outlier-mm sizes the outliers: give --outliers N too"),
    ],
    ids=["width", "outlier-mm"],
)
def test_simulate_refuses_an_option_it_would_ignore(tmp_path, args, message):
    """A new case beside S05 (simulate's options): --width without --console and
    --outlier-mm without --outliers were ignored without a word (exit 0), where --console
    without --controller is refused."""
    r = invoke("simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv", *args)
    assert r.exit_code == 2
    assert f"error: {message}" in r.output
    assert list(tmp_path.iterdir()) == []


def test_simulate_takes_the_options_with_what_they_apply_to(tmp_path):
    """The valid neighbour: --outlier-mm with --outliers, and the defaults, still run."""
    r = invoke(
        "simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv", "--outliers", 2, "--outlier-mm", 5
    )
    assert r.exit_code == 0, r.output


def test_refine_scale_without_a_reference_step_is_refused(tmp_path, log):
    """A new case beside the options above: solve --refine-scale on a log without a
    reference step ran without a word and without refining anything. Refused before the
    log is read when the robot file declares no gauge (AU02)."""
    r = invoke("solve", ROBOT, PLAN, log, "--refine-scale")
    assert r.exit_code == 2
    assert (
        "error: --refine-scale refines the scale the reference gauge measured; "
        f"{ROBOT} declares no gauge ([encoder] reference_length_mm), so its logs have no "
        "reference step: leave it out"
    ) in " ".join(r.output.split())


def test_refine_scale_with_a_reference_step_runs(tmp_path):
    """The valid neighbour: a log with its reference step takes --refine-scale."""
    robot, log_path = _with_gauge(tmp_path)
    r = invoke("solve", robot, PLAN, log_path, "--refine-scale")
    assert r.exit_code == 0, r.output


def _appended(text: str, table: str) -> str:
    """The Viper's robot file text with ``table`` added before [gravity]."""
    return text.replace("\n[gravity]", table + "\n[gravity]", 1)


METRES = {
    # case: (the robot file's edit, the key and values named, the example given)
    "tool point": (
        lambda t: re.sub(r"^point_mm = .*$", "point_mm = [-0.06, 0.0, 0.05]", t, flags=re.M),
        "tool.point_mm: [-0.06, 0, 0.05]",
        " (e.g. [-60, 0, 50])",
    ),
    "link radii": (
        lambda t: re.sub(
            r"^link_radius_mm = .*$",
            "link_radius_mm = [0.07, 0.07, 0.055, 0.045, 0.037]",
            t,
            flags=re.M,
        ),
        "geometry.link_radius_mm: [0.07, 0.07, 0.055, 0.045, 0.037]",
        "",
    ),
    "cell box": (
        lambda t: _appended(
            t,
            '\n[[cell.box]]\nname = "fence"\nmin_mm = [0.4, -0.5, -0.335]\n'
            "max_mm = [0.6, 0.5, 0.5]\n",
        ),
        "cell.box[2]: [0.4, -0.5, -0.335, 0.6, 0.5, 0.5]",
        "",
    ),
    "encoder housing": (
        lambda t: _appended(
            t,
            "\n[cell.encoder_housing]\ndirection = [0.0, 0.0, -1.0]\nlength_mm = 0.12\n"
            "radius_mm = 0.05\n",
        ),
        "cell.encoder_housing: [0.12, 0.05]",
        "",
    ),
}


@pytest.mark.parametrize("case", METRES)
def test_ud04_lengths_in_metres_in_the_robot_file_are_named(tmp_path, case):
    """UD04's neighbours in the robot file, each taken as mm without naming the unit: a tool
    point of [-0.06, 0, 0.05] (the plan was blamed: 'the wire length there is 0.0459 mm …
    coincides with θ0'); link radii of 0.07 … (0.07 mm capsules for the wire clearance and
    the collision checks, and gen wrote the programs); a fence box 0.4–0.6 m (a 0.2 mm box
    at the base that link 1 reached into on every move: 80 psi warnings, a collision per
    gen point); an encoder housing of 0.12 by 0.05 m (a 0.12 mm cylinder, no obstacle)."""
    edit, named, example = METRES[case]
    robot = tmp_path / "robot.toml"
    robot.write_text(edit(ROBOT.read_text()))
    r = invoke("psi", robot, PLAN)
    assert r.exit_code == 2
    assert r.output == (
        f"error: {robot}: {named}: every value under 1 mm: that looks like metres; give it in "
        f"mm{example}\n"
    )


@pytest.mark.parametrize("value", ["1.25", "0.5"])
def test_an_encoder_range_in_metres_is_named(tmp_path, value):
    """UD04's neighbour in [encoder]: range_mm = 1.25 for a 1250 mm wire was read as
    1.25 mm, and every message after it said 'range_mm 1.25' (gen: 'the nominal wire is
    61.5 mm long, beyond the encoder's range_mm 1.25') without naming the unit."""
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT.read_text().replace("range_mm = 1250.0", f"range_mm = {value}"))
    r = invoke("psi", robot, PLAN)
    assert r.exit_code == 2
    assert r.output == (
        f"error: {robot}: encoder.range_mm: is {value}: a wire under 10 mm spans no arm; "
        f"that looks like metres ({float(value) * 1000:g} mm); give the encoder's range in mm\n"
    )


def test_a_short_encoder_range_in_mm_is_read(tmp_path):
    """The valid neighbour: a short encoder's 50 mm range is mm, not metres."""
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT.read_text().replace("range_mm = 1250.0", "range_mm = 50.0"))
    r = invoke("psi", robot, PLAN)
    assert r.exit_code == 0, r.output
    assert "metres" not in r.output


def test_a_cell_box_in_mm_at_the_origin_is_read(tmp_path):
    """The valid neighbour: a box from the origin (a corner at 0, 0, 0) in mm."""
    robot = tmp_path / "robot.toml"
    box = (
        '\n[[cell.box]]\nname = "fence"\nmin_mm = [0.0, 0.0, 0.0]\nmax_mm = [600.0, 500.0, 500.0]\n'
    )
    robot.write_text(_appended(ROBOT.read_text(), box))
    r = invoke("psi", robot, PLAN)
    outcome_is_clean(r)
    assert "metres" not in r.output
    assert "box 'fence'" in r.output  # read, and in the arm's way


def test_c17_theta0_nan_is_refused_as_an_option():
    r = invoke("plan", ROBOT, "--theta0", "nan,-90,210,-90,0,-90")
    assert r.exit_code == 2
    assert "--theta0 'nan,-90,210,-90,0,-90': 'nan' is not an angle: give 6 joint" in r.output


@pytest.mark.parametrize(("value", "bad"), [("0,-90,inf,-90,0,-90", "inf"), ("0,x,1", "x")])
def test_c17_the_value_that_is_no_angle_is_named(value, bad):
    """C17: '--theta0 nan,…' gave 'give 6 joint angles', not which of the six is wrong."""
    r = invoke("plan", ROBOT, "--theta0", value)
    assert r.exit_code == 2
    assert f"--theta0 {value!r}: {bad!r} is not an angle" in r.output


@pytest.mark.parametrize(
    "loose", [["mount"], [f"loose{k}" for k in range(8)]], ids=["ND07", "ND12"]
)
def test_nd07_a_second_root_is_not_in_the_way(tmp_path, loose):
    """'2 root links (mount, …)' (ND07), '9 root links …' (ND12); 'name one with --base':
    the tip's own tree is the chain, whatever loose links the file has beside it."""
    urdf = tmp_path / "arm.urdf"
    links = "".join(f'<link name="{name}"/>\n' for name in loose)
    urdf.write_text(URDF.read_text().replace("</robot>", f"{links}</robot>"))
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml")
    assert r.exit_code == 0, r.output


@pytest.mark.parametrize(
    ("point", "message"),
    [
        ("1e9,0,0", "1e+09 mm from the tip link's origin"),  # UD03
        (
            "5000,0,0",
            "5000 mm from the tip link's origin; the wire's fixture is on the tip",
        ),  # UD03
        ("-0.06,0,0.05", "every coordinate under 1 mm: that looks like metres"),  # UD04
    ],
)
def test_ud03_ud04_a_wire_point_out_of_place_is_refused(tmp_path, point, message):
    r = invoke(
        "import-urdf", URDF, "--tip", "wire", f"--wire-point-mm={point}", "-o", tmp_path / "r"
    )
    assert r.exit_code == 2
    assert message in r.output


def test_ns13_a_gauge_of_a_nanometre_is_refused(tmp_path):
    robot = tmp_path / "r.toml"
    robot.write_text(
        ROBOT.read_text().replace("[encoder]\n", "[encoder]\nreference_length_mm = 1e-9\n")
    )
    r = invoke("psi", robot, PLAN)
    assert r.exit_code == 2
    assert "encoder.reference_length_mm: is 1e-09 mm: a gauge shorter than 50 mm" in r.output


def test_rk13_a_full_disk_names_the_journal_and_what_it_keeps(tmp_path, monkeypatch):
    """RK13, NK23: 'error: file: No space left on device', exit 2: the journal was not
    named."""
    import errno
    import socket
    import threading

    import wirecal.app.receive as rec
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.formats.run_token import run_token, token_line
    from wirecal.formats.simulated_log import simulate_log

    keep = rec._keep

    def full_after_20(jf, result, line):
        if len(result.lines) == 20:
            raise OSError(errno.ENOSPC, "No space left on device")
        keep(jf, result, line)

    monkeypatch.setattr(rec, "_keep", full_after_20)
    ur5 = load_robot(VIPER.parent / "ur5e" / "robot.toml")
    plan = load_plan(VIPER.parent / "ur5e" / "plan.toml", ur5)
    text = simulate_log(ur5, plan, {}, seed=1, counter_start=1000.0)
    ports, out, result = [], tmp_path / "run.csv", {}
    thread = threading.Thread(
        target=lambda: result.update(
            r=rec.receive(0, out, ur5, plan, timeout_s=10, on_listening=ports.append)
        ),
        daemon=True,
    )
    thread.start()
    while not ports:
        thread.join(0.05)
    with socket.create_connection(("127.0.0.1", ports[0]), timeout=10) as s:
        hello = token_line(run_token(ur5, plan.fingerprint())) + "\n"
        with contextlib.suppress(OSError):
            s.sendall((hello + text + "# end\n").encode())
    thread.join(20)
    r = result["r"]
    assert not r.complete
    assert r.stopped.startswith(f"{rec.journal_path(out)}: No space left on device after line 20")
    assert len(rec.journal_path(out).read_text().splitlines()) == 20
    assert not out.exists()


def test_nu02_a_16_bit_count_is_suspected_once(tmp_path, log):
    """A filtered 16-bit count: 'wire length … is negative: is the sign of mm_per_count
    right?' on every row; now once, naming the counter's width too."""
    lines = log.read_text().splitlines()
    first = next(float(x.split(",")[9]) for x in lines if x.startswith("zero,"))
    shift = 2**15 - 1000 - round(first)  # θ0 just below the 16-bit counter's turn
    for k, line in enumerate(lines):
        cells = line.split(",")
        if cells[0] in ("zero", "point"):
            counts = round(float(cells[9])) + shift
            cells[9] = f"{(counts + 2**15) % 2**16 - 2**15:.4f}"
            lines[k] = ",".join(cells)
    out = _solve_text(tmp_path, "\n".join(lines) + "\n")
    assert "or the logged counts wrap sooner than the 24-bit counter" in out, out
    assert out.count("is negative") == 0


def test_cl24_body_limits_in_radians_are_named(tmp_path):
    """psi flooded ~390 warnings and gen blamed joint 2's limits [-3.3, 0.78]."""
    robot = tmp_path / "r.toml"
    text = (VIPER.parent / "ur5e" / "robot.toml").read_text()
    text = re.sub(
        r"body_min_deg = \[.*\]", "body_min_deg = [-6.2, -6.2, -3.05, -6.2, -6.2, -6.2]", text
    )
    text = re.sub(r"body_max_deg = \[.*\]", "body_max_deg = [6.2, 0.78, 3.05, 6.2, 6.2, 6.2]", text)
    robot.write_text(text)
    r = invoke("psi", robot, VIPER.parent / "ur5e" / "plan.toml")
    assert r.exit_code == 2
    assert "cell.body_max_deg: every body limit is within ±2π: they look like radians" in r.output
    assert len(r.output.splitlines()) < 5


def test_the_spec_table_of_a_ur_sends_the_user_to_its_own_file(tmp_path):
    """patch.spec.txt told UR and ABB users to use 'the Adept SPEC utility'."""
    ur5 = VIPER.parent / "ur5e"
    log_path = tmp_path / "run.csv"
    assert invoke("simulate", ur5 / "robot.toml", ur5 / "plan.toml", "-o", log_path).exit_code == 0
    r = invoke("solve", ur5 / "robot.toml", ur5 / "plan.toml", log_path, "-o", tmp_path / "p.toml")
    assert r.exit_code == 0, r.output
    spec = (tmp_path / "p.spec.txt").read_text()
    assert "SPEC" not in spec
    assert "the file ending .ur_calibration.conf beside" in spec


@pytest.mark.slow
def test_sigint_stops_the_report_at_once(tmp_path, log):
    """NC09: SIGINT in report once ended in 'Fatal Python error … finalizing' (exit −6;
    once in 50 tries, not reproduced since)."""
    import signal
    import time

    for delay_s in (0.5, 1.5, 2.5):
        p = subprocess.Popen(
            [*WIRECAL, "report", str(ROBOT), str(PLAN), str(log), "-o", str(tmp_path / "r.html")],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        time.sleep(delay_s)
        t = time.perf_counter()
        p.send_signal(signal.SIGINT)
        _, err = p.communicate(timeout=30)
        if p.returncode == 0:  # finished before the signal
            (tmp_path / "r.html").unlink()
            continue
        assert p.returncode == 128 + signal.SIGINT, err
        assert "Fatal Python error" not in err
        assert time.perf_counter() - t < 2.0
        assert not (tmp_path / "r.html").exists()


@pytest.mark.parametrize("ppm", [5000, -5000])
def test_ns07_ns08_a_scale_error_without_a_gauge_is_diagnosed(tmp_path, ppm):
    """A 0.5 % scale error without a gauge: exit 3 with the generic advice only. Now the
    residual finding says the scale explains the misfit, by how much and which way, and
    what mm_per_count would be: the true one is the file's × (1 + ppm·10⁻⁶) (simulate's
    --encoder-scale-ppm), 0.025488 × 1.005 = 0.025615 (0.025361 for −5000); the run's
    0.5 K warming adds about 10 ppm, and the fit's own error is a few per cent of 5000."""
    log_path = tmp_path / "run.csv"
    args = ["-o", log_path, "--encoder-scale-ppm", ppm]
    assert invoke("simulate", ROBOT, PLAN, *args).exit_code == 0
    r = invoke("solve", ROBOT, PLAN, log_path)
    assert r.exit_code == 3
    text = " ".join(r.output.split())
    found = re.search(
        r"the encoder's scale explains it: the lengths read (\d+) ppm (longer|shorter) fit to "
        r"σ ([\d.]+) mm, a scale off beyond \[encoder\] scale_tolerance_ppm 500: "
        r"mm_per_count 0.025488 would be about ([\d.]+); check it",
        text,
    )
    assert found is not None, text
    assert abs(int(found.group(1)) - abs(ppm)) < 0.05 * abs(ppm)
    assert found.group(2) == ("longer" if ppm > 0 else "shorter")
    limit = float(re.search(r"allow at most ([\d.]+) mm", text).group(1))
    assert float(found.group(3)) <= limit
    assert float(found.group(4)) == pytest.approx(0.025488 * (1 + ppm * 1e-6), rel=5e-4)
    assert "measure a reference gauge (reference_length_mm)" in text


def test_a_misfit_the_scale_does_not_explain_keeps_the_general_advice(tmp_path, log):
    """Lengths off by ±0.3 mm at random: no scale fits them, so the scale is only a hint."""
    rng = np.random.default_rng(7)
    lines = log.read_text().splitlines(keepends=True)
    noisy = tmp_path / "noisy.csv"
    noisy.write_text(
        "".join(
            re.sub(
                r"^(point,(?:[^,]*,){8})([^,]*)",
                lambda m: f"{m.group(1)}{float(m.group(2)) + rng.choice([-12, 12]):.4f}",
                line,
            )
            for line in lines
        )
    )
    r = invoke("solve", ROBOT, PLAN, noisy)
    assert r.exit_code == 3, r.output
    text = " ".join(r.output.split())
    assert "an encoder scale off beyond [encoder] scale_tolerance_ppm: check mm_per_count" in text
    assert "the encoder's scale explains it" not in text


def test_nd21_overflowing_origins_are_refused_before_any_arithmetic(tmp_path):
    """Overflow warnings and 'differs … by inf mm; please report this URDF' before."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(URDF.read_text().replace('xyz="0 0 0.3"', 'xyz="0 0 1e308"', 1))
    r = invoke("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml")
    assert r.exit_code == 2
    assert "origin xyz 0 0 1e+308 is beyond 10 m" in r.output
    assert "inf" not in r.output
    assert "please report" not in r.output


@pytest.mark.parametrize(("length", "refused"), [(71, False), (72, True), (120, True)])
def test_ra04_a_robot_name_longer_than_a_rapid_string_is_refused_by_its_key(
    tmp_path, length, refused
):
    """RA04: a 120-character name gave 'internal error: the generated module breaks a RAPID
    rule'. The module logs the name in one string, '# robot: NAME' (9 + n characters), and
    a RAPID string holds 80 (kernel types: "0 to 80 characters"): n ≤ 71 is written, longer is
    refused naming the key and the length to shorten it to."""
    irb = VIPER.parent / "abb_irb120"
    name = "A" * length
    robot = re.sub(
        r'^name = ".*"$', f'name = "{name}"', (irb / "robot.toml").read_text(), count=1, flags=re.M
    )
    plan = re.sub(
        r'^robot = ".*"$', f'robot = "{name}"', (irb / "plan.toml").read_text(), count=1, flags=re.M
    )
    (tmp_path / "robot.toml").write_text(robot)
    (tmp_path / "plan.toml").write_text(plan)
    r = invoke("gen", tmp_path / "robot.toml", tmp_path / "plan.toml", "-o", tmp_path / "out")
    if not refused:
        assert r.exit_code == 0, r.output
        assert f'"# robot: {name}"' in (tmp_path / "out" / "WIRECAL.mod").read_text()
        return
    assert r.exit_code == 2, r.output
    assert "internal error" not in r.output
    assert f"{length} characters" in r.output
    assert "a RAPID string holds 80: shorten the name to 71 characters or fewer" in r.output
    assert not (tmp_path / "out").exists()


def test_ra04_a_name_with_a_trailing_space_is_the_same_name_in_robot_and_plan(tmp_path):
    """RA04's first try: 'plan is for 'ABB IRB 120 ' but the robot file describes 'ABB IRB
    120'': the robot file's name is read stripped, the plan's was not."""
    irb = VIPER.parent / "abb_irb120"
    robot = re.sub(r'^(name = ".*)"$', r'\1 "', (irb / "robot.toml").read_text(), flags=re.M)
    plan = re.sub(r'^(robot = ".*)"$', r'\1 "', (irb / "plan.toml").read_text(), flags=re.M)
    assert 'name = "ABB IRB 120 "' in robot
    assert 'robot = "ABB IRB 120 "' in plan
    (tmp_path / "robot.toml").write_text(robot)
    (tmp_path / "plan.toml").write_text(plan)
    r = invoke("psi", tmp_path / "robot.toml", tmp_path / "plan.toml")
    assert r.exit_code == 0, r.output


def test_nc09_an_error_a_ctrl_c_caused_ends_as_the_ctrl_c():
    """NC09 again: Ctrl-C while scipy's compiled optimizer initialised (report's lazy import)
    surfaced as 'ImportError: initialization failed': exit 1 and a traceback, not the stop."""
    import signal

    code = (
        "import os, signal\n"
        # a terminal's Ctrl-C, also where pytest runs as a background job (SIGINT ignored)
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        "from wirecal.cli.interrupt import stop_cleanly\n"
        "with stop_cleanly():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGINT)\n"
        "        signal.pause()\n"
        "    except KeyboardInterrupt:\n"
        "        raise ImportError('initialization failed')\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert p.returncode == 128 + signal.SIGINT, p.stderr
    assert "Traceback" not in p.stderr
    assert "stopped (SIGINT); nothing written" in p.stderr
    # an error no signal caused is still the error
    plain = code.replace(
        "        os.kill(os.getpid(), signal.SIGINT)\n        signal.pause()\n",
        "        raise KeyboardInterrupt\n",
    )
    p = subprocess.run([sys.executable, "-c", plain], capture_output=True, text=True, timeout=60)
    assert p.returncode == 1
    assert "ImportError: initialization failed" in p.stderr
