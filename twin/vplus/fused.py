"""V+ assignments and values written out as one Python function each: the twin's hot path.

The controller solver's programs are long runs of ``x = a*b + c*d - …`` and of array
elements ``wc.fx[b+1] = nx1+px1``; compiled node by node (:mod:`wirecal.twin.vplus.interp`)
each operation, each read of a variable and each statement is a closure call. A run of
assignments, a condition and an arithmetic expression are written out here instead
(:class:`~wirecal.twin.fused_code.Source`) with the closures' semantics, operation by
operation in their order: the operations counted as the nodes count them (a node before
its operands; / and MOD read the divisor first), an operation whose operands are all
single precision rounded to single (User's Guide p. 102: a float result here, any other
through the closures' own rounding, :func:`single_result`), a store into a REAL rounded, a
REAL LOCAL or global read rounded, an index rounded to the nearest integer (-407 below
zero), a variable without a value -406, a zero divisor -409, each statement's place set
as it starts. AUTO variables (the frame's slots), LOCAL and global scalars and arrays,
numbers and strings, unary minus, NOT, COM, + - * / MOD and the comparisons are written
out; a parameter, a function, AND/OR/XOR and the bitwise operators, SHIFT and a keyword
are their closures, called where the closures would evaluate them.

What is written depends on the program (its AUTO slots, scopes, DOUBLE declarations) and
the module (its transformation names), so it is kept for the node in that program of that
module (:func:`~wirecal.twin.fused_code.recipe_of`): a kept line's node is shared with
its copies in other programs.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable
from typing import Any, Protocol

from wirecal.lang.syntax import node_method
from wirecal.lang.vplus import nodes as N
from wirecal.lang.vplus.keywords import keyword
from wirecal.lang.vplus.parser import CONSTANTS
from wirecal.twin.fused_code import Recipe, Source, fused_runs, recipe_of
from wirecal.twin.machine import f32
from wirecal.twin.vplus.errors import array_index, division_by_zero, illegal_index, undefined

_PACK, _UNPACK = struct.Struct("f").pack, struct.Struct("f").unpack

_COUNTER = {"+": "add", "-": "add", "*": "mul", "/": "div"}
"""The operations counted and the counter each adds to (the interpreter's ``ops``)."""

_COMPARE = {"==": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
"""V+ comparisons and the Python operators the closures compare with."""

_VALUES = (N.Paren, N.Num, N.Str, N.Var, N.Neg, N.Not, N.Com, N.BinOp, N.Compare)
"""The nodes written out; a value of any other at its root is left to its closure."""


class Compiling(Protocol):
    """What the written code needs of the node-by-node compiler (one program's)."""

    i: Any  # the interpreter: its globals, ops (the counter), where and transforms
    prog: Any  # the program
    params: dict[str, int]
    autos: dict[str, int]
    locals: set[str]
    local_vals: dict[str, Any]

    @property
    def place(self) -> object:
        """Return the program and its module: what fixes a node's meaning (``recipe_of``)."""
        ...

    def is_double(self, name: str) -> bool:
        """Tell whether the variable ``name`` is declared DOUBLE in the program."""
        ...

    def expr(self, e: N.Expr) -> tuple[Callable, bool]:
        """Compile ``e`` node by node: its closure and whether it is DOUBLE."""
        ...

    def var(self, v: N.Var) -> tuple[Callable, Callable]:
        """Compile a variable node's getter and setter."""
        ...

    def array(self, name: str) -> dict:
        """Return the elements of the LOCAL or global array ``name``."""
        ...


def fused_steps(c: Compiling, steps: list[N.Stmt], one: Callable) -> list[tuple[N.Stmt, Any]]:
    """Compile a body's statements in order, each run of assignments as one function.

    Each function comes with its first statement (whose place the body sets); each other
    statement is compiled by ``one``.
    """
    return fused_runs(c, steps, _writable, lambda: _Writer(c), _names(c), one)


def fused_value(c: Compiling, e: N.Expr) -> tuple[Callable, bool] | None:
    """Return ``e`` as one function of the frame and whether it is DOUBLE.

    None where its root is a node not written out.
    """
    recipe = recipe_of(e, c.place, lambda: _value(c, e))
    return None if recipe is None else (recipe.function(c, _names(c)), recipe.note)


def single_result(v: Any) -> Any:
    """Return the result ``v`` of a REAL +, - or * rounded as the closures round it.

    A number rounded to single precision (:func:`~wirecal.twin.machine.f32`'s errors), a
    string as it is.
    """
    try:
        r = _UNPACK(_PACK(v))[0]
    except (OverflowError, struct.error):  # f32's overflow error; a string, or a fault
        return v if isinstance(v, str) else f32(v)
    return r if r - r == 0.0 else f32(v)  # f32's error for a finite v packed infinite


def _names(c: Compiling) -> dict[str, Any]:
    """Return the names of a compiler's written functions: counter, interpreter, scopes."""
    return {"ops": c.i.ops, "I": c.i, "G": c.i.gvals, "L": c.local_vals}


def _writable(s: N.Stmt) -> bool:
    return isinstance(s, N.Assign)


def _value(c: Compiling, e: N.Expr) -> Recipe | None:
    if not isinstance(e, _VALUES):
        return None
    w = _Writer(c)
    v, double = w.value(e)
    w.src.emit(f"return {v}")
    return w.src.recipe(double)


class _Writer:
    """Writes one run of statements' nodes into its :class:`Source`."""

    def __init__(self, c: Compiling):
        self.c = c
        self.src = Source(
            {
                "_undefined": undefined,
                "_illegal_index": illegal_index,
                "_division_by_zero": division_by_zero,
                "_single_result": single_result,
                "_index": array_index,
                "_fmod": math.fmod,
            }
        )

    def assign(self, s: N.Assign) -> None:
        """Emit the assignment ``s``, its place set first: the value, then its store."""
        src, c, target = self.src, self.c, s.target
        src.emit(f"I.where = {src.bind((c.prog.name, s.line))}")
        name = target.name
        if name in c.params:
            put = src.make(lambda c: c.var(target)[1])
            v, _ = self.value(s.value)
            src.flush()
            src.emit(f"{put}(f, {v})")
            return
        v, _ = self.value(s.value)
        rounding = self.kind(target) == "n" and not c.is_double(name)
        key = src.bind(name)
        if name in c.autos:
            slot = c.autos[name]
            if target.index is None:
                src.emit(f"f[{slot}] = {src.single(v) if rounding else v}")
                return
            src.emit(f"if f[{slot}] is None: f[{slot}] = {{}}")
            r = src.single(v) if rounding else v
            arr = src.let(f"f[{slot}]")
        elif target.index is None:
            src.emit(f"{self.scope(name)}[{key}] = {src.single(v) if rounding else v}")
            return
        else:
            r = src.single(v) if rounding else v
            arr = src.make(lambda c: c.array(name))
        src.emit(f"{arr}[{self.index(target.index)}] = {r}")

    def kind(self, v: N.Var) -> str:
        """Return the variable's kind, ``t`` for a transformation of the module."""
        return "t" if v.kind == "n" and v.name in self.c.i.transforms else v.kind

    def scope(self, name: str) -> str:
        """Return the dictionary of the scalar ``name``: the program's LOCALs or the globals."""
        return "L" if name in self.c.locals else "G"

    def index(self, index: list[N.Expr]) -> str:
        """Emit the index (each rounded to the nearest integer); return its local."""
        src = self.src
        ks = []
        for x in index:
            v, _ = self.value(x)
            number = src.bound.get(v)  # a number's index is rounded here (a table's)
            if type(number) is float and math.isfinite(number):
                ks.append(src.bind(array_index(number)))
            else:
                ks.append(src.let(f"_index({v})"))
        if len(ks) > 1:
            return src.let(f"({', '.join(ks)},)")
        k = src.bound.get(ks[0])
        if k is None:
            src.emit(f"if {ks[0]} < 0: _illegal_index({ks[0]})")
        elif k < 0:
            src.emit(f"_illegal_index({ks[0]})")
        return ks[0]

    def closure(self, e: N.Expr) -> tuple[str, bool]:
        """Emit the call of ``e``'s closure; return its value's local, and if it is DOUBLE."""
        self.src.flush()  # the closure may count
        double = self.c.expr(e)[1]
        return self.src.let(f"{self.src.make(lambda c: c.expr(e)[0])}(f)"), double

    @node_method
    def value(self, e: N.Expr) -> tuple[str, bool]:
        """Emit ``e``; return the local (or bound name) holding its value, and if DOUBLE."""
        return self.closure(e)

    @value.register
    def _(self, e: N.Paren) -> tuple[str, bool]:
        return self.value(e.expr)

    @value.register
    def _(self, e: N.Num) -> tuple[str, bool]:
        return self.src.bind(e.value if e.double else f32(e.value)), e.double

    @value.register
    def _(self, e: N.Str) -> tuple[str, bool]:
        return self.src.bind(e.text), True

    @value.register
    def _(self, e: N.Var) -> tuple[str, bool]:
        c, src, name = self.c, self.src, e.name
        if e.index is None and name in CONSTANTS:
            return src.bind(CONSTANTS[name]), False
        if name in c.params or (e.index is None and keyword(name) is not None):
            return self.closure(e)
        rounding = self.kind(e) == "n" and not c.is_double(name)
        key, t = src.bind(name), src.temp()
        if name in c.autos and e.index is None:
            src.emit(f"{t} = f[{c.autos[name]}]", f"if {t} is None: _undefined({key})")
            return t, c.is_double(name)
        if e.index is None:
            with src.block("try:"):
                src.emit(f"{t} = {self.scope(name)}[{key}]")
            with src.block("except KeyError:"):
                src.emit(f"_undefined({key})")
            if rounding:
                r = src.temp()
                src.emit(f"{r} = {t}")
                with src.block(f"if {t} is not None:"):
                    src.single(t, r)
                t = r
            return t, c.is_double(name)
        auto = name in c.autos
        arr = src.let(f"f[{c.autos[name]}]") if auto else src.make(lambda c: c.array(name))
        with src.block("try:"):
            src.emit(f"{t} = {arr}[{self.index(e.index)}]")
        with src.block("except (KeyError, TypeError):" if auto else "except KeyError:"):
            src.emit(f"_undefined({key})")
        return (src.single(t) if rounding and not auto else t), c.is_double(name)

    @value.register
    def _(self, e: N.Neg) -> tuple[str, bool]:
        v, double = self.value(e.expr)
        return self.src.let(f"-{v}"), double

    @value.register(N.Not)
    @value.register(N.Com)
    def _(self, e: N.Not | N.Com) -> tuple[str, bool]:
        v, _ = self.value(e.expr)
        form = "-1.0 if {v} == 0 else 0.0" if isinstance(e, N.Not) else "float(~round({v}))"
        return self.src.let(form.format(v=v)), False

    @value.register
    def _(self, e: N.Compare) -> tuple[str, bool]:
        x, _ = self.value(e.left)
        y, _ = self.value(e.right)
        return self.src.let(f"-1.0 if {x} {_COMPARE[e.op]} {y} else 0.0"), False

    @value.register
    def _(self, e: N.BinOp) -> tuple[str, bool]:
        src, op = self.src, e.op
        if op in ("/", "MOD"):
            return self.division(e)
        src.count(_COUNTER[op])
        x, dx = self.value(e.left)
        y, dy = self.value(e.right)
        v = src.let(f"{x} {op} {y}")
        return self.rounded(v, dx or dy, f"_single_result({v})")

    def division(self, e: N.BinOp) -> tuple[str, bool]:
        """Emit ``/`` or MOD: the divisor first (zero: -409), then the dividend."""
        src = self.src
        if e.op == "/":
            src.count("div")
        y, dy = self.value(e.right)
        src.emit(f"if {y} == 0: _division_by_zero()")
        x, dx = self.value(e.left)
        v = src.let(f"{x} / {y}" if e.op == "/" else f"_fmod({x}, {y})")
        return self.rounded(v, dx or dy, f"{v} if isinstance({v}, str) else _f32({v})")

    def rounded(self, v: str, double: bool, other: str) -> tuple[str, bool]:
        """Return the result ``v`` as it is where DOUBLE, else rounded to single precision.

        A float rounded here (:func:`~wirecal.twin.machine.f32`'s numbers and errors), any
        other value by ``other``: its closures' rounding.
        """
        if double:
            return v, True
        src, r = self.src, self.src.temp()
        with src.block(f"if type({v}) is float:"):
            src.single(v, r)
        with src.block("else:"):
            src.emit(f"{r} = {other}")
        return r, False
