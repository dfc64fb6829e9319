"""``wirecal lint`` on V+, both ways: constructs a controller takes, and constants and names
it refuses. Programs are written here for the test; each case names its page (UG = V+
Language User's Guide v17) or says the keyword's page was not read ("unconfirmed")."""

from __future__ import annotations

import re

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.gen.vplus.literals import MAX_MANTISSA, double_literal
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError


def prog(body: str) -> str:
    return ".PROGRAM t.main()\n" + body + "\n.END\n"


def problems(text: str) -> list[str]:
    try:
        parse_module(text, "t.v2")
    except WirecalError as exc:
        return exc.problems
    return []


ACCEPTED = {
    # motion and hand instructions (keywords: unconfirmed, their pages not read)
    "approach and depart": "SET p = HERE\nAPPRO p, 50\nAPPROS p, 20\nDEPART 30\nDEPARTS 30",
    "hand": "OPENI\nCLOSEI\nOPEN\nCLOSE\nRELAXI",
    "EXIT a loop": "i = 0\nWHILE TRUE DO\n    i = i+1\n    IF i > 3 THEN\n        EXIT\n"
    "    END\nEND",
    # the ends of the ranges: labels 0..65535 (UG p. 35), integers -16777216..16777215,
    # ^B up to 8 bits, doubles to about 1E+307 (UG p. 102), strings of 128 (UG p. 100)
    "range ends": (
        "65535 x = 16777215\ny = -16777216\nz = ^B11111111\nw = 1E+306\n"
        'd = ^D9007199254740992\nr = 16777216.0\n$s = "' + "a" * 128 + '"'
    ),
    "digits inside names and strings are no numbers": 'x99999999 = 1\n$s = "99999999999"',
}


@pytest.mark.parametrize("case", sorted(ACCEPTED))
def test_valid_v_plus_accepted(case):
    assert problems(prog(ACCEPTED[case])) == []


REJECTED = [
    # (body, problem, page)
    ("70000 x = 1", "label 70000: a step label is an integer 0 to 65535", "UG p. 35"),
    ('$s = "' + "b" * 130 + '"', "a string constant of 130 characters", "UG p. 100"),
    ("x = 1E+400", "1E+400: beyond the double-precision range", "UG p. 102"),
    ("x = 16777216", "16777216: beyond the integer range", "UG p. 102"),
    ("x = -16777217", "16777217: beyond the integer range", "UG p. 102"),
    ("x = ^H1000000", "^H1000000: beyond the integer range", "UG p. 102"),
    ("x = ^B111111111", "a ^B constant has at most 8 bits", "UG p. 102"),
    ("d = ^D9007199254740993", "beyond 2^53", "UG p. 102"),
    # keywords as names (UG p. 99; the keywords themselves unconfirmed)
    ("fine = 1", "'fine' is a V+ keyword", "unconfirmed"),
    ("AUTO hand", "'hand' is a V+ keyword", "unconfirmed"),
    ("inverse = 2", "'inverse' is a V+ keyword", "unconfirmed"),
    ("latch = 3", "'latch' is a V+ keyword", "unconfirmed"),
    ("LOCAL inrange", "'inrange' is a V+ keyword", "unconfirmed"),
    ("identical = 4", "'identical' is a V+ keyword", "unconfirmed"),
]


@pytest.mark.parametrize(("body", "message", "page"), REJECTED)
def test_invalid_v_plus_rejected(body, message, page):
    found = problems(prog(body))
    assert any(message in p for p in found), (page, found)
    assert all(p.startswith("t.v2:") for p in found)


@settings(max_examples=200, deadline=None)
@given(st.integers(min_value=0, max_value=2**30))
def test_whole_number_constants_pass_exactly_inside_the_integer_range(n):
    assert (problems(prog(f"x = {n}")) == []) == (n <= 16_777_215)
    assert (problems(prog(f"x = -{n}")) == []) == (n <= 16_777_216)


@settings(max_examples=300, deadline=None)
@given(st.floats(min_value=-1e12, max_value=1e12).filter(lambda x: abs(x) >= 1e-6))
def test_double_literals_are_whole_doubles_and_close(x):
    # |x| >= 1e-6: the powers of ten wc.p10[] go to 10^22, so 16 digits down to 1e-6
    text = double_literal(x)
    m = re.fullmatch(r"(-?)\^D(\d+)(?:/wc\.p10\[(\d+)\])?", text)
    if m is None:  # a whole number within the integer range, written plainly
        assert float(text) == x
        assert abs(x) < 2**24
        return
    assert int(m.group(2)) <= MAX_MANTISSA
    value = (-1 if m.group(1) else 1) * int(m.group(2)) / 10 ** int(m.group(3) or 0)
    assert abs(value - x) <= 1.2e-15 * abs(x)


# ---------- the conveyor-tracking option, checked before any motion (UG pp. 310, 317) ----------
def test_without_the_conveyor_option_nothing_moves(viper, paper_plan, tmp_path):
    from wirecal.twin.world import Faults

    from .conftest import TABLE5
    from .twin_runs import measure_in_twin

    r = measure_in_twin(
        viper, paper_plan, TABLE5, tmp_path, seed=1, faults=Faults(no_conveyor_option=True)
    )
    assert r.run is not None
    assert r.run.status == "halted"
    assert any("conveyor-tracking option" in line for line in r.run.console)
    assert r.world.moves == 0  # the moves of wc.run (run_measurement counts from wc.run on)
    assert r.world.lines_written == 0  # no log line
    # with the option, the same run moves: the count above is the run's own
    ok = measure_in_twin(viper, paper_plan, TABLE5, tmp_path / "ok", seed=1)
    assert ok.run is not None
    assert ok.world.moves > 70


def test_switch_takes_a_system_switch():
    assert problems(prog("x = SWITCH(BELT)\ny = SWITCH(POWER)")) == []
    found = problems(prog("AUTO k\nk = 1\nx = SWITCH(k)"))
    assert any("SWITCH needs a system switch name" in p for p in found), found
