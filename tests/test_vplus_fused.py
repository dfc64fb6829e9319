"""The V+ twin's written-out statements (twin/vplus/fused.py): the closures' numbers.

A run of assignments, a condition or an arithmetic expression written out as one function
must give the very values, operation counts (their order of first count too) and errors
of the closures it replaces; the tests run the same programs with it off and compare
(random programs: tests/test_twins_fused.py).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.lang.vplus.parser import parse_module
from wirecal.twin.vplus import interp as vplus_interp
from wirecal.twin.vplus.controller import VplusController
from wirecal.twin.vplus.interp import Interpreter
from wirecal.twin.world import World

PROGRAM = """.PROGRAM t.main()
    GLOBAL DOUBLE ga, gb, gc, g1, g2, g3
    GLOBAL gr
    AUTO DOUBLE a, b, c, x
    AUTO r, s
    a = ga
    b = gb
    c = gc
    r = gr
    s = r*r+r
    x = a*b+c*a-(b-c)*r
    g1 = x*(a+^D2)-3*c*r
    g2 = a*b*c-x+s*a
    g3 = ((a-b)*(a+b))-(c*c)
    IF a*b > c THEN
        TYPE "more"
    END
.END
"""

FINITE = st.floats(-1e6, 1e6, allow_nan=False)


def unfused(monkeypatch_context) -> None:
    """Leave every V+ statement and expression to the node-by-node closures."""
    monkeypatch_context.setattr(
        vplus_interp, "fused_steps", lambda c, steps, one: [(s, one(s)) for s in steps]
    )
    monkeypatch_context.setattr(vplus_interp, "fused_value", lambda *args: None)


def _run(viper, plan, tmp_path, source, values, *, fuse):
    cell = VplusController(World(viper, {}, plan.theta0_deg, tmp_path))
    interp = Interpreter(parse_module(source, "t.v2"), cell)
    for name, v in values.items():
        interp.set_global(name, v)
    if fuse:
        out = interp.execute("t.main")
    else:
        with pytest.MonkeyPatch.context() as m:
            unfused(m)
            out = interp.execute("t.main")
    results = [interp.gvals.get(g) for g in ("g1", "g2", "g3")]
    return out, results, list(interp.ops.items())


@settings(max_examples=40, deadline=None)
@given(a=FINITE, b=FINITE, c=FINITE, r=FINITE)
def test_fused_arithmetic_gives_the_closures_numbers_and_counts(
    viper, paper_plan, tmp_path_factory, a, b, c, r
):
    tmp_path = tmp_path_factory.mktemp("fused")
    values = {"ga": a, "gb": b, "gc": c, "gr": float(np.float32(r))}
    fused = _run(viper, paper_plan, tmp_path, PROGRAM, values, fuse=True)
    nodes = _run(viper, paper_plan, tmp_path, PROGRAM, values, fuse=False)
    assert fused[0].status == nodes[0].status == "completed"
    assert fused[0].console == nodes[0].console
    assert np.array_equal(np.array(fused[1]), np.array(nodes[1]), equal_nan=True)
    assert fused[2] == nodes[2]  # the counts, and the order each kind was first counted


def test_an_undefined_scalar_in_a_fused_expression_is_the_closures_error(
    viper, paper_plan, tmp_path
):
    source = ".PROGRAM t.main()\n    AUTO DOUBLE a, b, x\n    a = 1\n    x = a*b+a\n.END\n"
    fused = _run(viper, paper_plan, tmp_path, source, {}, fuse=True)
    nodes = _run(viper, paper_plan, tmp_path, source, {}, fuse=False)
    assert fused[0].message == nodes[0].message == "*Undefined value* b (-406)"
    assert (fused[0].program, fused[0].line) == (nodes[0].program, nodes[0].line) == ("t.main", 4)
    assert fused[2] == nodes[2]


def test_the_statements_are_written_out(viper, paper_plan, tmp_path, monkeypatch):
    """The comparisons above are not vacuous: the assignments and the condition are written."""
    runs, values = [], []
    steps, value = vplus_interp.fused_steps, vplus_interp.fused_value

    def steps_spy(c, steps_, one):
        out = steps(c, steps_, one)
        runs.extend(f for _, f in out if getattr(f, "__name__", "") == "fused")
        return out

    def value_spy(c, e):
        out = value(c, e)
        values.append(out)
        return out

    monkeypatch.setattr(vplus_interp, "fused_steps", steps_spy)
    monkeypatch.setattr(vplus_interp, "fused_value", value_spy)
    cell = VplusController(World(viper, {}, paper_plan.theta0_deg, tmp_path))
    Interpreter(parse_module(PROGRAM, "t.v2"), cell).execute("t.main")
    assert len(runs) == 1  # the ten assignments, one function
    assert sum(v is not None for v in values) == 1  # the IF's a*b > c


@pytest.mark.parametrize("k", [float("inf"), float("-inf"), float("nan")])
def test_an_index_that_is_not_a_finite_number_is_the_illegal_index_error(
    viper, paper_plan, tmp_path, k
):
    """An infinite or NaN index stops the run with -407, written out and as closures alike,
    not with Python's OverflowError or ValueError from rounding it."""
    source = (
        ".PROGRAM t.main()\n    GLOBAL gk, g1, ga[]\n    AUTO b[3]\n"
        "    b[gk] = 1\n    ga[gk] = 2\n    g1 = 0\n.END\n"
    )
    fused = _run(viper, paper_plan, tmp_path, source, {"gk": k}, fuse=True)
    nodes = _run(viper, paper_plan, tmp_path, source, {"gk": k}, fuse=False)
    for out in (fused[0], nodes[0]):
        assert out.status == "error"
        assert out.message == f"*Illegal array index* {k} (-407)"
        assert (out.program, out.line) == ("t.main", 4)
    assert fused[2] == nodes[2]
