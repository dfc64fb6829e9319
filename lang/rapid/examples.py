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
RM = "RAPID Reference Manual (yumpu.com/en/document/view/5679047)"
TOOLDATA = f"{RM}, pp. 225-227, tooldata"
MOVEJ = "RAPID reference manual, MoveJ (read in translation)"
LOADED_RRC = (
    "unconfirmed; loaded by an IRC5 RobotWare 6 controller: COMPAS RRC's modules, "
    "compas-rrc/compas_rrc_start@4b831ac robotstudio-stations/backups"
)
LOADED_KRAKER = "unconfirmed; loaded by an IRC5 controller: SDEBEUL/Kraker1@5a5835c (a backup)"
LOADED_PALLET = (
    "unconfirmed; loaded by an IRC5 controller: EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e"
)


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
    f"a PERS tooldata of the tool's load, moved with ({TOOLDATA})": module(
        "MoveAbsJ jt, v100, fine, grip;",
        "grip.tload.mass := 0.5;",
        data=(
            "PERS tooldata grip := [TRUE, [[0, 0, 100], [1, 0, 0, 0]], "
            "[0.4, [0, 0, 30], [1, 0, 0, 0], 0, 0, 0]];",
            "CONST jointtarget jt := [[0, -30, 30, 0, 60, 0], [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];",
        ),
    ),
    f"a PERS tooldata parameter passed on to a move ({TOOLDATA})": (
        "MODULE T\n  PROC go(jointtarget jt, PERS tooldata t)\n"
        "    MoveAbsJ jt, v100, fine, t;\n  ENDPROC\nENDMODULE\n"
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
    f"robtarget, tooldata, wobjdata and MoveJ/L/C ({RM} p. 211; {MOVEJ})": "\n".join(
        [
            "MODULE T",
            "  TASK PERS tooldata gripper := [TRUE, [[0, 0, 120], [1, 0, 0, 0]],"
            " [1.5, [0, 0, 40], [1, 0, 0, 0], 0, 0, 0]];",
            '  PERS wobjdata table := [FALSE, TRUE, "", [[400, 0, 10], [1, 0, 0, 0]],'
            " [[0, 0, 0], [1, 0, 0, 0]]];",
            "  CONST robtarget p1 := [[500, 0, 300], [0, 0, 1, 0], [0, 0, 0, 0],"
            " [9E9, 9E9, 9E9, 9E9, 9E9, 9E9]];",
            "  VAR robtarget p2;",
            "  PROC main()",
            "    p2 := Offs(p1, 0, 50, 0);",
            "    p2.trans.z := p2.trans.z - 20;",
            "    MoveJ p1, v500, z10, gripper \\WObj:=table;",
            "    MoveL p2, v100 \\V:=120, fine, gripper \\WObj:=table;",
            "    MoveC \\Conc, p1, p2, v100, z5 \\Z:=4, gripper;",
            "    MoveL Offs(p2, 0, 0, 30), v100, z0, tool0;",
            "    ConfL \\Off;",
            "  ENDPROC",
            "ENDMODULE",
            "",
        ]
    ),
    f"a RECORD, its literal and components; an ALIAS ({UNCONFIRMED})": "\n".join(
        [
            "MODULE T(SYSMODULE, NOSTEPIN)",
            "  RECORD sample",
            "    num count;",
            "    string label;",
            "    pos where;",
            "  ENDRECORD",
            "  ALIAS num metres;",
            '  LOCAL VAR sample s := [3, "first", [1, 2, 3]];',
            "  VAR metres m := 2;",
            "  PROC main()",
            "    s.where.x := s.count * m;",
            '    s.label := s.label + "!";',
            "  ENDPROC",
            "ENDMODULE",
            "",
        ]
    ),
    f"a TRAP, CONNECT … WITH, ITimer, ISignalDI, IDelete ({RM} p. 112)": "\n".join(
        [
            "MODULE T",
            "  VAR intnum tick;",
            "  VAR intnum door;",
            "  VAR num ticks := 0;",
            "  PROC main()",
            "    CONNECT tick WITH on_tick;",
            "    ITimer 0.5, tick;",
            "    CONNECT door WITH on_tick;",
            "    ISignalDI \\Single, di_door, 1, door;",
            "    WaitTime 2;",
            "    IDelete tick;",
            "    IDelete door;",
            "  ENDPROC",
            "  TRAP on_tick",
            "    ticks := ticks + 1;",
            "    IF INTNO = door RETURN;",
            "  ENDTRAP",
            "ENDMODULE",
            "",
        ]
    ),
    f"an ERROR handler with ERRNO, RETRY, TRYNEXT, RAISE ({RM} p. 385-386)": module(
        "tries := tries + 1;",
        "IF tries > 3 RAISE 10;",
        "ERROR",
        "  IF ERRNO = ERR_SOCK_TIMEOUT AND tries < 3 RETRY;",
        "  IF ERRNO = 10 RAISE;",
        "  TRYNEXT;",
        data=("VAR num tries := 0;",),
    ),
    f"GOTO a label of the routine ({UNCONFIRMED})": module(
        "again:",
        "n := n + 1;",
        "IF n < 3 GOTO again;",
        data=("VAR num n := 0;",),
    ),
    f"sockets and string functions ({UNCONFIRMED}: SocketCreate … SocketClose)": module(
        "SocketCreate sock;",
        'SocketConnect sock, "192.168.125.5", 1025 \\Time:=5;',
        'SocketSend sock \\Str:="hello" + ValToStr(n);',
        "SocketReceive sock \\Str:=reply \\Time:=10;",
        "IF SocketGetStatus(sock) = SOCKET_CONNECTED THEN",
        "  ok := StrToVal(StrPart(reply, 1, StrLen(reply) - 1), n);",
        '  n := n + StrFind(reply, 1, ",");',
        "ENDIF",
        "SocketClose sock;",
        data=(
            "VAR socketdev sock;",
            "VAR string reply;",
            "VAR num n := 1;",
            "VAR bool ok;",
        ),
    ),
    f"digital I/O and waits ({UNCONFIRMED}: SetDO, Set, Reset, PulseDO, WaitDI, WaitUntil)": module(
        "SetDO do_grip, 1;",
        "Set do_lamp;",
        "Reset do_lamp;",
        "PulseDO \\PLength:=0.2, do_lamp;",
        "WaitDI di_part, 1 \\MaxTime:=3 \\TimeFlag:=late;",
        "WaitUntil DOutput(do_grip) = 1 OR late;",
        "SetGO go_code, 5;",
        data=("VAR bool late;",),
    ),
    f"a switch, exclusive optional, VAR parameters, a named argument ({UNCONFIRMED})": "\n".join(
        [
            "MODULE T",
            "  PROC main()",
            "    VAR num x := 0;",
            "    bump x, Amount:=2 \\Twice;",
            "    bump x, 1 \\Once;",
            "  ENDPROC",
            "  PROC bump(VAR num v, num Amount \\switch Once | switch Twice)",
            "    v := v + Amount;",
            "    IF Present(Twice) v := v + Amount;",
            "  ENDPROC",
            "ENDMODULE",
            "",
        ]
    ),
    f"raw bytes, SetAO, IDisable/IEnable, CRobT and RelTool ({UNCONFIRMED}; SetAO: {RM} p. 409)": (
        module(
            "ClearRawBytes raw;",
            "PackRawBytes 7, raw, 1 \\IntX:=DINT;",
            "PackRawBytes 1.5, raw, RawBytesLen(raw) + 1 \\Float4;",
            "UnpackRawBytes raw \\Network, 1, n \\IntX:=DINT;",
            "SetAO ao_speed, n / 2;",
            "IDisable;",
            "here := RelTool(CRobT(\\Tool:=tool0 \\WObj:=wobj0), 0, 0, -10 \\Rz:=90);",
            "IEnable;",
            data=("VAR rawbytes raw;", "VAR num n;", "VAR robtarget here;"),
        )
    ),
    f"late binding: a procedure called by its name ({UNCONFIRMED})": module(
        '%"step" + ValToStr(n)%;',
        data=("VAR num n := 1;",),
    ).replace("ENDMODULE", "  PROC step1()\n  ENDPROC\nENDMODULE"),
    # --- RAPID as controllers load it (issue 32): the evidence is a public module that an
    # IRC5 controller held (a backup), cited; the rule itself is unconfirmed (no page read)
    f"the controller's %%% header before MODULE ({LOADED_KRAKER})": (
        "%%%\n  VERSION:1\n  LANGUAGE:ENGLISH\n%%%\n\n" + module('TPWrite "x";')
    ),
    f"a conditional argument \\Fast?Fast passes an optional parameter on ({LOADED_RRC})": (
        "MODULE T\n  PROC go(\\switch Fast)\n    move \\Fast?Fast;\n  ENDPROC\n"
        "  PROC move(\\switch Fast)\n  ENDPROC\nENDMODULE\n"
    ),
    f"a placeholder <SMT> in a routine ({LOADED_PALLET})": module("<SMT>"),
    f"routine data hides module data of its name ({LOADED_RRC})": module(
        "VAR num n;", "n := 2;", data=("VAR num n := 1;",)
    ),
    f"an array sized by a CONST declared further down ({LOADED_RRC})": module(
        "a{1} := 1;", data=("VAR num a{size};", "CONST num size := 4;")
    ),
    f"an array parameter {{*}} after a switch ({LOADED_RRC})": (
        "MODULE T\n  VAR num a{3};\n  PROC sum(\\switch Twice, num v{*})\n"
        '    TPWrite "" \\Num:=v{1};\n  ENDPROC\n  PROC main()\n    sum \\Twice, a;\n'
        "  ENDPROC\nENDMODULE\n"
    ),
    f"an ALIAS is its base type (a RECORD component, a FUNC's value) ({UNCONFIRMED})": (
        "MODULE T\n  ALIAS num level;\n  RECORD probe\n    level l;\n  ENDRECORD\n"
        "  VAR probe p;\n  FUNC level twice(level x)\n    RETURN 2 * x + p.l;\n  ENDFUNC\n"
        "ENDMODULE\n"
    ),
    f"UIMessageBox, btnres, icondata; WaitUntil \\Visualize \\Header \\Message \\Icon "
    f"({LOADED_RRC})": module(
        'answer := UIMessageBox(\\Header:="h" \\MsgArray:=["a", "b"] \\BtnArray:=["", "OK"]);',
        'WaitUntil TRUE \\PollRate:=0.1 \\Visualize \\Header:="h" \\Message:="m" \\Icon:=iconInfo;',
        data=("VAR btnres answer;",),
    ),
    f"TPWrite \\Pos, Stop \\AllMoveTasks, GetSysInfo \\SWVersionName ({LOADED_RRC})": module(
        'TPWrite "at " \\Pos:=p.trans;',
        "TPWrite GetSysInfo(\\SWVersionName);",
        "Stop \\AllMoveTasks;",
        data=("VAR robtarget p;",),
    ),
    f"file, data and EGM routines: IsFile, MakeDir, GetDataVal, RobOS, DotProd ({LOADED_RRC})": (
        module(
            'IF NOT IsFile("HOME:/logs" \\Directory) MakeDir "HOME:/logs";',
            'GetDataVal "n", n;',
            "IF RobOS() n := DotProd(p, p) + VectMagn(p);",
            "EOffsSet [0, 0, 0, 0, 0, 0];",
            data=("VAR num n;", "VAR pos p;"),
        )
    ),
    f"tasks data with its task names; egm_minmax ({LOADED_RRC})": module(
        "mm.min := -1;",
        data=('PERS tasks all{2} := [["T_ROB1"], ["T_ROB2"]];', "VAR egm_minmax mm := [-1, 1];"),
    ),
    f"a pos plus an aggregate, a signal variable read as its value ({LOADED_KRAKER})": module(
        "p := [10, 10, 30] + p;",
        "IF sig = 1 p := 2 * p;",
        data=("VAR pos p;", "VAR signaldi sig;"),
    ),
    f"AliasIO from a string naming the signal ({LOADED_KRAKER})": module(
        'AliasIO "di_1", sig;', data=("VAR signaldi sig;",)
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
    f"a CONST tooldata in a move: a tool is an entire persistent ({TOOLDATA})": (
        module(
            "MoveAbsJ jt, v100, fine, grip;",
            data=(
                "CONST tooldata grip := [TRUE, [[0, 0, 0], [1, 0, 0, 0]], "
                "[0.4, [0, 0, 30], [1, 0, 0, 0], 0, 0, 0]];",
                "VAR jointtarget jt;",
            ),
        ),
        "5: MoveAbsJ's Tool: a tooldata PERS, whole",
    ),
    f"an IN tooldata parameter in a move, not a persistent ({TOOLDATA})": (
        "MODULE T\n  PROC go(jointtarget jt, tooldata t)\n"
        "    MoveAbsJ jt, v100, fine, t;\n  ENDPROC\nENDMODULE\n",
        "3: MoveAbsJ's Tool: a tooldata PERS, whole",
    ),
    f"an element of a tooldata array in a move ({TOOLDATA})": (
        module(
            "MoveAbsJ jt, v100, fine, tools{1};",
            data=("PERS tooldata tools{2};", "VAR jointtarget jt;"),
        ),
        "5: MoveAbsJ's Tool: a tooldata PERS, whole",
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
    f"RETRY outside an ERROR handler ({UNCONFIRMED})": (
        module("RETRY;"),
        "3: RETRY outside an ERROR handler",
    ),
    f"RAISE without an error number outside a handler ({RM} p. 385)": (
        module("RAISE;"),
        "3: RAISE without an error number outside an ERROR handler",
    ),
    f"GOTO a label the routine has not ({UNCONFIRMED})": (
        module("GOTO nowhere;"),
        "3: GOTO nowhere: no label nowhere: in this routine",
    ),
    f"CONNECT with a PROC, not a TRAP ({RM} p. 112)": (
        module("CONNECT i WITH main;", data=("VAR intnum i;",)),
        "4: CONNECT … WITH main: no TRAP main in the task",
    ),
    f"CONNECT to an undeclared interrupt ({RM} p. 112: a variable of type intnum)": (
        "MODULE T\n  PROC main()\n    CONNECT i WITH t;\n  ENDPROC\n"
        "  TRAP t\n  ENDTRAP\nENDMODULE\n",
        "3: unknown data name i",
    ),
    f"MoveL to a jointtarget ({MOVEJ}: ToPoint is a robtarget)": (
        module("MoveL jt, v100, fine, tool0;", data=("VAR jointtarget jt;",)),
        "4: MoveL's ToPoint is a robtarget, not a jointtarget",
    ),
    f"a robtarget literal of three parts ({RM} p. 211: trans, rot, robconf, extax)": (
        module("", data=("CONST robtarget p := [[1, 2, 3], [1, 0, 0, 0], [0, 0, 0, 0]];",)),
        "2: 3 values for a robtarget, which has 4 components",
    ),
    f"a component a robtarget has not ({RM} p. 211)": (
        module("p.trans.w := 1;", data=("VAR robtarget p;",)),
        "4: pos has no component w",
    ),
    f"a RECORD component of an unknown type ({UNCONFIRMED})": (
        "MODULE T\n  RECORD r\n    nums a;\n  ENDRECORD\nENDMODULE\n",
        "2: unknown data type nums",
    ),
    f"SetDO's signal given as a number ({UNCONFIRMED})": (
        module("SetDO 4, 1;"),
        "3: SetDO's Signal is the name of a digital output signal (signaldo)",
    ),
    f"StrPart with two arguments ({UNCONFIRMED})": (
        module('s := StrPart("abc", 1);', data=("VAR string s;",)),
        "4: StrPart takes 3 argument(s)",
    ),
    f"SocketCreate on a num ({UNCONFIRMED})": (
        module("SocketCreate n;", data=("VAR num n;",)),
        "4: SocketCreate's Socket is a socketdev, not a num",
    ),
    f"a named argument out of its place ({UNCONFIRMED})": (
        module("MoveL Speed:=v100, p, fine, tool0;", data=("VAR robtarget p;",)),
        "4: MoveL: Speed := where ToPoint is due",
    ),
    f"a late-bound name that is not a string ({UNCONFIRMED})": (
        module("%n%;", data=("VAR num n;",)),
        "4: a late-bound procedure's name is a string, not a num",
    ),
    f"a TRAP called as a procedure ({RM} p. 112: an interrupt transfers control to it)": (
        "MODULE T\n  PROC main()\n    t;\n  ENDPROC\n  TRAP t\n  ENDTRAP\nENDMODULE\n",
        "3: t is a TRAP: an interrupt runs it, a call cannot",
    ),
    f"TRYNEXT outside an ERROR handler ({UNCONFIRMED})": (
        module("TRYNEXT;"),
        "3: TRYNEXT outside an ERROR handler",
    ),
    f"WaitDI compared with a string ({UNCONFIRMED})": (
        module('WaitDI di1, "1";'),
        "3: WaitDI's Value is a num, not a string",
    ),
    f"a wobjdata literal of four parts ({UNCONFIRMED}: robhold, ufprog, ufmec, uframe, oframe)": (
        module("", data=('PERS wobjdata w := [FALSE, TRUE, "", [[0, 0, 0], [1, 0, 0, 0]]];',)),
        "2: 4 values for a wobjdata, which has 5 components",
    ),
    f"text after ENDMODULE ({UNCONFIRMED})": (
        "MODULE T\nENDMODULE\n{0;0}\n",
        "3: '{' after ENDMODULE: a file holds one module and nothing after it",
    ),
    f"UnpackRawBytes into a constant ({UNCONFIRMED}: its Value is written)": (
        module(
            "UnpackRawBytes raw, 1, k \\Float4;", data=("VAR rawbytes raw;", "CONST num k := 1;")
        ),
        "5: k is a CONST: it cannot be assigned",
    ),
    f"SetAO on a digital output's data ({RM} p. 409: Signal is a signalao)": (
        module("SetAO d, 1;", data=("VAR signaldo d;",)),
        "4: SetAO's Signal is the name of an analog output signal (signalao)",
    ),
    f"a PROC named like RAPID's MoveL ({UNCONFIRMED})": (
        "MODULE T\n  PROC MoveL()\n  ENDPROC\nENDMODULE\n",
        "2: MoveL is a RAPID routine's name: rename it",
    ),
    f"a conditional argument on no optional parameter ({UNCONFIRMED})": (
        "MODULE T\n  PROC go(num Fast)\n    move \\Fast?Fast;\n  ENDPROC\n"
        "  PROC move(\\switch Fast)\n  ENDPROC\nENDMODULE\n",
        "3: move \\Fast?Fast: Fast is not an optional parameter of this routine",
    ),
    f"a conditional argument for no such optional argument ({UNCONFIRMED})": (
        "MODULE T\n  PROC go(\\switch Fast)\n    move \\Slow?Fast;\n  ENDPROC\n"
        "  PROC move(\\switch Fast)\n  ENDPROC\nENDMODULE\n",
        "3: move \\Slow: no such optional argument",
    ),
    f"routine data declared twice in one routine ({UNCONFIRMED})": (
        module("VAR num n;", "VAR num n;"),
        "4: n is declared twice",
    ),
    f"an array sized by a VAR, not a CONST ({UNCONFIRMED})": (
        module("a{1} := 1;", data=("VAR num a{size};", "VAR num size := 4;")),
        "2: an array size must be a positive integer",
    ),
    f"an array where an array parameter's {{*}} needs one ({UNCONFIRMED})": (
        "MODULE T\n  PROC sum(\\switch Twice, num v{*})\n  ENDPROC\n  PROC main()\n"
        "    sum \\Twice, 3;\n  ENDPROC\nENDMODULE\n",
        "5: sum's v is a num{*}, not a number",
    ),
    f"a string added to a pos ({UNCONFIRMED})": (
        module('p := p + "x";', data=("VAR pos p;",)),
        "4: pos + string",
    ),
    f"Stop with an optional argument it has not ({UNCONFIRMED})": (
        module("Stop \\AllTasks;"),
        "3: Stop \\AllTasks: no such optional argument",
    ),
    f"WaitUntil \\Icon given a string ({UNCONFIRMED})": (
        module('WaitUntil TRUE \\Icon:="info";'),
        "3: WaitUntil's Icon is a num, not a string",
    ),
    f"an unknown UI function ({UNCONFIRMED})": (
        module('n := UIMessageBoxes(\\Header:="h");', data=("VAR num n;",)),
        "4: unknown function UIMessageBoxes",
    ),
    f"the %%% header not closed ({UNCONFIRMED})": (
        "%%%\n  VERSION:1\n" + module("Stop;"),
        "1: syntax error at '%'",
    ),
    f"a placeholder <SMT> where an expression is due ({UNCONFIRMED})": (
        module("n := <SMT>;", data=("VAR num n;",)),
        "4: syntax error",
    ),
    f"800 chained operators ({UNCONFIRMED}: wirecal's bound)": (
        module("n := " + " + ".join(["1"] * 800) + ";", data=("VAR num n;",)),
        "4: an expression nested more than 100 levels deep",
    ),
}
