"""An interpreter of the URScript wirecal generates, with the UR controller's numbers.

Programs are compiled into Python closures once, dispatching on the node types of
:mod:`wirecal.lang.urscript.nodes`, as the V+ interpreter does. What the interpreter
holds to, and how sure we are of it (see :mod:`wirecal.gen.urscript.facts`):

* ints are 32-bit and floats 32-bit (UR16e User Manual p. 181, *confirmed*): every float
  literal, result and stored value is rounded to IEEE single precision (:func:`f32`); an
  int result outside [-2^31, 2^31[ wraps, two's complement (*unconfirmed*: the
  controller's behaviour on overflow was not read; the generated programs rely on it to
  unwrap the raw count by subtraction);
* int op int is an int for ``+ - * %``, ``/`` gives a float, and any float operand makes
  the result a float (*unconfirmed*);
* lists are indexed from 0 and copied on assignment; an index out of range stops the
  program (*unconfirmed*); a struct (what ``time(0)`` returns) is read by member name;
* conditions and ``and``/``or``/``xor``/``not`` take booleans only; strings are joined
  with ``str_cat``, which writes an int as its digits and a float with 6 decimals (SD
  15.51, *confirmed* — see :mod:`wirecal.gen.urscript.facts` for the sources); ``+`` of
  strings stops the program and a boolean is written True/False (*unconfirmed*);
  ``floor`` returns an int (SD 16.9, *confirmed*);
* scope: a variable assigned in the program's own body is global, as is one qualified
  ``global``; inside a function a parameter or a ``local`` variable is local, and a free
  variable is the global of that name if there is one, else local (*unconfirmed*: the
  Script Manual's "Scoping rules" page was not read);
* reading a variable before it has a value stops the program.

Everything the program does to the outside world — motion, the encoder, sockets, the
log and popups, time — goes through the controller
(:class:`wirecal.twin.urscript.controller.URController`).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import fields

from wirecal.lang.syntax import node_method
from wirecal.lang.urscript import nodes as N
from wirecal.lang.urscript.parser import Program, operands, walk
from wirecal.solver.errors import WirecalError
from wirecal.twin.machine import Halt, Kept, Outcome, RunError, Stopped, f32, rounded
from wirecal.twin.urscript.fused import fused_steps, fused_value
from wirecal.twin.urscript.values import (
    COUNTED,
    FLOAT_OPS,
    URError,
    copy_value,
    element,
    i32,
    mixed,
    negative,
    number,
    position,
    to_float,
    to_str,
    truth,
)


class _Return(Exception):
    def __init__(self, value):
        self.value = value


class Interpreter:
    """Runs a parsed program against a cell."""

    def __init__(self, program: Program, cell):
        _check_subset(program, cell)
        self.program, self.cell = program, cell
        self.globals: dict[str, object] = {}
        self.ops: Counter[str] = Counter()  # arithmetic executed: add (+ −), mul, div, sqrt
        self.where = 0
        self._functions: dict[str, Callable] = {}
        self.global_names = _global_names(program)

    def execute(self) -> Outcome:
        """Run the program; its outcome and the lines it wrote to the log (textmsg, popup)."""
        start = len(self.cell.console)
        try:
            self.function(self.program.name)([])
            status, message = "completed", ""
        except Halt:
            status, message = "halted", "halt"
        except Stopped as s:
            status, message = "stopped", str(s)
        except RunError as e:
            status, message = "error", e.message
        except RecursionError:
            status, message = "error", "stack overflow"
        return Outcome(status, self.program.name, self.where, message, self.cell.console[start:])

    def function(self, name: str) -> Callable:
        """Return the compiled function ``name`` (compiled on first use)."""
        fn = self._functions.get(name)
        if fn is None:
            d = self.program.functions[name]
            fn = self._functions[name] = _Compiler(self, d).compile()
        return fn


_UNRUN = (N.Jump, N.Critical, N.ThreadOp, N.Pose, N.RunThread, N.RpcCall)
"""Valid URScript (the checker accepts it) that wirecal never emits and the twin does not run."""


SUBSET_CHECKS_KEPT = 16
"""Programs whose subset check is kept, per kind of cell (a parse is kept by its text: the
twin runs the same programs again and again)."""

_CHECKED = Kept(SUBSET_CHECKS_KEPT)


def _check_subset(program: Program, cell) -> None:
    """Refuse, before running, what the twin does not run: raise :class:`WirecalError`.

    The answer is kept per parsed program and kind of cell (:data:`SUBSET_CHECKS_KEPT`).
    """
    problems = _CHECKED.get(lambda: _subset_problems(program, cell), program, type(cell))
    if problems:
        raise WirecalError(problems)


def _subset_problems(program: Program, cell) -> list[str]:
    """Return what the twin does not run in ``program`` on ``cell``, by line."""
    problems = []
    for s in walk([program.functions[program.name]]):
        where = f"{program.source}:{s.line}"
        if isinstance(s, N.Def) and (s.kind != "def" or s.defaults):
            problems.append(
                f"{where}: {s.kind} {s.name}: threads, sec programs and default "
                "values are not in the URScript subset the twin runs"
            )
        exprs = _expressions(s)
        if isinstance(s, _UNRUN) or any(isinstance(e, _UNRUN) for e in exprs):
            problems.append(f"{where}: not in the URScript subset the twin runs")
        problems += [
            f"{where}: {e.name} is not a function the twin runs"
            for e in exprs
            if isinstance(e, N.Call) and e.name not in program.functions and not _runs(e.name, cell)
        ]
    return sorted(set(problems))


def _expressions(s: N.Stmt) -> list[N.Expr]:
    """Every expression on a statement's line, nested ones included."""
    todo = [getattr(s, f.name) for f in fields(s)]
    todo = [e for e in todo if isinstance(e, N.Expr)]
    if isinstance(s, N.Assign):
        todo += s.target.indices
    if isinstance(s, N.If):
        todo += [c for c, _ in s.branches]
    out = []
    while todo:
        e = todo.pop()
        out.append(e)
        todo += operands(e)
    return out


def _global_names(program: Program) -> set[str]:
    """Names that are global: assigned in the program's own body, or qualified ``global``."""
    names = {s.target.name for s in program.body if isinstance(s, N.Assign) and s.scope != "local"}
    names |= {
        s.target.name for s in walk(program.body) if isinstance(s, N.Assign) and s.scope == "global"
    }
    return names


class _Compiler:
    """Compiles one function into a closure taking its argument values."""

    def __init__(self, interp: Interpreter, d: N.Def):
        self.i, self.d = interp, d
        self.place: object = d  # what fixes a name's scope here (fused_code.recipe_of)
        self.main = d.name == interp.program.name
        own = [s for s in walk(d.body) if not isinstance(s, N.Def)]
        self.locals = set(d.params) | {
            s.target.name for s in own if isinstance(s, N.Assign) and s.scope == "local"
        }

    def is_global(self, name: str) -> bool:
        if name in self.locals:
            return False
        return self.main or name in self.i.global_names

    def compile(self) -> Callable:
        body = self.body(self.d.body)
        params = self.d.params

        def run(args):
            frame = dict(zip(params, args, strict=True))
            try:
                body(frame)
            except _Return as r:
                return r.value
            return None

        return run

    def body(self, steps: list[N.Stmt]) -> Callable:
        fns = fused_steps(self, [s for s in steps if not isinstance(s, N.Def)], self.stmt)

        def run(frame):
            for f in fns:
                f(frame)

        return run

    # ---------- statements ----------
    def stmt(self, s: N.Stmt) -> Callable:
        interp, line, inner = self.i, s.line, self._stmt(s)

        def run(frame):
            interp.where = line
            inner(frame)

        return run

    @node_method
    def _stmt(self, s: N.Stmt) -> Callable:  # pragma: no cover - every statement is registered
        raise AssertionError(type(s).__name__)

    @_stmt.register
    def _(self, s: N.Assign):
        value = self.expr(s.value)
        name = s.target.name
        store = self.i.globals if self.is_global(name) else None
        if not s.target.indices:

            def assign(frame):  # a list or struct is copied (_copy), a number or string not
                v = value(frame)
                (frame if store is None else store)[name] = (
                    copy_value(v) if isinstance(v, (list, dict)) else v
                )

            return assign
        get = self.read(name)
        indices = [self.expr(e) for e in s.target.indices]

        def assign_element(frame):
            container = get(frame)
            for ix in indices[:-1]:
                container = element(container, ix(frame))
            k = position(container, indices[-1](frame))
            container[k] = copy_value(value(frame))

        return assign_element

    @_stmt.register
    def _(self, s: N.CallStmt):
        f = self.expr(s.call)
        return lambda frame: f(frame)

    @_stmt.register
    def _(self, s: N.Return):
        value = self.expr(s.value) if s.value is not None else (lambda frame: None)

        def ret(frame):
            raise _Return(value(frame))

        return ret

    @_stmt.register
    def _(self, s: N.HaltStmt):
        def halt(frame):
            raise Halt("halt")

        return halt

    @_stmt.register
    def _(self, s: N.While):
        cond, body = self.condition(s.cond), self.body(s.body)

        def while_(frame):
            while truth(cond(frame)):
                body(frame)

        return while_

    @_stmt.register
    def _(self, s: N.If):
        branches = [(self.condition(c), self.body(b)) for c, b in s.branches]
        other = self.body(s.orelse)

        def if_(frame):
            for cond, body in branches:
                if truth(cond(frame)):
                    body(frame)
                    return
            other(frame)

        return if_

    # ---------- expressions ----------
    def condition(self, e: N.Expr) -> Callable:
        """Compile a condition: written out as one function where it can be (``fused``)."""
        return fused_value(self, e) or self.expr(e)

    def read(self, name: str) -> Callable:
        """Compile the read of a variable; reading one without a value stops the program."""
        store = self.i.globals if self.is_global(name) else None

        def get(frame):
            try:
                return (store if store is not None else frame)[name]
            except KeyError:
                raise URError(f"variable {name} has no value") from None

        return get

    @node_method
    def expr(self, e: N.Expr) -> Callable:  # pragma: no cover - every expression is registered
        raise AssertionError(type(e).__name__)

    @expr.register
    def _(self, e: N.Num):
        v = e.value if e.is_int else f32(e.value)
        return lambda frame: v

    @expr.register
    def _(self, e: N.Bool):
        v = e.value
        return lambda frame: v

    @expr.register
    def _(self, e: N.Str):
        v = e.text
        return lambda frame: v

    @expr.register
    def _(self, e: N.Var):
        return self.read(e.name)

    @expr.register
    def _(self, e: N.ListLit):
        items = [self.expr(x) for x in e.items]
        return lambda frame: [f(frame) for f in items]

    @expr.register
    def _(self, e: N.Index):
        base, ix = self.expr(e.base), self.expr(e.index)
        return lambda frame: element(base(frame), ix(frame))

    @expr.register
    def _(self, e: N.Field):
        base, name = self.expr(e.base), e.name

        def member(frame):
            value = base(frame)
            if not isinstance(value, dict) or name not in value:
                raise URError(f"{to_str(value)!r} has no member {name}")
            return value[name]

        return member

    @expr.register
    def _(self, e: N.Neg):
        f = self.expr(e.expr)

        return lambda frame: negative(f(frame))

    @expr.register
    def _(self, e: N.Not):
        f = self.expr(e.expr)
        return lambda frame: not truth(f(frame))

    @expr.register
    def _(self, e: N.Logic):
        a, b = self.expr(e.left), self.expr(e.right)
        if e.op == "and":
            return lambda frame: truth(a(frame)) and truth(b(frame))
        if e.op == "or":
            return lambda frame: truth(a(frame)) or truth(b(frame))
        return lambda frame: truth(a(frame)) != truth(b(frame))

    @expr.register
    def _(self, e: N.Compare):
        a, b, op = self.expr(e.left), self.expr(e.right), _COMPARE[e.op]
        ordered = e.op not in ("==", "!=")

        def compare(frame):
            x, y = a(frame), b(frame)
            if ordered:
                number(x, e.op), number(y, e.op)
            return op(x, y)

        return compare

    @expr.register
    def _(self, e: N.BinOp):
        return _arithmetic(self.i, e.op, self.expr(e.left), self.expr(e.right))

    @expr.register
    def _(self, e: N.Call):
        args = [self.expr(a) for a in e.args]
        kwargs = {k: self.expr(v) for k, v in e.kwargs.items()}
        interp = self.i
        if e.name in interp.program.functions:
            name = e.name
            return lambda frame: interp.function(name)([copy_value(a(frame)) for a in args])
        builtin = _builtin(interp, e.name)

        def call(frame):
            return builtin(*(a(frame) for a in args), **{k: v(frame) for k, v in kwargs.items()})

        return call


_COMPARE: dict[str, Callable] = {
    "==": lambda x, y: x == y,
    "!=": lambda x, y: x != y,
    "<": lambda x, y: x < y,
    ">": lambda x, y: x > y,
    "<=": lambda x, y: x <= y,
    ">=": lambda x, y: x >= y,
}


def _arithmetic(interp: Interpreter, op: str, a: Callable, b: Callable) -> Callable:
    """Compile ``a op b``, counting the operations as executed (module docstring)."""
    kind, divides, ops = COUNTED[op], op in "/%", interp.ops
    single, other = rounded(FLOAT_OPS[op]), mixed(op, ops)

    def f(frame):
        x, y = a(frame), b(frame)
        if type(x) is float and type(y) is float:  # the usual case: two numbers, no int
            ops[kind] += 1
            if divides and y == 0:
                raise URError("division by zero")
            return single(x, y)
        return other(x, y)

    return f


def _runs(name: str, cell) -> bool:
    """Tell whether :func:`_builtin` has a Python function for ``name``."""
    return name == "sqrt" or name in _PURE or callable(getattr(cell, name, None))


def _builtin(interp: Interpreter, name: str) -> Callable:
    """Return the Python function behind a URScript function (pure ones here, else the cell's)."""
    if name == "sqrt":
        return _sqrt(interp)
    return _PURE.get(name) or getattr(interp.cell, name)


def _sqrt(interp: Interpreter) -> Callable:
    def sqrt(f):
        v = to_float(f)
        if v < 0:
            raise URError(f"sqrt of a negative number ({to_str(v)})")
        interp.ops["sqrt"] += 1
        return f32(math.sqrt(v))

    return sqrt


def _floor(f) -> int:
    return i32(math.floor(number(f, "floor")))


def _round(f) -> int:
    return i32(math.floor(number(f, "round") + 0.5))


def _to_num(s) -> int | float:
    text = str(s).strip()
    try:
        return i32(int(text))
    except ValueError:
        pass
    try:
        return f32(float(text))
    except ValueError:
        raise URError(f"to_num: {text!r} is not a number") from None


def _not_a_string(v) -> int:
    raise URError(f"str_len of {to_str(v)!r}, which is not a string")


def _length(v) -> int:
    if not isinstance(v, list):
        raise URError(f"get_list_length of {to_str(v)!r}, which is not a list")
    return len(v)


_PURE: dict[str, Callable] = {
    "str_cat": lambda a, b: to_str(a) + to_str(b),
    "str_len": lambda s: len(s) if isinstance(s, str) else _not_a_string(s),
    "floor": _floor,
    "round": _round,
    "to_num": _to_num,
    "fabs": lambda f: abs(number(f, "fabs")),
    "sin": lambda f: f32(math.sin(to_float(f))),
    "cos": lambda f: f32(math.cos(to_float(f))),
    "atan2": lambda y, x: f32(math.atan2(to_float(y), to_float(x))),
    "r2d": lambda r: f32(math.degrees(to_float(r))),
    "d2r": lambda d: f32(math.radians(to_float(d))),
    "norm": lambda a: (
        f32(math.sqrt(sum(to_float(x) ** 2 for x in a)))
        if isinstance(a, list)
        else abs(number(a, "norm"))
    ),
    "get_list_length": _length,
}
