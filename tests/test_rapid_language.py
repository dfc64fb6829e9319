"""The RAPID checker both ways: valid modules pass, errors are caught by name.

The modules of both ways are wirecal.lang.rapid.examples (each names its page); those here
are RAPID beyond the twin's subset (clean for the checker, refused by the twin's check),
hostile input and the task scope.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.lang.rapid import Rapid
from wirecal.lang.rapid.checker import Checker, check, check_task
from wirecal.lang.rapid.examples import INVALID, VALID, module
from wirecal.lang.rapid.parser import parse_module


@pytest.mark.parametrize("text", VALID.values(), ids=list(VALID))
def test_valid_modules_pass(text: str) -> None:
    assert check(text, "t.mod") == []


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
    "ERR_OVERFLOW": module("IF ERRNO = ERR_OVERFLOW Stop;"),
    "a BACKWARD handler": module("Stop;", "BACKWARD", "  Stop;"),
    "a named argument": module("WaitTime Time:=1;"),
    "exclusive parameters": "MODULE T\n  PROC p(\\switch a | switch b)\n  ENDPROC\nENDMODULE\n",
    "a VAR parameter": "MODULE T\n  PROC p(VAR num a)\n  ENDPROC\nENDMODULE\n",
    "CONNECT": "MODULE T\n  VAR intnum i;\n  PROC main()\n    CONNECT i WITH t;\n  ENDPROC\n"
    "  TRAP t\n  ENDTRAP\nENDMODULE\n",
    "late binding": module('%"main"%;'),
}


@pytest.mark.parametrize("text", OUTSIDE.values(), ids=list(OUTSIDE))
def test_rapid_beyond_the_subset_lints_clean_and_the_twin_refuses_it(text: str) -> None:
    """Valid RAPID the twin does not run: the checker accepts it; the twin's check
    (``subset=True``, what ``twin.rapid.interp.run_module`` runs first) names it."""
    assert check(text, "t.mod") == []
    refused = Checker(parse_module(text), subset=True).run()
    assert refused
    assert all("not in wirecal's RAPID subset" in m for _, m in refused), refused
    assert not any("unknown" in m or "syntax error" in m for _, m in refused), refused


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
            list('MODULEPROCENDIFTHENVARnum:=;()[]{},.\\"!+-*/<>=%| \n0123456789')
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


def test_external_calls_take_routines_of_other_modules() -> None:
    text = module("wc_helper 1, 2;", "x := other_func(3) + 1;", data=("VAR num x;",))
    assert [p.split(": ", 1)[1][:24] for p in check(text, "t.mod")] == [
        "unknown instruction wc_h",
        "unknown function other_f",
    ]
    assert Rapid().lint(text, "t.mod", external_calls=True) == []
    # RAPID's own routines are still checked against their signatures
    found = Rapid().lint(module("MoveL 1;"), "t.mod", external_calls=True)
    assert [p.split(": ", 1)[1][:25] for p in found] == [
        "MoveL takes 4 argument(s)",
        "MoveL's ToPoint is a robt",
    ]


def test_the_declared_examples_hold() -> None:
    lang = Rapid()
    assert len(lang.valid_examples) >= 7
    assert len(lang.invalid_examples) >= 25
    assert all(lang.lint(e.text, "v.mod", e.software) == [] for e in lang.valid_examples)
    assert all(lang.lint(e.text, "i.mod", e.software) for e in lang.invalid_examples)


OPERATORS = ["+", "-", "*", "/", " DIV ", " MOD ", " AND ", " OR ", "<", "="]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.sampled_from(OPERATORS), min_size=1, max_size=300), st.integers(0, 130))
def test_any_chain_or_nesting_is_answered_never_crashed(ops: list[str], parens: int) -> None:
    """Chained operators and brackets at any depth: problems, never RecursionError."""
    expression = "(" * parens + "1" + "".join(f"{op}1" for op in ops) + ")" * parens
    found = check(module(f"x := {expression};", data=("VAR num x;",)), "t.mod")
    if parens > 100:
        assert any("nested more than 100" in p for p in found), found
    if parens + len(ops) <= 50:
        assert not any("nested" in p for p in found), found


@settings(max_examples=60, deadline=None)
@given(st.text(alphabet=st.sampled_from('-Name "SignalType DI GO EIO_SIGNAL:\\\n x')))
def test_any_configuration_text_reads_without_a_crash(text: str) -> None:
    from wirecal.lang.rapid.eio import config_signals

    signals = config_signals(text)
    assert all(t.startswith("signal") for t in signals.values())


def test_a_for_variable_lives_only_in_its_loop():
    """RAPID Reference Manual, FOR, p. 8-FOR-2 (yumpu.com/en/document/view/5679047, page
    292): "The loop counter (of data type num) can only be accessed from within the FOR loop
    and consequently hides other data and routines that have the same name." Read after
    ENDFOR it is an unknown name; a string i hidden by the loop is a string again after it."""
    loop = ("FOR i FROM 1 TO 3 DO", '  TPWrite "x"\\Num:=i;', "ENDFOR")
    after = Rapid().lint(module(*loop, 'TPWrite "y"\\Num:=i;'), "t.mod")
    assert len(after) == 1
    assert after[0].startswith("t.mod:6: unknown data name i")
    hidden = module(*loop, "TPWrite i;", data=('VAR string i := "s";',))
    assert Rapid().lint(hidden, "t.mod") == []
