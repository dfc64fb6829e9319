"""The RAPID twin's interpreter: the controller's numbers and a fake controller's calls.

The expectations are written from the rules (num 32-bit, dnum 64-bit: RAPID kernel, built-in
data types), never computed with the interpreter.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

import pytest

from wirecal.lang.rapid.checker import check
from wirecal.lang.rapid.examples import module
from wirecal.solver.errors import WirecalError
from wirecal.twin.machine import RunError
from wirecal.twin.rapid.interp import fixed, load_module, number_text, run_module


@dataclass
class FakeController:
    """Record what the program asks; a counter that grows by 3 per read; a scripted answer."""

    now: float = 0.0
    joints: tuple[float, ...] = (0.0,) * 6
    calls: list[tuple] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    pendant: list[str] = field(default_factory=list)
    count: int = 4294967000
    open_text: str = ""

    def move_abs_j(self, joints_deg, speed, zone, tool_kg):
        self.joints = joints_deg
        self.calls.append(("move", joints_deg, speed, zone, tool_kg))
        self.now += 2.0

    def joints_deg(self):
        return self.joints

    def group_input(self, name):
        self.calls.append(("gi", name))
        self.count = (self.count + 3) % 2**32
        return self.count

    def has_group_input(self, name):
        return name.startswith("wc_giCount")

    def open_file(self, path, append):
        self.calls.append(("open", path, append))
        return 7

    def write_file(self, handle, text, newline=True):
        assert handle == 7
        self.open_text += text
        if newline:
            self.lines.append(self.open_text)
            self.open_text = ""

    def close_file(self, handle):
        self.calls.append(("close", handle))

    def tp_write(self, text):
        self.pendant.append(text)

    def tp_erase(self):
        self.calls.append(("erase",))

    def tp_read_num(self, prompt):
        self.pendant.append(prompt)
        return 1.0

    def grip_load(self, mass_kg, cog_mm):
        self.calls.append(("gripload", mass_kg, cog_mm))

    def wait_time(self, seconds):
        self.now += seconds

    def now_s(self):
        return self.now

    def stop(self, why):
        self.calls.append(("stop", why))


def run(*body: str, data: tuple[str, ...] = (), extra: tuple[str, ...] = ()):
    """Run PROC main() of a module with ``data``, ``body`` and ``extra`` routines."""
    text = "\n".join(["MODULE T", *data, *extra, "PROC main()", *body, "ENDPROC", "ENDMODULE", ""])
    ctl = FakeController()
    return run_module(text, "t.mod", ctl), ctl


def single(x: float) -> float:
    return struct.unpack("f", struct.pack("f", x))[0]


def test_num_is_single_precision_and_dnum_double() -> None:
    _, ctl = run(
        "n := 8388608;",
        "n := n * 2 + 1;",
        "d := 8388608;",
        "d := d + 1;",
        "x := 0.1;",
        'TPWrite "" \\Num:=n;',
        'TPWrite "" \\Dnum:=d;',
        'TPWrite NumToStr(x * 3, 9) + " " + DnumToStr(NumToDnum(x), 12);',
        data=("VAR num n;", "VAR dnum d;", "VAR num x;"),
    )
    # 16777217 is not a single-precision number: n rounds to 16777216 (2^24; the kernel
    # promises exact integers to 8388608 only)
    assert ctl.pendant[0] == "16777216"
    assert ctl.pendant[1] == "8388609"
    # 0.1 as a single is 0.100000001490116...; times 3 in single precision
    x3 = single(single(0.1) * 3)
    assert ctl.pendant[2] == f"{x3:.9f} {single(0.1):.12f}"
    assert abs(x3 - 0.3) > 1e-9


def test_div_mod_and_arithmetic() -> None:
    _, ctl = run(
        'TPWrite "" \\Num:=14 DIV 4;',
        'TPWrite "" \\Num:=14 MOD 4;',
        'TPWrite "" \\Num:=-14 DIV 4;',
        'TPWrite "" \\Num:=2 + 3 * 4 - 8 / 2;',
        'TPWrite "" \\Num:=Round(2.345 \\Dec:=2) + Trunc(-1.7);',
    )
    assert ctl.pendant == ["3", "2", "-3", "10", "1.35"]


def test_arithmetic_executed_is_counted() -> None:
    """Each +, -, *, /, DIV, MOD and Sqrt executed counts once; a negation, a comparison,
    a string's + and the FOR loop's own step do not."""
    body = [
        "x := 1 + 2 * 3 - 4 / 2;",  # add 2, mul 1, div 1
        "FOR i FROM 1 TO 5 DO",
        "  x := x + Sqrt(x);",  # 5 × (add, sqrt)
        "ENDFOR",
        "d := SqrtDnum(d * d);",  # mul, sqrt
        "x := 7 DIV 2 + 7 MOD 2;",  # div 2, add 1
        "x := -x;",
        "IF x < 3 THEN",
        '  TPWrite "a" + "b";',
        "ENDIF",
    ]
    text = "\n".join(
        ["MODULE T", "VAR num x;", "VAR dnum d := 2;", "PROC main()", *body, "ENDPROC", "ENDMODULE"]
    )
    interp = load_module(text, "t.mod", FakeController())
    assert interp.ops == {}
    assert interp.execute().status == "completed"
    assert interp.ops == {"add": 8, "mul": 2, "div": 3, "sqrt": 6}


def test_division_by_zero_stops() -> None:
    outcome, ctl = run("n := 1 / n;", data=("VAR num n;",))
    assert outcome.status == "error"
    assert "division by zero" in outcome.message
    assert ctl.calls[-1][0] == "stop"


@pytest.mark.parametrize(
    ("write", "what"),
    [('TPWrite "" \\Dnum:=d;', "a written number"), ("TPWrite DnumToStr(d, 2);", "NumToStr")],
)
def test_an_infinite_number_written_stops_the_run_with_a_rapid_error(write, what) -> None:
    """A dnum overflowed to infinity, then written: the run stops with the RAPID error and
    its line, not Python's OverflowError (an exploring Hypothesis run found it)."""
    outcome, ctl = run("d := 1E300;", "d := d * 1E300;", write, data=("VAR dnum d;",))
    assert outcome.status == "error"
    assert outcome.message.startswith(f"{what}: inf is not a finite number")
    assert ctl.pendant == []


def test_control_flow() -> None:
    _, ctl = run(
        "VAR num s := 0;",
        "FOR i FROM 1 TO 10 DO",
        "  IF i MOD 2 = 0 THEN",
        "    s := s + i;",
        "  ELSEIF i = 5 THEN",
        "    s := s + 100;",
        "  ENDIF",
        "ENDFOR",
        "FOR j FROM 5 TO 1 DO",
        "  s := s + 1000;",
        "ENDFOR",
        "WHILE s > 2000 DO",
        "  s := s - 1000;",
        "ENDWHILE",
        "TEST s",
        "CASE 1, 2:",
        "  s := 0;",
        "CASE 1130:",
        "  s := -1;",
        "DEFAULT:",
        "  s := -2;",
        "ENDTEST",
        'TPWrite "s " \\Num:=s;',
    )
    # 2+4+6+8+10 = 30, +100 at 5; 5 passes of the down-counting loop: 5130; WHILE → 1130
    assert ctl.pendant == ["s -1"]


def test_routines_inout_func_and_records() -> None:
    _, ctl = run(
        "VAR num k := 1;",
        "bump k;",
        "bump k \\Twice;",
        "jt := CJointT();",
        "jt.robax.rax_2 := twice(jt.robax.rax_2);",
        "a{2, 1} := 7;",
        "MoveAbsJ jt \\NoEOffs, v100, fine, tool0;",
        'TPWrite "k" \\Num:=k + a{2, 1};',
        data=("VAR jointtarget jt;", "VAR num a{2, 2};"),
        extra=(
            "PROC bump(INOUT num x, \\switch Twice)",
            "  x := x + 1;",
            "  IF Present(Twice) x := x + 10;",
            "ENDPROC",
            "FUNC num twice(num v)",
            "  RETURN 2 * v - 3;",
            "ENDFUNC",
        ),
    )
    # k: 1 → 2 → 13; a{2,1} = 7
    assert ctl.pendant == ["k20"]
    move = next(c for c in ctl.calls if c[0] == "move")
    assert move[1] == (0.0, -3.0, 0.0, 0.0, 0.0, 0.0)
    assert move[2] == (100.0, 500.0, 5000.0, 1000.0)
    assert move[3] == "fine"
    assert move[4] == 0.0  # tool0: no tool load (RAPID Reference Manual, tooldata)


def test_file_group_input_and_clock() -> None:
    _, ctl = run(
        'Open "HOME:" \\File:="wc.log", log \\Write;',
        "ClkReset clk;",
        "ClkStart clk;",
        "first := GInputDnum(wc_gi);",
        "WaitTime 1.2345;",
        "d := GInputDnum(wc_gi) - first;",
        'Write log, "t " + NumToStr(ClkRead(clk), 3) \\NoNewLine;',
        'Write log, " d" \\Dnum:=d;',
        'Write log, "big " + DnumToStr(first, 0);',
        "Close log;",
        data=("VAR iodev log;", "VAR clock clk;", "VAR dnum first;", "VAR dnum d;"),
    )
    assert ("open", "HOME:/wc.log", False) in ctl.calls
    # ClkRead: whole milliseconds of 1.2345 s
    assert ctl.lines == ["t 1.234 d3", "big 4294967003"]
    assert ("close", 7) in ctl.calls


def test_stop_and_exit() -> None:
    outcome, _ = run("Stop;", 'TPWrite "after";')
    assert outcome.status == "paused"
    outcome, ctl = run("EXIT;", 'TPWrite "after";')
    assert outcome.status == "halted"
    assert ctl.pendant == []


def test_string_over_80_characters_stops() -> None:
    outcome, _ = run(
        'VAR string s := "' + "x" * 60 + '";',
        "s := s + s;",
    )
    assert outcome.status == "error"
    assert "120 characters" in outcome.message


def test_index_out_of_range_stops() -> None:
    outcome, _ = run("VAR num i := 4;", "a{i} := 1;", data=("VAR num a{3};",))
    assert outcome.status == "error"
    assert "outside 1..3" in outcome.message


def test_checker_problems_refuse_the_run() -> None:
    with pytest.raises(WirecalError, match="unknown instruction Frob"):
        run("Frob;")
    with pytest.raises(WirecalError, match=r"MoveAbsJ \\Conc: the twin does not run it"):
        run("MoveAbsJ \\Conc, jt, v100, fine, tool0;", data=("VAR jointtarget jt;",))


BEYOND = {
    "MoveL": ("MoveL p, v100, fine, tool0;", ("VAR robtarget p;",), "the data type robtarget"),
    "SetDO": ("SetDO do1, 1;", (), "SetDO: a RAPID instruction"),
    "GOTO": ("l1:", (), "a label \\(GOTO\\)"),
    "RAISE": ("RAISE 10;", (), "RAISE"),
    "INTNO": ("IF INTNO = 1 Stop;", (), "INTNO: RAPID's predefined data"),
    "an error the subset does not name": ("IF ERRNO = ERR_OVERFLOW Stop;", (), "ERR_OVERFLOW"),
    "late binding": ('%"main"%;', (), "late binding"),
    "a named argument": ("WaitTime Time:=1;", (), "a named required argument"),
}


@pytest.mark.parametrize(("body", "data", "named"), BEYOND.values(), ids=list(BEYOND))
def test_rapid_the_checker_accepts_and_the_twin_does_not_run_is_refused_by_name(
    body: str, data: tuple[str, ...], named: str
) -> None:
    """Valid RAPID (the checker passes it) beyond the subset stops before anything runs."""
    ctl = FakeController()
    text = module(body, data=data)
    assert check(text, "t.mod") == []
    with pytest.raises(WirecalError, match=named + ".*not in wirecal's RAPID subset"):
        run_module(text, "t.mod", ctl)
    assert ctl.calls == []
    assert ctl.pendant == []


def test_number_formats() -> None:
    assert fixed(2.5, 0) == "3"
    assert fixed(-0.00001, 3) == "0.000"
    assert fixed(-1.25, 1) == "-1.3"
    assert number_text(3.0000001, 6) == "3"
    assert number_text(0.25, 6) == "0.25"


def test_the_generated_module_runs_to_its_end() -> None:
    """The golden module of examples/abb_irb120 (rapid2's generator) lints clean and runs."""
    from .conftest import ROOT

    text = (ROOT / "tests" / "golden" / "abb_irb120" / "WIRECAL.mod").read_text(encoding="ascii")
    ctl = FakeController()
    ctl.group_input = lambda name: 1000  # type: ignore[method-assign]  # the wire does not move
    outcome = run_module(text, "WIRECAL.mod", ctl, "wc_run")
    assert outcome.status == "completed", outcome
    assert ctl.lines[0].startswith("# wirecal-log")
    assert ctl.lines[-1] == "# end"
    moves = [c for c in ctl.calls if c[0] == "move"]
    assert len(moves) > 45
    assert all(c[3] == "fine" for c in moves)


def test_recursion_without_end_stops() -> None:
    text = "MODULE T\nPROC main()\n  main;\nENDPROC\nENDMODULE\n"
    outcome = run_module(text, "t.mod", FakeController())
    assert outcome.status == "error"
    assert "nested more than 40 deep" in outcome.message


def test_an_absent_optional_argument_stops_when_read() -> None:
    outcome, ctl = run(
        "show;",
        "show \\x:=2;",
        extra=(
            "PROC show(\\num x)",
            '  IF Present(x) TPWrite "x" \\Num:=x;',
            '  TPWrite "y" \\Num:=x;',
            "ENDPROC",
        ),
    )
    assert outcome.status == "error"
    assert "optional argument x is not present" in outcome.message
    assert ctl.pendant == []


def test_a_func_returns_data_of_its_type() -> None:
    _, ctl = run(
        'TPWrite NumToStr(tenth() * 13, 9) + " " + DnumToStr(dtenth() * 13, 12);',
        extra=(
            "FUNC num tenth()",
            "  RETURN 0.1;",
            "ENDFUNC",
            "FUNC dnum dtenth()",
            "  RETURN 0.1;",
            "ENDFUNC",
        ),
    )
    # the num: 0.1 rounded to single, times 13, rounded again: 1.300000072 (not 1.299999952,
    # what 0.1 * 13 in double rounded once would give)
    assert ctl.pendant == ["1.300000072 1.300000000000"]


# ---------- ERROR handlers, RAISE, AliasIO (the generated module's, issue 32) ----------
def test_an_error_handler_sees_errno_and_returns() -> None:
    outcome, ctl = run(
        "VAR num x := 0;",
        "x := 1 / x;",
        'TPWrite "not reached";',
        "ERROR",
        "IF ERRNO = ERR_DIVZERO THEN",
        '  TPWrite "divided by zero";',
        "  RETURN;",
        "ENDIF",
        "RAISE;",
    )
    assert outcome.status == "completed", outcome
    assert ctl.pendant == ["divided by zero"]


def test_raise_in_a_handler_passes_the_error_on() -> None:
    outcome, ctl = run(
        "inner;",
        'TPWrite "not reached";',
        extra=(
            "PROC inner()",
            "  VAR num x := 0;",
            "  x := 2 / x;",
            "ERROR",
            '  TPWrite "inner saw it";',
            "  RAISE;",
            "ENDPROC",
        ),
    )
    assert outcome.status == "error", outcome
    assert "division by zero" in outcome.message
    assert ctl.pendant == ["inner saw it"]


def test_a_refused_write_is_err_fileacc_for_the_handler() -> None:
    class FullDisk(FakeController):
        def write_file(self, handle, text, newline=True):
            raise RunError(3, "Write: WIRECAL.LOG: the disk is full")

    text = "\n".join(
        [
            "MODULE T",
            "VAR iodev log;",
            "PROC main()",
            '  Open "HOME:" \\File:="L.LOG", log \\Write;',
            '  Write log, "x";',
            "ERROR",
            '  IF ERRNO = ERR_FILEACC TPWrite "the disk may be full";',
            "  RAISE;",
            "ENDPROC",
            "ENDMODULE",
            "",
        ]
    )
    ctl = FullDisk()
    outcome = run_module(text, "t.mod", ctl)
    assert outcome.status == "error"
    assert "the disk is full" in outcome.message
    assert ctl.pendant == ["the disk may be full"]


def test_aliasio_binds_a_signalgi_variable_to_the_configured_signal() -> None:
    outcome, ctl = run(
        'AliasIO "wc_giCount0", gi;',
        "TPWrite DnumToStr(GInputDnum(gi), 0);",
        data=("VAR signalgi gi;",),
    )
    assert outcome.status == "completed", outcome
    assert ("gi", "wc_giCount0") in ctl.calls


def test_an_unbound_signal_variable_stops_with_a_message() -> None:
    outcome, _ = run("TPWrite DnumToStr(GInputDnum(gi), 0);", data=("VAR signalgi gi;",))
    assert outcome.status == "error"
    assert "the signal variable gi is not bound (AliasIO)" in outcome.message


def test_aliasio_to_a_signal_the_configuration_lacks_runs_the_handler() -> None:
    """The generated wc_bind's pattern: the handler's message, then the error stops the run."""
    outcome, ctl = run(
        'AliasIO "di_missing", gi;',
        "ERROR",
        'IF ERRNO = ERR_ALIASIO_DEF TPWrite "no such group input";',
        "RAISE;",
        data=("VAR signalgi gi;",),
    )
    assert outcome.status == "error"
    assert "AliasIO: no signal di_missing in the I/O configuration" in outcome.message
    assert ctl.pendant == ["no such group input"]


def test_the_generated_module_names_a_missing_counter_signal() -> None:
    """WIRECAL.mod on a controller without wc_giCount0: wc_check says so and stops."""
    from pathlib import Path

    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.gen.rapid.program import module_text

    irb = Path(__file__).resolve().parent.parent / "examples" / "abb_irb120"
    robot = load_robot(irb / "robot.toml")
    text = module_text(robot, load_plan(irb / "plan.toml", robot))

    class Unconfigured(FakeController):
        def has_group_input(self, name):
            return False

    ctl = Unconfigured()
    outcome = load_module(text, "WIRECAL.mod", ctl).execute("wc_check")
    assert outcome.status == "error"
    assert "AliasIO: no signal wc_giCount0" in outcome.message
    assert ctl.pendant[0] == "wirecal: no group input wc_giCount0 in the I/O configuration:"
    assert not [c for c in ctl.calls if c[0] == "gi"]


def test_gripload_tells_the_controller_the_payload_and_load0_none() -> None:
    """GripLoad of a loaddata: its mass (kg) and centre (mm); load0: no payload."""
    _, ctl = run(
        "GripLoad wc_load;",
        "GripLoad load0;",
        data=("PERS loaddata wc_load := [2.5, [-10, 0, 50], [1, 0, 0, 0], 0, 0, 0];",),
    )
    loads = [c for c in ctl.calls if c[0] == "gripload"]
    assert loads == [("gripload", 2.5, (-10.0, 0.0, 50.0)), ("gripload", 0.0, (0.0, 0.0, 0.0))]


def test_the_twin_refuses_pos_and_orient_arithmetic_by_name() -> None:
    """pos and orient are the subset's data (a loaddata's parts), not its arithmetic: each
    operation is refused by line before running, never a crash."""
    with pytest.raises(WirecalError, match=r"t.mod:\d+: pos \+ pos: not in wirecal's RAPID subset"):
        run("a := a + a;", data=("VAR pos a := [1, 2, 3];",))
    with pytest.raises(WirecalError, match=r"orient \* orient: not in wirecal's RAPID subset"):
        run("o := o * o;", data=("VAR orient o := [1, 0, 0, 0];",))
