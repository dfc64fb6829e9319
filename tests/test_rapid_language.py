"""The RAPID checker both ways: small modules of the subset pass, errors are caught by name.

Each module is written here and names the page its rule comes from (lang/rapid/tables.py
lists what was read); "unconfirmed" marks a rule wirecal holds to without a page read.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.lang.rapid import Rapid
from wirecal.lang.rapid.checker import check, check_task

KERNEL_TYPES = "RAPID kernel, built-in data types (num, dnum, string)"
MOVEABSJ = "RAPID reference manual, MoveAbsJ"
UNCONFIRMED = "unconfirmed"


def module(*body: str, data: tuple[str, ...] = ()) -> str:
    """Return a module with ``data`` and a PROC main() holding ``body``."""
    return "\n".join(
        ["MODULE T", *(f"  {d}" for d in data), "  PROC main()"]
        + [f"    {line}" for line in body]
        + ["  ENDPROC", "ENDMODULE", ""]
    )


VALID = {
    f"MoveAbsJ to a jointtarget, v100, fine, tool0, with \\NoEOffs ({MOVEABSJ})": module(
        "MoveAbsJ jt \\NoEOffs, v100, fine, tool0;",
        "MoveAbsJ [[0, 0, 0, 0, 90, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]], v, z10, tool0;",
        data=(
            "CONST jointtarget jt := [[0, -30, 30, 0, 60, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];",
            "VAR speeddata v := [200, 20, 5000, 1000];",
        ),
    ),
    f"num and dnum arithmetic, literals of either ({KERNEL_TYPES})": module(
        "n := n * 2 + 1 / 3 - 7 DIV 2 + 7 MOD 2;",
        "d := d + 4294967296;",
        "d := d * NumToDnum(n);",
        "n := DnumToNum(d) + Abs(-n) + Sqrt(4) + Round(n \\Dec:=2) + Trunc(n);",
        "n := 8388608;",
        data=("VAR num n := 1;", "VAR dnum d := -4503599627370496;"),
    ),
    f"records and arrays: components, {{i}} and {{i,j}} ({UNCONFIRMED})": module(
        "jt.robax.rax_1 := a{2, 3} + b{1};",
        "jt := CJointT();",
        "b := [1, 2, 3];",
        data=(
            "VAR jointtarget jt;",
            "VAR num a{2, 3} := [[1, 2, 3], [4, 5, 6]];",
            "VAR num b{3};",
        ),
    ),
    f"IF/ELSEIF/ELSE, compact IF, WHILE, FOR with STEP, TEST ({UNCONFIRMED})": module(
        "VAR num k := 0;",
        "IF k > 1 AND NOT (k = 3) OR (k > 0) XOR TRUE = FALSE THEN",
        "  k := 1;",
        "ELSEIF k <> 2 THEN",
        "  k := 2;",
        "ELSE",
        "  Incr k;",
        "ENDIF",
        "IF k < 0 k := 0;",
        "WHILE k < 10 DO",
        "  k := k + 1;",
        "ENDWHILE",
        "FOR i FROM 10 TO 1 STEP -2 DO",
        "  k := k + i;",
        "ENDFOR",
        "TEST k",
        "CASE 1, 2:",
        "  k := 0;",
        "DEFAULT:",
        "  Stop;",
        "ENDTEST",
    ),
    f"the file, the FlexPendant, clocks, the group input ({UNCONFIRMED})": module(
        'Open "HOME:" \\File:="wc.log", log \\Write;',
        'Write log, "count " \\Dnum:=GInputDnum(wc_giCount);',
        'Write log, "head" \\NoNewLine;',
        "Close log;",
        "TPErase;",
        'TPWrite "n = " \\Num:=ClkRead(clk);',
        'TPReadNum answer, "1 = yes";',
        "ClkReset clk;",
        "ClkStart clk;",
        "ClkStop clk;",
        "WaitTime 0.5;",
        'TPWrite "len " + NumToStr(StrLen("abc"), 0) + DnumToStr(GInputDnum(wc_giCount), 0);',
        data=("VAR iodev log;", "VAR clock clk;", "VAR num answer;"),
    ),
    f"FUNC with RETURN, PROC with INOUT and an optional switch ({UNCONFIRMED})": "\n".join(
        [
            "MODULE T",
            "  FUNC dnum delta(dnum now, dnum ref)",
            "    RETURN now - ref;",
            "  ENDFUNC",
            "  PROC bump(INOUT num x, \\switch Twice)",
            "    x := x + 1;",
            "  ENDPROC",
            "  PROC main()",
            "    VAR num k := 0;",
            "    VAR dnum d;",
            "    bump k;",
            "    bump k \\Twice;",
            "    d := delta(10, 3) * 2;",
            "    EXIT;",
            "  ENDPROC",
            "ENDMODULE",
        ]
    ),
    f"case-insensitive keywords and names, comments, module attributes ({UNCONFIRMED})": "\n".join(
        [
            "module t (NOSTEPIN)",
            "  ! a comment",
            "  var num Count := 1; ! after a statement",
            "  proc MAIN()",
            "    count := COUNT + 1;",
            "  endproc",
            "endmodule",
        ]
    ),
}


@pytest.mark.parametrize("text", VALID.values(), ids=list(VALID))
def test_valid_modules_pass(text: str) -> None:
    assert check(text, "t.mod") == []


INVALID = {
    f"unknown instruction ({UNCONFIRMED})": (
        module("Frobnicate 1;"),
        "3: unknown instruction Frobnicate",
    ),
    f"wrong argument count, MoveAbsJ without Tool ({MOVEABSJ})": (
        module("MoveAbsJ jt, v100, fine;", data=("VAR jointtarget jt;",)),
        "4: MoveAbsJ takes 4 argument(s)",
    ),
    f"an optional argument MoveAbsJ has not ({MOVEABSJ})": (
        module("MoveAbsJ jt \\Fast, v100, fine, tool0;", data=("VAR jointtarget jt;",)),
        "4: MoveAbsJ \\Fast: no such optional argument",
    ),
    f"a num where MoveAbsJ takes a jointtarget ({MOVEABSJ})": (
        module("MoveAbsJ 5, v100, fine, tool0;"),
        "3: MoveAbsJ's ToJointPos is a jointtarget, not a number",
    ),
    f"num and dnum mixed ({KERNEL_TYPES})": (
        module("d := d + n;", data=("VAR num n;", "VAR dnum d;")),
        "5: num and dnum mixed",
    ),
    f"a dnum assigned to a num ({KERNEL_TYPES})": (
        module("n := d;", data=("VAR num n;", "VAR dnum d;")),
        "5: n is a num, not a dnum: convert with NumToDnum or DnumToNum",
    ),
    f"a string assigned to a num ({KERNEL_TYPES})": (
        module('n := "5";', data=("VAR num n;",)),
        "4: n is a num, not a string",
    ),
    f"a num added to a string ({KERNEL_TYPES})": (
        module('s := "n = " + 5;', data=("VAR string s;",)),
        "4: string + numeric literal",
    ),
    f"an undeclared name ({UNCONFIRMED})": (
        module("x := 1;"),
        "3: unknown data name x (not declared in this module",
    ),
    f"a reserved word as a name ({UNCONFIRMED}: RAPID kernel, reserved words)": (
        module("", data=("VAR num step;",)),
        "2: step is a RAPID reserved word: it cannot be a name",
    ),
    f"a reserved word as a routine name ({UNCONFIRMED}: RAPID kernel, reserved words)": (
        "MODULE T\n  PROC main()\n    Stop;\n  ENDPROC\n  PROC Retry()\n  ENDPROC\nENDMODULE\n",
        "5: Retry is a RAPID reserved word: it cannot be a name",
    ),
    f"an integer literal beyond num's exact range ({KERNEL_TYPES}: 8388608)": (
        module("n := 8388609;", data=("VAR num n;",)),
        "4: the integer 8388609 is beyond what a num holds exactly",
    ),
    f"missing ENDPROC ({UNCONFIRMED})": (
        "MODULE T\n  PROC main()\n    Stop;\nENDMODULE\n",
        "4: PROC (line 2) without its ENDPROC: found 'ENDMODULE'",
    ),
    f"missing ENDIF ({UNCONFIRMED})": (
        module("IF TRUE THEN", "  Stop;"),
        "5: IF (line 3) without its ENDIF: found 'ENDPROC'",
    ),
    f"a string of 81 characters ({KERNEL_TYPES}: at most 80)": (
        module('TPWrite "' + "x" * 81 + '";'),
        "3: a string of 81 characters: a RAPID string holds at most 80",
    ),
    f"assignment to a CONST ({UNCONFIRMED})": (
        module("k := 2;", data=("CONST num k := 1;",)),
        "4: k is a CONST: it cannot be assigned",
    ),
    f"assignment to a FOR variable ({UNCONFIRMED})": (
        module("FOR i FROM 1 TO 3 DO", "  i := 2;", "ENDFOR"),
        "4: i is a FOR loop variable: it cannot be assigned",
    ),
    f"a FUNC without RETURN ({UNCONFIRMED})": (
        "MODULE T\n  FUNC num f()\n    TPErase;\n  ENDFUNC\nENDMODULE\n",
        "2: the FUNC f has no RETURN",
    ),
    f"RETURN without a value in a FUNC ({UNCONFIRMED})": (
        "MODULE T\n  FUNC num f()\n    RETURN;\n  ENDFUNC\nENDMODULE\n",
        "3: RETURN in the FUNC f needs a num value",
    ),
    f"a condition that is not a bool ({UNCONFIRMED})": (
        module("IF 1 THEN", "  Stop;", "ENDIF"),
        "3: an IF condition is a bool, not a number",
    ),
    f"TPReadNum's answer must be a variable ({UNCONFIRMED})": (
        module('TPReadNum 5, "x";'),
        "3: TPReadNum's Answer must be a variable",
    ),
    f"a component a record has not ({UNCONFIRMED})": (
        module("jt.robax.rax_7 := 1;", data=("VAR jointtarget jt;",)),
        "4: robjoint has no component rax_7",
    ),
    f"an aggregate of the wrong size ({UNCONFIRMED})": (
        module("", data=("VAR num a{3} := [1, 2];",)),
        "2: 2 values for an array of 3",
    ),
    f"a GInputDnum argument that is not a signal name ({UNCONFIRMED})": (
        module("d := GInputDnum(5);", data=("VAR dnum d;",)),
        "4: GInputDnum's Signal is the name of a group input signal",
    ),
    f"an instruction called as a function ({UNCONFIRMED})": (
        module("n := TPErase();", data=("VAR num n;",)),
        "4: TPErase: a RAPID function not in wirecal's RAPID subset",
    ),
}


@pytest.mark.parametrize(("text", "expected"), INVALID.values(), ids=list(INVALID))
def test_invalid_modules_are_caught(text: str, expected: str) -> None:
    found = check(text, "t.mod")
    assert any(p.startswith("t.mod:" + expected.split(":")[0] + ":") for p in found), found
    assert any(expected.split(": ", 1)[1] in p for p in found), found


OUTSIDE = {
    "MoveL": module("MoveL p, v100, fine, tool0;", data=("VAR robtarget p;",)),
    "a TRAP": "MODULE T\n  TRAP t\n    Stop;\n  ENDTRAP\nENDMODULE\n",
    "an ERROR handler": module("Stop;", "ERROR", "  RETRY;"),
    "GOTO and a label": module("l1:", "GOTO l1;"),
    "a RECORD": "MODULE T\n  RECORD r\n    num x;\n  ENDRECORD\nENDMODULE\n",
    "a zonedata variable": module("", data=("VAR zonedata z := z10;",)),
    "SetDO": module("SetDO do1, 1;"),
}


@pytest.mark.parametrize("text", OUTSIDE.values(), ids=list(OUTSIDE))
def test_constructs_outside_the_subset_say_so(text: str) -> None:
    found = check(text, "t.mod")
    assert found
    assert any("not in wirecal's RAPID subset" in p for p in found), found
    assert not any("unknown" in p or "syntax error" in p for p in found), found


def test_software_versions() -> None:
    text = module("Stop;")
    assert check(text, "t.mod", "6.15") == []
    assert check(text, "t.mod", "7.10") == []
    assert check(text, "t.mod", "5.16") == [
        't.mod:1: software = "5.16": wirecal\'s RAPID is written for RobotWare 6 (IRC5) '
        "and 7 (OmniCore)"
    ]


def test_declaration() -> None:
    lang = Rapid()
    assert (lang.key, lang.suffix, lang.live_check) == ("rapid", ".mod", "wc_check")
    caps = lang.capabilities
    assert caps.int_bits is None
    assert caps.float_bits == 32
    assert caps.encoder_interfaces == ("group",)
    assert caps.counter_bits == 32
    assert set(caps.software_lines) == {6, 7}
    assert lang.lint(module("Frobnicate;"), "x.mod") != []


HOSTILE = {
    "an empty file": ("", "1: syntax error at the end of the file"),
    "a NUL byte": ("\x00", "1: unexpected character '\\x00'"),
    "a string left open": (module('TPWrite "abc;'), "3: a string not closed on its line"),
    "two modules in one file": (
        "MODULE A\nENDMODULE\nMODULE B\nENDMODULE\n",
        "3: a second MODULE: one module per file",
    ),
    "3000 nested parentheses": (
        module("n := " + "(" * 3000 + "1" + ")" * 3000 + ";", data=("VAR num n;",)),
        "4: brackets nested more than 100 deep",
    ),
    "2000 nested IFs": (
        module(*["IF TRUE THEN"] * 2000, *["ENDIF"] * 2000),
        "67: blocks nested more than 64 deep",
    ),
    "a dnum literal beyond double": (
        module("", data=("VAR dnum d := 1E400;",)),
        "2: a literal beyond a dnum's range",
    ),
    "a num literal beyond single": (
        module("", data=("VAR num n := 1E39;",)),
        "2: a literal beyond a num's range",
    ),
    "a name of 33 characters (unconfirmed: RAPID kernel, identifiers)": (
        module("", data=("VAR num " + "a" * 33 + ";",)),
        "2: the name " + "a" * 33 + " has 33 characters: RAPID takes 32",
    ),
}


@pytest.mark.parametrize(("text", "expected"), HOSTILE.values(), ids=list(HOSTILE))
def test_hostile_inputs_are_problems_not_tracebacks(text: str, expected: str) -> None:
    found = check(text, "t.mod")
    assert any(p.startswith("t.mod:" + expected) for p in found), found


@given(
    st.text(
        alphabet=st.sampled_from(
            list('MODULEPROCENDIFTHENVARnum:=;()[]{},.\\"!+-*/<>= \n0123456789')
        ),
        max_size=300,
    )
)
@settings(max_examples=200, deadline=None)
def test_any_text_gives_problems_not_exceptions(text: str) -> None:
    found = check("MODULE T\n" + text + "\nENDMODULE\n", "t.mod")
    assert all(p.startswith("t.mod:") for p in found)


def test_a_routine_newer_than_the_software_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    """The tables hold RobotWare 6.0 for every routine; a later one is refused by name."""
    from wirecal.lang.rapid import tables

    newer = tables.Routine(tables.INSTRUCTIONS["tperase"].params, since="6.14")
    monkeypatch.setitem(tables.INSTRUCTIONS, "tperase", newer)
    text = module("TPErase;")
    assert check(text, "t.mod", "6.14") == []
    assert check(text, "t.mod") == []
    assert check(text, "t.mod", "6.13") == [
        "t.mod:3: TPErase needs RobotWare 6.14 (the controller has 6.13)"
    ]


def test_a_task_of_several_modules_shares_global_data_and_routines() -> None:
    """RAPID's task scope (unconfirmed): global data and routines of every module are seen;
    LOCAL ones only in their own module."""
    shared = "\n".join(
        [
            "MODULE Shared",
            "  PERS num count := 0;",
            "  LOCAL VAR num hidden;",
            "  PROC bump()",
            "    count := count + 1;",
            "  ENDPROC",
            "  LOCAL PROC secret()",
            "  ENDPROC",
            "ENDMODULE",
        ]
    )
    main = module("bump;", "count := count * 2;")
    assert check_task({"shared.mod": shared, "main.mod": main}) == []
    assert check(main, "main.mod") != []
    hidden = module("hidden := 1;", "secret;")
    found = check_task({"shared.mod": shared, "main.mod": hidden})
    assert [p.split(":")[:2] for p in found] == [["main.mod", "3"], ["main.mod", "4"]]
