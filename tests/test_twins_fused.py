"""The three twins' fused statements (twin/*/fused.py): the closures' behaviour.

An assignment or a condition written out as one Python function must give the very values
(bit for bit), operation counts (and the order each kind was first counted), errors and
lines of the node-by-node closures it replaces; the tests run random programs with the
fused statements and without (the hooks returning None leave every statement to the
closures) and compare. Whole runs (a measurement run and the controller solver: the log's
bytes, the results, counts and console) are compared in the slow test at the end.
"""

from __future__ import annotations

import copy
import math
import struct

import numpy as np
import pytest
from hypothesis import given, reject, settings
from hypothesis import strategies as st

from wirecal.app.compare import controller_runs
from wirecal.app.twin_runs import generate, measure_in_twin
from wirecal.formats.log import load_measurements
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors
from wirecal.lang.urscript.parser import parse_program
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError
from wirecal.twin.machine import RunError
from wirecal.twin.rapid import interp as rapid_interp
from wirecal.twin.urscript import interp as urscript_interp
from wirecal.twin.vplus import interp as vplus_interp

from .conftest import ROOT
from .test_rapid_interp import FakeController
from .test_urscript_twin import Log
from .test_vplus_fused import unfused as vplus_unfused
from .test_vplus_rules import _Console

EXAMPLES = ROOT / "examples"


def _bits(v):
    """A value with its floats as their bits (NaN and -0.0 compared exactly)."""
    if isinstance(v, float):
        return ("float", struct.pack(">d", v))
    if isinstance(v, list):
        return [_bits(x) for x in v]
    if isinstance(v, dict):
        return {k: _bits(x) for k, x in v.items()}
    return (type(v).__name__, v)


def _unfused(monkeypatch_context, module):
    monkeypatch_context.setattr(module, "fused_steps", lambda c, steps, one: list(map(one, steps)))
    monkeypatch_context.setattr(module, "fused_value", lambda *args: None)


def _both(run):
    """Return ``run()`` with the fused statements and without."""
    fused = run()
    with pytest.MonkeyPatch.context() as m:
        _unfused(m, urscript_interp)
        _unfused(m, rapid_interp)
        vplus_unfused(m)
        nodes = run()
    return fused, nodes


# ---------- URScript ----------
UR_LEAVES = ["a", "b", "c", "i", "j", "l[i]", "l[0]", "l[2]", "2.5", "0.0", "3", "0", "7.25"]
UR_LEAVES += ["1000000.0", "2147483647", "True"]


def _ur_expr(arithmetic=("+", "-", "*", "/", "%")):
    return st.recursive(
        st.sampled_from(UR_LEAVES),
        lambda kids: st.one_of(
            st.tuples(kids, st.sampled_from(arithmetic), kids).map(lambda t: f"({' '.join(t)})"),
            kids.map(lambda k: f"-({k})"),
        ),
        max_leaves=8,
    )


def _ur_condition():
    compare = st.tuples(_ur_expr(), st.sampled_from(["<", ">", "<=", ">=", "==", "!="]), _ur_expr())
    single = compare.map(lambda t: f"({' '.join(t)})") | st.sampled_from(["True", "a", "(not i)"])
    return st.recursive(
        single,
        lambda kids: st.tuples(kids, st.sampled_from(["and", "or", "xor"]), kids).map(
            lambda t: f"({' '.join(t)})"
        ),
        max_leaves=3,
    )


UR_VALUE = st.one_of(
    st.floats(width=32),
    st.floats(-1e6, 1e6, width=32),
    st.integers(-(2**31), 2**31 - 1),
    st.integers(-1, 3),
    st.booleans(),
)


def _ur_run(text: str, args: list):
    interp = urscript_interp.Interpreter(parse_program(text, "t.script"), Log())
    try:
        result = ("returned", _bits(interp.function("f")(args)))
    except RunError as e:
        result = ("error", e.message)
    return result, interp.where, list(interp.ops.items()), interp.cell.console


@settings(max_examples=40, deadline=None)
@given(
    exprs=st.lists(_ur_expr(), min_size=4, max_size=4),
    index=st.sampled_from(["i", "j", "0", "(i + 1)", "2"]),
    cond=_ur_condition(),
    values=st.lists(UR_VALUE, min_size=5, max_size=5),
    items=st.lists(UR_VALUE, min_size=3, max_size=3),
)
def test_urscript_fused_statements_give_the_closures_values_counts_and_errors(
    exprs, index, cond, values, items
):
    text = "\n".join(
        [
            "def p():",
            "  def f(a, b, c, i, j, l):",
            f"    x = {exprs[0]}",
            f"    l[{index}] = {exprs[1]}",
            f"    if {cond}:",
            f"      y = {exprs[2]}",
            "    else:",
            f"      y = {exprs[3]}",
            "    end",
            "    textmsg(str_cat(x, y))",
            "    return [x, y, l]",
            "  end",
            "end",
            "",
        ]
    )
    try:
        parse_program(text, "t.script")
    except WirecalError:
        reject()  # a constant int that overflows 32 bits: the checker refuses the program
    fused, nodes = _both(lambda: _ur_run(text, [*values, list(items)]))
    assert fused == nodes


def _written(monkeypatch, module) -> list:
    """Record the functions the module's hooks return (a statement's, a run's, a condition's)."""
    made: list = []
    for name in ("fused_steps", "fused_value"):
        original = getattr(module, name)

        def hook(*args, f=original):
            got = f(*args)
            made.extend(got if isinstance(got, list) else [got])
            return got

        monkeypatch.setattr(module, name, hook)
    return made


def _generated(made: list) -> int:
    return sum(getattr(f, "__code__", None) is not None and f.__name__ == "fused" for f in made)


def test_urscript_statements_are_fused(monkeypatch):
    """The comparison above is not vacuous: the program's statements are written out."""
    made = _written(monkeypatch, urscript_interp)
    text = "def p():\n  a = 1.5\n  b = a * a + 2\n  if b > a and a < 2:\n    b = -b\n  end\nend\n"
    interp = urscript_interp.Interpreter(parse_program(text, "t.script"), Log())
    interp.execute()
    assert interp.globals["b"] == -4.25
    assert _generated(made) == 3  # the first two assignments, the condition, the third


# ---------- RAPID ----------
def _rapid_expr(leaves):
    return st.recursive(
        st.sampled_from(leaves),
        lambda kids: st.one_of(
            st.tuples(kids, st.sampled_from(["+", "-", "*", "/", "DIV", "MOD"]), kids).map(
                lambda t: f"({' '.join(t)})"
            ),
            kids.map(lambda k: f"-({k})"),
        ),
        max_leaves=8,
    )


NUM_LEAVES = ["a", "b", "c", "r{i}", "r{2}", "m{i, 2}", "2.5", "0", "3", "1000000", "p{1}"]
DNUM_LEAVES = ["d", "e", "NumToDnum(a)", "2.5", "0", "3"]
RAPID_DATA = (
    "VAR num a;",
    "VAR num b;",
    "VAR num c;",
    "VAR num i;",
    "VAR dnum d;",
    "VAR dnum e;",
    "VAR num x;",
    "VAR dnum y;",
    "VAR bool t;",
    "VAR num r{3};",
    "VAR num m{2, 2};",
    "VAR num p{2};",
)
NUM = st.one_of(st.floats(width=32), st.floats(-1e6, 1e6, width=32), st.integers(-2, 4))


def _rapid_run(text: str, values: dict):
    ctl = FakeController()
    interp = rapid_interp.load_module(text, "t.mod", ctl)
    for name, v in values.items():
        interp.globals[name] = copy.deepcopy(v)
    out = interp.execute("main")
    named = {k: _bits(interp.globals[k]) for k in ("x", "y", "t", "r", "m", "p")}
    return out, named, list(interp.ops.items()), ctl.calls, ctl.pendant


@settings(max_examples=40, deadline=None)
@given(
    nums=st.lists(_rapid_expr(NUM_LEAVES), min_size=3, max_size=3),
    dnum=_rapid_expr(DNUM_LEAVES),
    compare=st.sampled_from(["<", ">", "<=", ">=", "=", "<>"]),
    logic=st.sampled_from(["AND", "OR", "XOR"]),
    values=st.lists(NUM, min_size=8, max_size=8),
    dnums=st.lists(st.floats() | st.integers(-2, 4), min_size=2, max_size=2),
)
def test_rapid_fused_statements_give_the_closures_values_counts_and_errors(
    nums, dnum, compare, logic, values, dnums
):
    body = [
        f"x := {nums[0]};",
        f"y := {dnum};",
        f"r{{i}} := {nums[1]};",
        f"t := {nums[0]} {compare} {nums[2]} {logic} NOT (y < d);",
        f"IF x {compare} {nums[1]} OR t THEN",
        f"  m{{2, i}} := {nums[2]};",
        "ELSE",
        "  p{2} := -x;",
        "ENDIF",
        'TPWrite "x " \\Num:=x;',
    ]
    text = "\n".join(["MODULE T", *RAPID_DATA, "PROC main()", *body, "ENDPROC", "ENDMODULE", ""])
    single = [float(np.float32(v)) for v in values]
    given_values = dict(zip("abci", single, strict=False))
    given_values |= {"d": float(dnums[0]), "e": float(dnums[1])}
    given_values |= {"r": single[4:7], "m": [[single[7], 1.0], [2.0, 3.0]], "p": [0.5, 0.0]}
    if not math.isfinite(given_values["i"]) or given_values["i"] == int(given_values["i"]):
        given_values["i"] = float(min(max(int(np.nan_to_num(given_values["i"])), -1), 4))
    fused, nodes = _both(lambda: _rapid_run(text, given_values))
    assert fused == nodes


def test_rapid_statements_are_fused(monkeypatch):
    """The comparison above is not vacuous: the module's statements are written out."""
    made = _written(monkeypatch, rapid_interp)
    body = ["a := 1.5;", "d := NumToDnum(a) * 2;", "IF a > 1 AND d < 4 THEN", "  a := -a;"]
    text = "\n".join(["MODULE T", "VAR num a;", "VAR dnum d;", "PROC main()", *body])
    text += "\nENDIF\nENDPROC\nENDMODULE\n"
    interp = rapid_interp.load_module(text, "t.mod", FakeController())
    interp.execute("main")
    assert (interp.globals["a"], interp.globals["d"]) == (-1.5, 3.0)
    assert _generated(made) == 3  # the first two assignments, the condition, the third


# ---------- whole runs ----------
PLAN_FILES = {"viper_s650": "paper_plan.toml"}
"""An arm's plan where it is not plan.toml."""


@pytest.mark.slow
@pytest.mark.parametrize("arm", ["ur5e", "abb_irb120", "viper_s650"])
def test_whole_runs_are_the_same_with_the_fused_statements(arm, tmp_path):
    """A measurement run's log bytes and outcomes, the controller solver's results, counts
    and console: the same with the fused statements and without."""
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    plan = load_plan(EXAMPLES / arm / PLAN_FILES.get(arm, "plan.toml"), robot)
    programs = generate(robot, plan)
    truth = random_errors(robot, 2.0, np.random.default_rng(5))
    folders = iter(tmp_path / str(k) for k in range(2))

    def whole_run():
        folder = next(folders)
        run = measure_in_twin(robot, plan, truth, folder / "run", programs, seed=3)
        m = load_measurements(run.log, plan, robot)
        solved = controller_runs(robot, plan, m, folder / "solve", programs=programs)
        results = {k: (r.offsets, list(r.operations.items()), r.console) for k, r in solved.items()}
        return run.log.read_bytes(), run.mount, run.run, results

    fused, nodes = _both(whole_run)
    assert fused[1].status == fused[2].status == "completed"
    assert fused == nodes


@pytest.mark.parametrize("fused", [True, False])
@pytest.mark.parametrize(
    ("statement", "message"),
    [
        ("x := a DIV 2;", "DIV of inf: DIV and MOD take integers"),
        ("x := 7 MOD b;", "MOD of nan: DIV and MOD take integers"),
        ("x := r{a};", "index inf outside 1..3"),
        ("r{b} := 1;", "index nan outside 1..3"),
        ("x := r{2.5};", "index 2.5 outside 1..3"),
    ],
)
def test_rapid_nan_and_infinity_stop_the_run_with_a_rapid_error(
    statement, message, fused, monkeypatch
):
    """An infinite or NaN operand of DIV/MOD or index is the run's error, not a traceback."""
    if not fused:
        _unfused(monkeypatch, rapid_interp)
    text = "\n".join(
        ["MODULE T", *RAPID_DATA, "PROC main()", statement, "ENDPROC", "ENDMODULE", ""]
    )
    interp = rapid_interp.load_module(text, "t.mod", FakeController())
    interp.globals["a"], interp.globals["b"] = math.inf, math.nan
    interp.globals["r"] = [0.0, 0.0, 0.0]
    out = interp.execute("main")
    assert (out.status, out.message) == ("error", message)


# ---------- one line in two programs ----------
# The line parsers keep a line's node by its text and copy it shallowly, so a line's
# expressions are the same objects in every program that has the line: what is written
# for an expression must follow the program it runs in (its slots, its scopes).


def test_a_vplus_line_in_two_programs_uses_each_programs_slots(viper, paper_plan, tmp_path):
    """The same ``s = e*(1-e2*(…))`` lines, ``e2`` at slot 1 in one program, 0 in the next."""
    from wirecal.lang.vplus.parser import parse_module
    from wirecal.twin.vplus.controller import VplusController
    from wirecal.twin.vplus.interp import Interpreter
    from wirecal.twin.world import World

    lines = "    e2 = e*e\n    s = e*(1-e2*(1-e2*3))\n"
    first = ".PROGRAM t.main()\n    GLOBAL DOUBLE e, s\n    AUTO DOUBLE z, e2\n"
    first += f"    z = 1\n{lines}.END\n"
    second = f".PROGRAM t.main()\n    GLOBAL DOUBLE e, s\n    AUTO DOUBLE e2\n{lines}.END\n"
    for text, e in ((first, 0.5), (second, 0.25)):
        cell = VplusController(World(viper, {}, paper_plan.theta0_deg, tmp_path))
        interp = Interpreter(parse_module(text, "t.v2"), cell)
        interp.set_global("e", e)
        assert interp.execute("t.main").status == "completed"
        assert interp.get_global("s") == e * (1 - e * e * (1 - e * e * 3))


def test_a_urscript_condition_in_two_places_reads_each_places_variable():
    """``if n > 0:`` reads a global in one function and a local in the other."""
    text = "\n".join(
        [
            "def p():",
            "  n = 5",
            "  def g():",
            "    r = 0",
            "    if n > 0:",
            "      r = 1",
            "    end",
            "    return r",
            "  end",
            "  def f(x):",
            "    local n = x",
            "    r = 0",
            "    if n > 0:",
            "      r = 1",
            "    end",
            "    return r + 10 * g()",
            "  end",
            "end",
        ]
    )
    interp = urscript_interp.Interpreter(parse_program(text, "t.script"), Log())
    interp.globals["n"] = 5  # as p's body sets it
    assert interp.function("f")([-1]) == 10  # f's local n is -1; g reads the global n = 5


# ---------- V+ ----------
# AUTO REAL a, i, ar[], u (never set); AUTO DOUBLE d, da[]; LOCAL lo; GLOBAL REAL g, gr[];
# GLOBAL DOUBLE gd, gda[]; the parameter p (a closure, by reference)
VPLUS_LEAVES = ["a", "d", "g", "gd", "lo", "p", "i", "ar[i]", "ar[1]", "da[i]", "gr[i]"]
VPLUS_LEAVES += ["gda[i+1]", "gr[2]", "gr[d]", "ar[d]", "u", "2.5", "0", "3", "1E30", "^D2"]
VPLUS_LEAVES += ["PI", "ABS(a)", "(NOT d)"]


def _vplus_expr():
    return st.recursive(
        st.sampled_from(VPLUS_LEAVES),
        lambda kids: st.one_of(
            st.tuples(kids, st.sampled_from(["+", "-", "*", "/", "MOD"]), kids).map(
                lambda t: f"({' '.join(t)})"
            ),
            st.tuples(kids, st.sampled_from(["<", ">", "<=", ">=", "==", "<>"]), kids).map(
                lambda t: f"({' '.join(t)})"
            ),
            kids.map(lambda k: f"-({k})"),
            kids.map(lambda k: f"SQRT({k})"),
        ),
        max_leaves=8,
    )


VPLUS_VALUE = st.one_of(
    st.floats(width=32),
    st.floats(-1e6, 1e6),
    st.integers(-2, 3),
    st.sampled_from([0.5, -0.0, 1e300, "s"]),
)

VPLUS_PROGRAM = """.PROGRAM t.main(p)
    GLOBAL DOUBLE gd, gda[], r1, r2, r3
    GLOBAL g, gr[], gi
    LOCAL lo
    AUTO a, i, ar[4], u
    AUTO DOUBLE d, da[4]
    i = gi
    a = g
    d = gd
    lo = gr[0]
    ar[1] = gr[1]
    ar[2] = a
    da[1] = gda[1]
    da[2] = g
    r1 = {0}
    d = {1}
    ar[i] = {2}
    gr[i+1] = {3}
    IF {4} THEN
        r2 = {5}
        a = {6}
    ELSE
        r3 = {7}
    END
    TYPE a, d
.END
"""


def _vplus_run(text: str, values: dict, *, fuse: bool):
    interp = vplus_interp.Interpreter(parse_module(text, "t.v2"), _Console())
    for (name, index), v in values.items():
        interp.set_global(name, v, index)
    with pytest.MonkeyPatch.context() as m:
        if not fuse:
            vplus_unfused(m)
        try:
            out = interp.execute("t.main", values[("p", None)])
            result = (out.status, out.program, out.line, out.message, out.console)
        except (TypeError, ValueError, OverflowError, struct.error) as e:  # Python errors, alike
            result = (type(e).__name__, str(e), interp.where)
    globals_ = {k: _bits(v) for k, v in interp.gvals.items()}
    arrays = {k: _bits(v) for k, v in interp.garr.items() if v}
    return result, globals_, arrays, list(interp.ops.items())


@settings(max_examples=40, deadline=None)
@given(
    exprs=st.lists(_vplus_expr(), min_size=8, max_size=8),
    values=st.lists(VPLUS_VALUE, min_size=8, max_size=8),
    index=st.sampled_from([0.0, 1.0, 1.4, 2.6, -1.0, 3]),
)
def test_vplus_fused_statements_give_the_closures_values_counts_and_errors(exprs, values, index):
    """Random V+ programs: the same values (bits), counts (in order), errors, lines, console.

    AUTO, LOCAL and GLOBAL scalars and arrays, REAL and DOUBLE, a parameter, numbers of
    both precisions, every arithmetic operator, comparisons, NOT, unary minus and SQRT
    (a closure inside written code); an undefined AUTO, a zero divisor, a negative index,
    single-precision overflow, NaN, an int and a string among the values.
    """
    text = VPLUS_PROGRAM.format(*exprs)
    names = [("g", None), ("gd", None), ("gr", 0), ("gr", 1), ("gda", 1), ("gr", 2)]
    given_values = dict(zip(names, values, strict=False))
    given_values[("gda", 2)] = values[6]
    given_values[("p", None)] = values[7]
    given_values[("gi", None)] = index
    fused = _vplus_run(text, given_values, fuse=True)
    nodes = _vplus_run(text, given_values, fuse=False)
    assert fused == nodes
