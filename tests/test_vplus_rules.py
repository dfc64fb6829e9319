"""The V+ rules of the front end, each both ways (accepted and rejected), on small programs
written for the test; every case cites the manual page (or marks the fact unconfirmed).
Sources: V+ Language User's Guide v17 (UG p. N), V+ Language Reference Guide keyword pages
(KE), the eV+3 Keyword Reference (EV3 p. 16)."""

from __future__ import annotations

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.lang.vplus import nodes as N
from wirecal.lang.vplus.keywords import keyword, keywords
from wirecal.lang.vplus.parser import parse_module, parse_step
from wirecal.solver.errors import WirecalError
from wirecal.twin.vplus.interp import Interpreter, Trans


def prog(body: str, extra: str = "", header: str = ".PROGRAM t.main()") -> str:
    return header + "\n" + body + "\n.END\n" + extra


def problems(text: str, **kw) -> list[str]:
    try:
        parse_module(text, "t.v2", **kw)
    except WirecalError as exc:
        return exc.problems
    return []


# ---------- names: keywords are reserved (UG p. 99; EV3 p. 16) ----------
REJECTED_NAMES = {
    # UG p. 99's own example of an invalid name: PI is a function
    "pi = 3": "t.v2:2: t.main: 'pi' is a V+ keyword",
    # OFF is a system constant (UG p. 103, p. 128)
    "AUTO DOUBLE off": "t.v2:2: t.main: 'off' is a V+ keyword (system constant;",
    # BASE is an instruction (issue 11 quotes its reference page)
    "base = 1": "t.v2:2: t.main: 'base' is a V+ keyword (instruction;",
    # DZ is a real-valued function (KE dx_r.html)
    "AUTO dz": "t.v2:2: t.main: 'dz' is a V+ keyword (function;",
    # a keyword read as a variable, where it is no value (SPEED is an instruction)
    "x = speed+1": "'speed' is a V+ keyword (instruction",
    "FOR type = 1 TO 3\nEND": "'type' is a V+ keyword",
}


@pytest.mark.parametrize("body", sorted(REJECTED_NAMES))
def test_keyword_as_name_rejected(body):
    found = problems(prog(body))
    assert any(REJECTED_NAMES[body] in p for p in found), found
    assert all("cannot be a name" in p for p in found if "keyword" in p)


def test_keyword_as_program_or_parameter_name_rejected():
    found = problems(prog("", header=".PROGRAM base(x)"))
    assert any("t.v2:1: base: 'base' is a V+ keyword" in p for p in found), found
    found = problems(prog("", header=".PROGRAM t.main(dz, $s)"))
    assert any("t.v2:1: t.main: 'dz' is a V+ keyword" in p for p in found), found


def test_names_like_keywords_accepted():
    # only the whole name is reserved: pie, base.z, offset, dz2 are names (UG p. 99)
    assert problems(prog("pie = 3\nbase.z = 1\nAUTO offset, dz2\noffset = pie+base.z")) == [
        "t.v2:4: t.main: declaration after executable steps"
    ]
    assert problems(prog("AUTO offset, dz2\npie = 3\nbase.z = 1\noffset = pie+base.z")) == []


def test_constants_are_values():
    # TRUE, ON = -1 and FALSE, OFF = 0 can be used wherever a value is (UG p. 103)
    src = prog("x = OFF\nIF TRUE THEN\n    TYPE ON, FALSE\nEND")
    assert problems(src) == []


def test_each_keyword_reported_once_per_program():
    found = problems(prog("AUTO off\noff = 1\nTYPE off"))
    assert len(found) == 1, found


# ---------- the statement language (UG p. 35: every part of a step is optional) ----------
ACCEPTED = {
    # CALL: a variable or array element by reference, an expression by value, an omitted
    # argument undefined (UG p. 43, p. 45; EV3 p. 16 `CALL program_name(1, , n+3)`)
    "call forms": "AUTO a[3], i\ni = 1\na[1] = 2\nCALL t.sub(a[i], (a[1]), a[], , 3)",
    # TRANS: "if any parameter is omitted, its value is taken to be zero" (KE trans_t.html)
    "trans with three values": "SET t = TRANS(1, 2, 3)\nSET u = TRANS(1, , 3)",
    # #PPOINT: one value per joint (UG p. 166) — a SCARA has four
    "ppoint of four": "SET #p = #PPOINT(1, 2, 3, 4)",
    # a step label on any line, also inside a block (UG p. 35 puts no restriction on it)
    "label in WHILE": "i = 0\nWHILE i < 3 DO\n 10 i = i+1\n    IF i == 1 GOTO 10\nEND",
    # format specifiers: WRITE (lun) $msg, /S in Adept's own driver (third-party use)
    "format specifiers": 'TYPE /S\nTYPE "a", /S\nTYPE /C2, "x", 3',
    # declarations with a type (UG p. 107; AUTO LOC in the ROS driver)
    "typed declarations": "AUTO REAL r[10]\nAUTO LOC #cur\nLOCAL $tmp, i\nGLOBAL DOUBLE d",
    # instructions the twin does not execute still parse as instructions
    "generic instructions": (
        "AUTO lun, $in\nSELECT ROBOT = 1\nATTACH ()\nSIGNAL -2001, 2002\nWAIT\n"
        "WAIT.EVENT , 0.5\nEXECUTE 1 t.sub(1, 2, 3, 4, 5)\nREAD (lun, 0, 0) $in\n"
        'FOPEN (lun, 16) "/LOCAL_PORT 11000"\nSPEED 100 ALWAYS\nACCEL (1) 100, 100\n'
        "TIMER 1 = 0\nx = STATE(4) BAND 4"
    ),
    # string functions and operators (UG p. 100, p. 113)
    "string functions": '$s = $MID("abc", 1, 2)+$CHR(65)\nx = LEN($s) XOR 1\ny = COM ^B101',
    # numbers: ^H hexadecimal, ^B binary, ^ octal, ^D double (UG p. 102); 'A (UG p. 100)
    "numbers": "x = ^HFF+^B101+^17+1E-03+'A\nd = ^D12",
    # DO … UNTIL
    "do until": "i = 0\nDO\n    i = i+1\nUNTIL i > 3",
}
SUB = ".PROGRAM t.sub(x, y, a[], z, w)\n.END\n"


@pytest.mark.parametrize("case", sorted(ACCEPTED))
def test_valid_v_plus_accepted(case):
    assert problems(prog(ACCEPTED[case], SUB)) == []


REJECTED = {
    "TRANS with seven values": ("SET t = TRANS(1, 2, 3, 4, 5, 6, 7)", "TRANS takes 0 to 6"),
    "PPOINT of none": ("SET #p = #PPOINT()", "#PPOINT takes 1 to 12 arguments, not 0"),
    "GOTO to no label": ("i = 0\nWHILE i < 3 DO\n 10 i = i+1\nEND\nGOTO 20", "GOTO 20: no such"),
    "unknown instruction": ("JMOVE #p", "t.v2:2: t.main: unknown instruction JMOVE"),
    "unknown function": ("x = ROUND(2.5)", "t.v2:2: t.main: unknown function ROUND"),
    "UNTIL without DO": ("UNTIL x", "UNTIL without DO"),
    "DO closed by END": ("DO\nEND", "END inside a DO block"),
    "CALL passes a number to a string": ("CALL t.s(3)", "a number where t.s takes a string"),
    "array element for an array": ("CALL t.a(x[1])", "a is an array; pass a[]"),
    "location assigned without SET": ("#p = #q", "type-prefix misuse"),
    "format outside an operand": ("x = /S", "bad syntax"),
}


@pytest.mark.parametrize("case", sorted(REJECTED))
def test_invalid_v_plus_rejected(case):
    body, message = REJECTED[case]
    found = problems(prog(body, ".PROGRAM t.s($s)\n.END\n.PROGRAM t.a(a[])\n.END\n"))
    assert any(message in p for p in found), found


def test_external_calls():
    src = prog("CALL other.prog(1)\nEXECUTE 1 other.task()")
    assert len(problems(src)) == 2
    assert problems(src, external_calls=True) == []


def test_typed_tree():
    s = parse_step("CALL f(x[i], (y), a[], , 3)")
    assert isinstance(s, N.Call)
    assert s.program == "f"
    assert isinstance(s.args[0], N.Var)
    assert s.args[0].index == [N.Var("i")]
    assert isinstance(s.args[1], N.Paren)
    assert s.args[2] == N.ArrayArg("a")
    assert s.args[3] is None
    assert s.args[4] == N.Num(3.0, False)
    s = parse_step("WRITE (lun) $a, /S")
    assert isinstance(s, N.Instruction)
    assert s.name == "write"
    assert s.clauses[0] == N.Clause([], [N.Paren(N.Var("lun")), N.Var("$a")], None)
    assert s.clauses[1] == N.Clause(["/S"], [], None)
    s = parse_step("WAIT.EVENT , 3")
    assert s.clauses[0] is None
    # keywords are case-insensitive (UG p. 99); names are kept in lower case
    assert parse_step("Set #P = here") == parse_step("SET #p = HERE")


def test_crlf_and_lf_give_the_same_module():
    src = prog("AUTO i\nFOR i = 1 TO 2\n    TYPE i\nEND")
    lf = parse_module(src, "t.v2")
    crlf = parse_module(src.replace("\n", "\r\n"), "t.v2")
    assert lf == crlf
    bad = prog("AUTO i\nx = 1\nAUTO j").replace("\n", "\r\n")
    assert problems(bad) == ["t.v2:4: t.main: declaration after executable steps"]


def test_data_sections_are_skipped():
    src = prog("x = 1") + ".REALS\nx = 3\n.END\n"
    assert problems(src) == []


# ---------- the twin runs what it models and refuses the rest by name ----------
class _Console:
    def __init__(self):
        self.console: list[str] = []

    def type_(self, text):
        self.console.append(text)


def run(src: str, name: str = "t.main"):
    interp = Interpreter(parse_module(src, "t.v2"), _Console())
    return interp, interp.execute(name)


def test_twin_call_semantics():
    # a variable and an array element by reference, (expr) by value (UG p. 43, p. 45; the
    # element by reference as Adept's ROS driver uses it: unconfirmed by a manual page)
    src = prog(
        "AUTO a[3], b, c\na[1] = 1\nb = 1\nc = 1\nCALL t.inc(a[1], b, (c), )\nTYPE a[1], b, c",
        ".PROGRAM t.inc(x, y, z, w)\n    x = x+1\n    y = y+1\n    z = z+1\n"
        "    TYPE DEFINED(w)\n.END\n",
    )
    _, out = run(src)
    assert out.status == "completed", out
    assert out.console == ["0", "221"]


def test_twin_trans_omitted_arguments_are_zero():
    # KE trans_t.html: "if any parameter is omitted, its value is taken to be zero"
    interp, out = run(prog("SET t = TRANS(1, , 3)"))
    assert out.status == "completed", out
    t = interp.get_global("t")
    assert isinstance(t, Trans)
    assert t.values() == (1.0, 0.0, 3.0, 0.0, 0.0, 0.0)


def test_twin_labels_and_loops():
    src = prog(
        "i = 0\nWHILE i < 5 DO\n    i = i+1\n    IF i < 3 GOTO 10\n    TYPE i\n 10 \nEND\n"
        "DO\n    i = i-2\nUNTIL i < 0\nTYPE i"
    )
    _, out = run(src)
    assert out.status == "completed", out
    assert out.console == ["3", "4", "5", "-1"]


def test_twin_refuses_what_it_does_not_model():
    _, out = run(prog("SIGNAL 1\nTYPE 1"))
    assert out.status == "error"
    assert out.line == 2
    assert "*Not executed by the digital twin* SIGNAL is not executed by the twin" in out.message
    _, out = run(prog("TYPE /S"))
    assert "TYPE with format specifiers" in out.message
    _, out = run(prog("x = DX(TRANS(1))"))
    assert "function DX" in out.message


# ---------- hypothesis ----------
NAMES = st.from_regex(r"[a-z][a-z0-9._]{0,14}", fullmatch=True)


@settings(max_examples=200, deadline=None)
@given(NAMES)
def test_any_valid_name_is_accepted_unless_a_keyword(name):
    found = problems(prog(f"AUTO {name}\n{name} = 1\nTYPE {name}"))
    if keyword(name) is None:
        assert found == []
    else:  # a statement keyword (DO, END) also breaks the syntax of its lines
        assert any(f"t.v2:2: t.main: '{name}' is a V+ keyword" in p for p in found), found


@settings(max_examples=300, deadline=None)
@given(
    st.text(alphabet=st.sampled_from(list(" \t\r\n\".,;:()[]=+-*/<>#$%^'01aAzZ._")), max_size=80)
)
def test_lint_never_tracebacks(text):
    # any text: either a module, or problems — never an exception of another kind
    for module in (".PROGRAM t.main()\n" + text + "\n.END\n", text):
        problems = _problems(module)
        assert all(p.startswith("t.v2") for p in problems or ())


def _problems(text: str) -> list[str] | None:
    """The problems the checker reports for ``text``, or None when it is clean."""
    try:
        parse_module(text, "t.v2")
    except WirecalError as exc:
        return exc.problems
    return None


@settings(max_examples=100, deadline=None)
@given(st.lists(st.sampled_from(sorted(keywords())), min_size=1, max_size=6))
def test_lint_never_tracebacks_on_keyword_soup(words):
    try:
        parse_module(prog(" ".join(words)), "t.v2")
    except WirecalError:
        pass


# ---------- wirecal lint ----------
def test_lint_cli(tmp_path):
    good = tmp_path / "GOOD.V2"
    good.write_bytes(prog("AUTO i\ni = 1").replace("\n", "\r\n").encode())
    bad = tmp_path / "BAD.V2"
    bad.write_text(prog("AUTO off\npi = 3"))
    runner = CliRunner()
    r = runner.invoke(main, ["lint", str(good)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(main, ["lint", "--separately", str(good), str(bad)])
    assert r.exit_code == 1
    lines = r.stdout.strip().splitlines()
    assert len(lines) == 2, lines
    assert lines[0].startswith(f"{bad}:2: t.main: 'off' is a V+ keyword")
    assert lines[1].startswith(f"{bad}:3: t.main: 'pi' is a V+ keyword")
    together = runner.invoke(main, ["lint", str(good), str(bad)]).stdout  # one memory
    assert f"{bad}:1: program t.main is also defined in {good}" in together
    r = runner.invoke(main, ["lint", str(good), str(tmp_path / "MISSING.V2")])
    assert r.exit_code == 2
    assert "error: " in r.stderr
    assert "MISSING.V2: cannot read" in r.stderr


# ---------- the generator runs the same checker on its own output ----------
def test_generator_checks_its_own_output(viper, paper_plan, monkeypatch):
    from wirecal.gen.vplus import program

    def render(*args, **kwargs):
        return ".PROGRAM wc.x()\n    AUTO base\n    base = 1\n.END\n"

    monkeypatch.setattr(program, "render", render)
    with pytest.raises(WirecalError) as info:
        program.module_text(viper, paper_plan)
    assert info.value.problems[0].startswith("internal error: the generated module breaks")
    assert info.value.problems[1].startswith("WIRECAL.V2:2: wc.x: 'base' is a V+ keyword")


@pytest.mark.slow
def test_lint_generated_module_with_validation(tmp_path):
    from .conftest import VIPER

    runner = CliRunner()
    args = [str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml"), "-o", str(tmp_path)]
    r = runner.invoke(main, ["gen", *args, "--validation", str(VIPER / "validation.toml")])
    assert r.exit_code == 0, r.output
    r = runner.invoke(main, ["lint", str(tmp_path / "WIRECAL.V2")])
    assert r.exit_code == 0, r.output
    assert r.stdout == ""


def test_more_valid_forms():
    # CALL without an argument list (EV3 p. 16); a compound transformation (UG p. 314;
    # KE trans_t `MOVE frame:TRANS(...)`); a whole array as a function argument
    # (EVREF p. 311 `LAST (array_name[])`)
    body = "CALL t.none\nMOVES %belt:loc_1\nMOVE frame:TRANS(1, 2)\nx = LAST(a[])\nCASE x OF\n"
    body += "  VALUE 1:\n    TYPE 1\n  ANY\nEND"
    assert problems(prog(body, ".PROGRAM t.none()\n.END\n")) == []
    assert any("MOVE needs a location" in p for p in problems(prog("MOVE 3")))


def test_every_instruction_of_the_table_parses_as_an_instruction():
    structured = {"auto", "local", "global", "call", "if", "for", "while", "do", "case", "goto"}
    names = [k.name for k in keywords().values() if "instruction" in k.kinds]
    assert len(names) > 50
    for name in names:
        if name in structured:
            continue
        for line in (name, f"{name} x, 1", f"{name} (lun) $s, /S"):
            step = parse_step(line)
            assert isinstance(step, N.Instruction), line
            assert step.name == name


def test_the_twin_knows_only_keywords():
    from wirecal.lang.vplus.forms import FORMS
    from wirecal.lang.vplus.parser import FUNCTIONS

    for name in FORMS:
        assert "instruction" in keywords()[name].kinds, name
    for name in FUNCTIONS:
        assert "function" in keywords()[name].kinds, name
