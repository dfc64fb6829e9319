"""``wirecal lint`` on URScript, both ways: the manual's language passes, errors are caught.

Each program is written here (never copied from others' scripts) and names the page its
rule was read on; "unconfirmed" marks a construct accepted because Universal Robots' own
public scripts use it (docs/languages.md), not because a manual page was read.
"""

from __future__ import annotations

import re

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.gen.request import GenRequest
from wirecal.lang.urscript import URScript
from wirecal.lang.urscript.parser import BUILTINS, parse_program
from wirecal.solver.errors import WirecalError
from wirecal.twin.urscript.interp import Interpreter

THREADS = "SW5.20 Threads page"
TYPES = "UR16e User Manual p. 181; UR5 CB3 User Manual 3.4.5 p. II-69"
TICKS = "SW5.20 encoder_get_tick_count page"


def program(*body: str) -> str:
    """Return ``def p():``, the body indented two spaces, ``end``."""
    return "\n".join(["def p():", *(f"  {line}" for line in body), "end", ""])


def problems(text: str) -> list[str]:
    """Return the checker's problems (none: an empty list)."""
    try:
        parse_program(text, "t.script")
    except WirecalError as exc:
        return exc.problems
    return []


VALID = {
    "pose literal, written p[x, y, z, rx, ry, rz] (" + TYPES + ")": [
        "x = p[0.4, -0.1, 0.3, 0, 3.1416, 0]",
        "y = pose_trans(x, p[0, 0, 0.05, 0, 0, 0])",
        "z = x[2] + y[0]",
    ],
    "threads, run, join, kill, critical sections (" + THREADS + ")": [
        "global count = 0",
        "thread counter():",
        "  enter_critical",
        "  count = count + 1",
        "  exit_critical",
        "  return False",
        "end",
        "h = run counter()",
        "join h",
        "g = run counter()",
        "kill g",
    ],
    "default and named arguments (unconfirmed; Universal Robots' client library)": [
        'def greet(s, times=1, title="wirecal"):',
        "  n = 0",
        "  while n < times:",
        "    popup(s, title=title)",
        "    n = n + 1",
        "  end",
        "end",
        'greet("a")',
        'greet("b", 2)',
        'greet("c", title="x")',
    ],
    "break and continue in a while (unconfirmed; Universal Robots' client library)": [
        "k = 0",
        "while True:",
        "  k = k + 1",
        "  if k < 3:",
        "    continue",
        "  end",
        "  break",
        "end",
    ],
    "a statement over lines while a bracket is open or after an operator (unconfirmed)": [
        "s = str_cat(",
        '  "a", str_cat("b",',
        '  "c"))',
        "ok = s == 1 or",
        "  s == 2",
    ],
    "int range ends, the raw count (" + TYPES + "; " + TICKS + ")": [
        "lo = -2147483648",
        "hi = 2147483647",
        'c = encoder_get_tick_count(1, opt="raw")',
        "f = encoder_get_tick_count(0)",
        "big = 3.4e38",
    ],
    "documented functions others' scripts call (signatures unconfirmed)": [
        "movel(get_actual_tcp_pose(), a=1.2, v=0.25)",
        "set_tcp(p[0, 0, 0.1, 0, 0, 0])",
        'ok = socket_open("10.0.0.2", 30000, "s")',
        'line = socket_read_line("s", timeout=0.5)',
        'k = str_find(line, "OK")',
        "q = get_inverse_kin(p[0.4, 0, 0.3, 0, 3.14, 0])",
        "stopl(1.2)",
    ],
}


@pytest.mark.parametrize("body", VALID.values(), ids=list(VALID))
def test_the_manuals_language_passes(body):
    assert problems(program(*body)) == []


INVALID = [
    # (program lines, the problem reported, where the rule was read)
    (["x = 2147483648"], "outside the 32-bit int range", TYPES),
    (["x = -2147483649"], "outside the 32-bit int range", TYPES),
    (["x = 2147483647 + 1"], "overflows 32 bits", TYPES),
    (["x = 65536 * 65536"], "overflows 32 bits", TYPES),
    (["x = 1e39"], "beyond the largest 32-bit float", TYPES),
    (["c = encoder_get_tick_count(2)"], "encoder_index must be 0 or 1", TICKS),
    (['c = encoder_get_tick_count(0, opt="rawx")'], 'opt is "" or "raw"', TICKS),
    (["encoder_enable_pulse_decode(-1, 1, 8, 9)"], "encoder_index must be 0 or 1", TICKS),
    (["q = [1, 2, 3]", "x = q[3]"], "q[3]: index out of range", TYPES),
    (["q = p[1, 2, 3, 0, 0, 0]", "q[6] = 1"], "q[6]: index out of range", TYPES),
    (["thread t(a):", "end"], "bad syntax", THREADS),
    (["x = run nothing()"], "no thread nothing", THREADS),
    (["def f():", "end", "x = run f()"], "no thread f", THREADS),
    (["thread t():", "end", "t()"], "start it with run t()", THREADS),
    (["join h"], "no thread handle h", THREADS),
    (["break"], "'break' outside a while loop", "unconfirmed"),
    (["def f(a=1, b):", "end"], "without a default follows", "unconfirmed"),
    (["def f(a, b=2):", "end", "f()"], "f needs a", "unconfirmed"),
    (["movel(p[0, 0, 0, 0, 0, 0], speed=1)"], "movel has no parameter speed", "unconfirmed"),
    (["x = p[1, 2]", "y = q[1, 2]"], "a list index is one expression", TYPES),
]


@pytest.mark.parametrize(("body", "message", "page"), INVALID)
def test_invalid_programs_are_caught(body, message, page):
    found = problems(program(*body))
    assert any(message in p for p in found), (page, found)
    assert all(p.startswith("t.script:") for p in found)


def test_a_sec_program_is_a_script():
    text = "sec s():\n  set_standard_digital_out(1, True)\nend\n"
    assert problems(text) == []


def test_lint_names_the_line_and_exits_1(tmp_path):
    bad = tmp_path / "bad.script"
    bad.write_text(program("x = 1", "c = encoder_get_tick_count(2)"))
    out = CliRunner().invoke(main, ["lint", str(bad)])
    assert out.exit_code == 1
    assert f"{bad}:3: encoder_get_tick_count: encoder_index must be 0 or 1, not 2" in out.output


def test_every_function_row_is_well_formed():
    assert len(BUILTINS) > 150
    for name, b in BUILTINS.items():
        assert name.isidentifier()
        assert 0 <= b.required <= len(b.params)
        pages = ("SD", "SW", "UR article")  # Script Manual pages, or a UR support article
        assert b.source == "unconfirmed" or any(k in b.source for k in pages), name
    # the functions wirecal emits were read on a page
    emitted = ("movej", "encoder_get_tick_count", "socket_open", "textmsg", "floor")
    payload = ("get_target_payload", "get_target_payload_cog", "set_payload")
    for name in (*emitted, *payload):
        assert BUILTINS[name].source != "unconfirmed", name


def test_the_payload_calls_as_the_script_directory_gives_them():
    """set_target_payload(m, cog, inertia=[0]*6, transition_time=0) (SD §15.46: kg, m from
    the tool mount, kg·m² at the CoG, s): 2 to 4 arguments, by those names; the deprecated
    set_payload_mass/_cog and get_target_payload_inertia read too (§15.44, 15.45, 15.22);
    get_target_payload_mass on no Universal Robots page read."""
    b = BUILTINS["set_target_payload"]
    assert (b.params, b.required) == (("m", "cog", "inertia", "transition_time"), 2)
    assert "§15.46" in b.source
    assert "kg*m^2" in b.source
    for name, section in [
        ("set_payload_cog", "§15.44"),
        ("set_payload_mass", "§15.45"),
        ("get_target_payload_inertia", "§15.22"),
        ("set_payload", "§15.43"),
    ]:
        assert section in BUILTINS[name].source, name
    assert BUILTINS["get_target_payload_mass"].source == "unconfirmed"
    ok = "set_target_payload(1.5, [0, 0, 0.05], [0, 0, 0, 0, 0, 0], transition_time=0.5)"
    assert URScript().lint(program(ok), "t.script", "5.20") == []
    for bad, why in [
        ("set_target_payload(1.5)", "set_target_payload needs cog"),
        ("set_target_payload(1.5, [0, 0, 0], [0, 0, 0, 0, 0, 0], 0, 1)", "at most 4 argument"),
    ]:
        assert any(why in p for p in URScript().lint(program(bad), "t.script", "5.20")), bad


def test_the_twin_refuses_what_it_does_not_run():
    text = program("thread t():", "end", "h = run t()")
    with pytest.raises(WirecalError, match="not in the URScript subset the twin runs"):
        Interpreter(parse_program(text, "t.script"), object())
    text = program("x = floor(2.5)", "movel(p[0, 0, 0, 0, 0, 0])")
    with pytest.raises(WirecalError) as info:
        Interpreter(parse_program(text, "t.script"), object())
    assert info.value.problems == [
        "t.script:3: movel is not a function the twin runs",
        "t.script:3: not in the URScript subset the twin runs",  # the pose literal
    ]


@settings(max_examples=200, deadline=None)
@given(st.integers(min_value=-(2**40), max_value=2**40))
def test_int_literals_pass_exactly_inside_int32(n):
    found = problems(program(f"x = {n}"))
    assert (found == []) == (-(2**31) <= n <= 2**31 - 1)


# ---------- [controller] software: generation uses only what that version has ----------
def _ur5_with(software: str | None):
    """The UR5e example's robot (dict) and plan, with ``software`` declared instead."""
    import copy
    import tomllib
    from pathlib import Path

    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import robot_from_dict

    ur5 = Path(__file__).resolve().parents[1] / "examples" / "ur5e"
    data = copy.deepcopy(tomllib.loads((ur5 / "robot.toml").read_text()))
    if software is not None:
        data["controller"]["software"] = software
    robot = robot_from_dict(data, "r.toml")
    return robot, load_plan(ur5 / "plan.toml", robot)


@pytest.mark.parametrize(
    ("software", "refused"),
    [
        ("3.7", ["filtered count", "inputs 8-11"]),  # CB3 before the conveyor guide's 3.8
        ("3.15", []),  # CB3: the filtered count, no clock (gen/urscript/cb3.py)
        ("5.1", ["time()", 'opt="raw"', "inputs 8-11"]),
        ("5.11", ["time()", 'opt="raw"']),
        ("5.19.2", ['opt="raw"']),
        ("5.20", []),
        ("5.25.1", []),
        ("10.7", ["time()", 'opt="raw"', "inputs 8-11"]),  # PolyScope X: pages not read
    ],
)
def test_generation_refuses_calls_older_software_lacks(software, refused):
    from wirecal.gen.urscript import GENERATOR

    robot, plan = _ur5_with(software)
    if not refused:
        out = GENERATOR.programs(robot, plan, GenRequest())
        assert f"# Controller software: {software}." in out["wc_run.script"]
        return
    with pytest.raises(WirecalError) as info:
        GENERATOR.programs(robot, plan, GenRequest())
    lines = info.value.problems
    assert len(lines) == len(refused), lines  # each rule once
    for what in refused:
        line = next(x for x in lines if what in x)
        assert line.startswith(f'r.toml: controller.software = "{software}": wc_')  # program
        assert re.search(r"\.script:\d+: ", line)  # and line of the call
        assert "universal-robots.com" in line or "Script Directory" in line  # the page


@pytest.mark.parametrize(
    ("software", "message"),
    [
        ("5.x", 'give the version as numbers, e.g. "5.20"'),
        ("", "give a non-empty string"),
        ("6.0", "wirecal knows CB3 3.x, e-Series 5.x, PolyScope X 10.x"),
    ],
)
def test_software_key_is_checked(software, message):
    with pytest.raises(WirecalError) as info:
        _ur5_with(software)
    assert any(
        p.startswith("r.toml: controller.software") and message in p for p in info.value.problems
    ), info.value.problems


def test_software_is_written_back():
    import tomllib

    from wirecal.formats.robot_file import robot_file_text, robot_from_dict

    robot, _ = _ur5_with("5.23.1")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    assert robot_from_dict(tomllib.loads(text), "again.toml").controller.software == "5.23.1"


def test_gen_warns_when_the_software_is_not_declared(tmp_path):
    from pathlib import Path

    example = Path("examples/ur5e/robot.toml").read_text(encoding="utf-8")
    assert example.count('\nsoftware = "5.20"\n') == 1
    robot = tmp_path / "robot.toml"
    robot.write_text(example.replace('\nsoftware = "5.20"\n', "\n"), encoding="utf-8")
    out = CliRunner().invoke(
        main, ["gen", str(robot), "examples/ur5e/plan.toml", "-o", str(tmp_path / "out")]
    )
    assert out.exit_code == 0, out.output
    assert "[controller] software not declared" in out.output
    assert "5.20 or later" in out.output


@settings(max_examples=100, deadline=None)
@given(
    st.lists(st.integers(-1000, 1000), min_size=1, max_size=8),
    st.lists(st.booleans(), min_size=8, max_size=8),
)
def test_a_list_split_over_lines_is_the_same_program(values, breaks):
    one = program(f"x = [{', '.join(map(str, values))}]", "y = x[0]")
    parts = [str(v) + ("," if k < len(values) - 1 else "") for k, v in enumerate(values)]
    lines, current = [], "x = ["
    for part, cut in zip(parts, breaks, strict=False):
        current += part
        if cut:
            lines.append(current)
            current = "  "
        else:
            current += " "
    lines.append(current + "]")
    split = program(*lines, "y = x[0]")
    a, b = parse_program(one, "a.script"), parse_program(split, "b.script")
    assert a.body[0].value == b.body[0].value  # the same list literal node
    assert b.body[1].line == 2 + len(lines)  # after "def p():" and the list's lines


def test_lint_software_names_each_call_and_page(tmp_path):
    script = tmp_path / "t.script"
    script.write_text(
        program(
            "now = time(0)",
            'c = encoder_get_tick_count(0, opt="raw")',
            "f = encoder_get_tick_count(0)",  # no opt: not the 5.20 form
        )
    )
    old = CliRunner().invoke(main, ["lint", "--software", "5.19", str(script)])
    assert old.exit_code == 1
    assert f'{script}:3: encoder_get_tick_count(i, opt="raw") is documented from software 5.20' in (
        old.output
    )
    assert "not confirmed on 5.19" in old.output
    assert ":2: " not in old.output  # time() is documented on 5.19
    assert ":4: " not in old.output
    cb3 = CliRunner().invoke(main, ["lint", "--software", "3.15", str(script)])
    assert f"{script}:2: time() returning struct(sec, nanosec)" in cb3.output
    new = CliRunner().invoke(main, ["lint", "--software", "5.20", str(script)])
    assert new.exit_code == 0, new.output
    bad = CliRunner().invoke(main, ["lint", "--software", "5.x", str(script)])
    assert bad.exit_code == 2
    assert "give the version as numbers" in bad.output


def test_a_generated_program_breaking_a_rule_is_an_internal_error():
    from wirecal.gen.urscript.program import software_problems

    robot, _ = _ur5_with("5.20")

    def lint(text: str) -> list[str]:
        return URScript().lint(text, "wc_x.script", "5.20")

    with pytest.raises(WirecalError) as info:
        software_problems(robot, lint(program("y = z")))
    assert info.value.problems == [
        "internal error: a generated program breaks a URScript rule (please report):",
        "wc_x.script:2: variable z is read but never assigned",
    ]
    assert software_problems(robot, lint(program("y = 1"))) == []


# ---------- statements on one joined text (ur_rtde's injected register offset) ----------
def test_a_statement_after_another_on_a_joined_text_is_read_as_the_controller_reads_it():
    sent = "def p():\n  global a = # offset\n24  global b = # offset\n24  x = a + b\nend\n"
    assert problems(sent) == []
    assert any("bad syntax" in p for p in problems(sent.replace("24  global b", "24 ) global b")))


def test_splitting_a_hostile_joined_text_is_bounded():
    text = "def p():\n  x = 1 +\n" + "  y = 1 " * 5000 + "z = (\nend\n"
    found = problems(text)  # a message, never RecursionError, in well under a second
    assert found
    assert all(p.startswith("t.script:") for p in found)
