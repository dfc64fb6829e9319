"""RAPID assignments and conditions written out as one Python function each.

WIRECAL.mod's wc_solve is long runs of ``x := a * b + c * d;`` on num data; compiled node
by node (:mod:`wirecal.twin.rapid.interp`) each operation, each read of data and each
statement is a closure call. An assignment of num, dnum, bool or string data, and the
condition of an IF or WHILE, are written out here instead
(:class:`~wirecal.twin.fused_code.Source`) with the closures' semantics, operation by
operation in their order, each with the type the checker's typer gives it (as the
closures are compiled): a num result rounded to single precision, a dnum one not, each
counted where the closures count it, ``/`` by zero, DIV, MOD, an index outside an array,
an optional argument not present and a string over 80 characters stopping the program
with the closures' errors (:mod:`wirecal.twin.rapid.values`). Numbers, strings,
booleans, data, components, array elements, negation, NOT, arithmetic, comparisons and
AND/OR/XOR are written out; any other node (a function call, an aggregate) is its
closure, called where the closures would evaluate it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from wirecal.lang.rapid import nodes as N
from wirecal.lang.rapid.checker import BOOL, DNUM, LITERAL, NUM, STRING, Type
from wirecal.lang.syntax import node_method
from wirecal.twin.fused_code import Recipe, Source, fused_runs, written
from wirecal.twin.machine import f32
from wirecal.twin.rapid.values import (
    COUNTED,
    RapidError,
    arith,
    position,
    string,
)

_COMPARE = {"=": "==", "<>": "!=", "<": "<", ">": ">", "<=": "<=", ">=": ">="}
_SCALARS = (NUM, DNUM, BOOL, STRING)


class Compiling(Protocol):
    """What the fused code needs of the node-by-node compiler."""

    interp: Any  # the interpreter: its globals, ops (the counter) and line
    typer: Any  # the checker's typer, the routine's scope
    local: dict[str, Any]  # the routine's own data and parameters
    place: object  # the parsed module: each node is in one routine of it

    def expr(self, e: N.Expr, want: Type | None) -> Callable:
        """Compile ``e`` node by node into a closure of the frame."""
        ...

    def static(self, e: N.Expr, want: Type | None) -> Type:
        """Return the type ``e`` is computed in (a literal takes the context's)."""
        ...


def fused_steps(c: Compiling, steps: list[N.Stmt], one: Callable) -> list[Callable]:
    """Compile a block's statements in order, each run of assignments as one function.

    Each assignment's line is set as it starts, as the closures do; each other statement
    (and an assignment of a record or an array: copied, not written out) is compiled by
    ``one``.
    """
    runs = fused_runs(c, steps, lambda s: _writable(c, s), lambda: _Writer(c), _names(c), one)
    return [f for _, f in runs]


def fused_value(c: Compiling, e: N.Expr) -> Callable | None:
    """Return the expression ``e`` (a condition: bool) as one function of the frame.

    None where its root is a node not written out.
    """
    return written(e, lambda: _value(c, e), c, _names(c))


def _names(c: Compiling) -> dict[str, Any]:
    """Return the names of a compiler's written-out functions: counter, interpreter, data."""
    return {"ops": c.interp.ops, "I": c.interp, "G": c.interp.globals}


def _writable(c: Compiling, s: N.Stmt) -> bool:
    return isinstance(s, N.Assign) and c.typer.type(s.target) in _SCALARS


def _value(c: Compiling, e: N.Expr) -> Recipe | None:
    if not isinstance(e, N.Num | N.Str | N.Bool | N.Name | N.Index | N.Not | N.BinOp):
        return None
    w = _Writer(c)
    w.src.emit(f"return {w.value(e, BOOL)}")
    return w.src.recipe()


def _absent(name: str) -> None:
    raise RapidError(f"the optional argument {name} is not present")


class _Writer:
    """Writes one statement's nodes into its :class:`Source`."""

    def __init__(self, c: Compiling):
        self.c = c
        self.single: set[str] = set()  # the locals holding a num result, rounded
        self.src = Source(
            {
                "_position": position,
                "_arith": arith,
                "_string": string,
                "_absent": _absent,
            }
        )

    def assign(self, s: N.Assign) -> None:
        """Emit the assignment ``s``, its line set first."""
        self.c.typer.line = s.line  # as the closures' compiler has it for the statement
        want = self.c.typer.type(s.target)
        self.src.emit(f"I.line = {self.src.bind(s.line)}")
        v = self.value(s.value, want)
        if want == NUM and v not in self.single:
            v = self.src.single(self.src.let(f"float({v})"))
        elif want == DNUM:
            v = self.src.let(f"float({v})")
        self.store(s.target, v)

    def data(self, name: str) -> str:
        """Return the expression of data ``name`` (the frame's, else a global)."""
        key = name.lower()
        return f"{'f' if key in self.c.local else 'G'}[{self.src.bind(key)}]"

    def element(self, array: str, indices: list[N.Expr]) -> tuple[str, str]:
        """Emit the indices of an element of ``array``; return its list and position.

        The indices are evaluated first, then each is checked against its dimension in
        turn (:func:`~wirecal.twin.rapid.values.element_holder`'s order and errors).
        """
        values = [self.value(i, NUM) for i in indices]
        holder = array
        for n, i in enumerate(values):
            bad = f"_position({holder}, {i})"  # raises: NaN, infinite or outside
            k = self.src.let(f"int({i}) if 1 <= {i} <= len({holder}) else {bad}")
            self.src.emit(f"if {k} != {i}: {bad}")
            if n == len(values) - 1:
                return holder, self.src.let(f"{k} - 1")
            holder = self.src.let(f"{holder}[{k} - 1]")
        raise AssertionError("an element has an index")

    def store(self, target: N.Expr, v: str) -> None:
        """Emit the store of ``v`` into ``target``.

        The target's indices are evaluated after the value, as the closures' store does.
        """
        if isinstance(target, N.Name):
            self.src.emit(f"{self.data(target.name)} = {v}")
        elif isinstance(target, N.Component):
            base = self.value(target.base, None)
            self.src.emit(f"{base}[{self.src.bind(target.field.lower())}] = {v}")
        else:
            assert isinstance(target, N.Index)
            holder, k = self.element(self.value(target.base, None), target.indices)
            self.src.emit(f"{holder}[{k}] = {v}")

    def closure(self, e: N.Expr, want: Type | None) -> str:
        """Emit the call of ``e``'s closure; return the local of its value."""
        self.src.flush()  # the closure may count, or call a routine that does
        line = self.c.typer.line  # a call's closure restores the statement's line

        def make(c: Compiling) -> Callable:
            c.typer.line = line
            return c.expr(e, want)

        return self.src.let(f"{self.src.make(make)}(f)")

    @node_method
    def value(self, e: N.Expr, want: Type | None) -> str:
        """Emit ``e`` in the context ``want``; return the local (or name) of its value."""
        return self.closure(e, want)

    @value.register
    def _(self, e: N.Num, want: Type | None) -> str:
        if want == NUM:
            return self.src.bind(f32(float(e.value)))
        return self.src.bind(float(e.value) if want == DNUM else e.value)

    @value.register(N.Str)
    @value.register(N.Bool)
    def _(self, e: N.Str | N.Bool, want: Type | None) -> str:
        return self.src.bind(e.value)

    @value.register
    def _(self, e: N.Name, want: Type | None) -> str:
        key = e.name.lower()
        v = self.src.let(self.data(e.name))
        if key in self.c.local and self.c.local[key].kind == "OPT":
            self.src.emit(f"if {v} is None: _absent({self.src.bind(e.name)})")
        return v

    @value.register
    def _(self, e: N.Component, want: Type | None) -> str:
        return self.src.let(f"{self.value(e.base, None)}[{self.src.bind(e.field.lower())}]")

    @value.register
    def _(self, e: N.Index, want: Type | None) -> str:
        holder, k = self.element(self.value(e.base, None), e.indices)
        return self.src.let(f"{holder}[{k}]")

    @value.register
    def _(self, e: N.Neg, want: Type | None) -> str:
        t = self.c.static(e, want)
        if t not in (NUM, DNUM):
            return self.closure(e, want)
        v = self.src.let(f"float(-{self.value(e.a, t)})")
        return self.rounded(v) if t == NUM else v

    @value.register
    def _(self, e: N.Not, want: Type | None) -> str:
        return self.src.let(f"not {self.value(e.a, BOOL)}")

    @value.register
    def _(self, e: N.BinOp, want: Type | None) -> str:
        op, src = e.op, self.src
        if op in ("AND", "OR", "XOR"):
            r = src.let(self.value(e.a, BOOL))
            if op == "XOR":
                return src.let(f"{r} != {self.value(e.b, BOOL)}")
            with src.block(f"if {'' if op == 'AND' else 'not '}{r}:"):
                src.emit(f"{r} = {self.value(e.b, BOOL)}")
            return r
        ta, tb = self.c.typer.type(e.a), self.c.typer.type(e.b)
        if ta == tb == STRING and op == "+":
            return src.let(f"_string({self.value(e.a, STRING)} + {self.value(e.b, STRING)})")
        if op in _COMPARE:
            operand = next((t for t in (ta, tb) if t not in (LITERAL, None)), DNUM)
            x, y = self.value(e.a, operand), self.value(e.b, operand)
            return src.let(f"{x} {_COMPARE[op]} {y}")
        t = self.c.static(e, want)
        x, y = self.value(e.a, t), self.value(e.b, t)
        src.count(COUNTED[op])
        if op in ("+", "-", "*"):
            v = src.let(f"{x} {op} {y}")
        elif op == "/":
            src.emit(f"if {y} == 0: _arith('/', {x}, {y})")
            v = src.let(f"{x} / {y}")
        else:
            v = src.let(f"_arith({op!r}, {x}, {y})")
        return self.rounded(v) if t == NUM else v

    def rounded(self, v: str) -> str:
        """Emit ``v`` rounded to single precision; the result is known to be rounded."""
        r = self.src.single(v)
        self.single.add(r)
        return r
