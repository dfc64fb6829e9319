"""Small RAPID modules the checker must accept, and ones it must refuse, with their pages.

Each module is written for wirecal (never copied from others' modules) and names the page its
rule comes from (:mod:`.tables` lists what was read); "unconfirmed" marks a rule wirecal
holds to without a page read. The tests (tests/test_rapid_language.py) and the registry's
conformance suite (:attr:`wirecal.lang.rapid.Rapid.valid_examples`, ``invalid_examples``)
run them; an invalid one carries "LINE: the problem" the checker must report.
"""

from __future__ import annotations

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


VALID: dict[str, str] = {
    # name (the page) → a module the checker accepts
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


INVALID: dict[str, tuple[str, str]] = {
    # name (the page) → (a module, "LINE: the problem the checker reports")
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
