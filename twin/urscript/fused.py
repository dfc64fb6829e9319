"""URScript assignments and conditions written out as one Python function each.

The controller solver wc_solve is long runs of ``x = a * b + c * d`` on floats; compiled
node by node (:mod:`wirecal.twin.urscript.interp`) each operation, each read of a
variable and each statement is a closure call. An assignment, and the condition of an
``if`` or ``while``, are written out here instead
(:class:`~wirecal.twin.fused_code.Source`) with the closures' semantics, operation by
operation in their order (:mod:`wirecal.twin.urscript.values`): two floats take the
fast path (counted, a zero divisor refused, the result rounded to single precision),
two ints added, subtracted or multiplied are counted and wrapped to 32 bits, any other
pair goes through :func:`~wirecal.twin.urscript.values.mixed` (the closures' own checks
and errors); a variable without a value, a list index out of range, a condition that is
no boolean stop the program with the closures' messages. Numbers, booleans, strings,
variables, list elements, unary minus, arithmetic, comparisons and and/or/xor/not are
written out; any other node (a call, a member, a list) is its closure, called where the
closures would evaluate it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from wirecal.lang.syntax import node_method
from wirecal.lang.urscript import nodes as N
from wirecal.twin.fused_code import Recipe, Source, fused_runs, written
from wirecal.twin.machine import f32
from wirecal.twin.urscript import values as V

_INT_FAST = {"+", "-", "*"}
"""Operators whose int case is written out (``/`` of ints is a float, ``%`` its own)."""


class Compiling(Protocol):
    """What the fused code needs of the node-by-node compiler."""

    i: Any  # the interpreter: its globals, ops (the counter) and where (the line)
    place: object  # the function's definition: what fixes a name's scope

    def is_global(self, name: str) -> bool:
        """Tell whether the variable ``name`` is a global (else the frame's)."""
        ...

    def expr(self, e: N.Expr) -> Callable:
        """Compile ``e`` node by node into a closure of the frame."""
        ...


_WRITTEN = (N.Num, N.Bool, N.Str, N.Var, N.Index, N.Neg, N.Not, N.Logic, N.Compare, N.BinOp)
"""The nodes written out; a statement of any other at its root is left to its closure."""


def fused_steps(c: Compiling, steps: list[N.Stmt], one: Callable) -> list[Callable]:
    """Compile a body's statements in order, each run of assignments as one function.

    Each assignment's line is set as it starts, as every statement's; each other statement
    is compiled by ``one``. An assignment of a call, a member or a list to a variable is
    not written out (nothing to gain).
    """
    runs = fused_runs(c, steps, _writable, lambda: _Writer(c), _names(c), one)
    return [f for _, f in runs]


def fused_value(c: Compiling, e: N.Expr) -> Callable | None:
    """Return the expression ``e`` (a condition) as one function of the frame.

    None where its root is a node not written out.
    """
    return written(e, lambda: _value(c, e), c, _names(c))


def _names(c: Compiling) -> dict[str, Any]:
    """Return the names of a compiler's written-out functions: counter, interpreter, globals."""
    return {"ops": c.i.ops, "I": c.i, "G": c.i.globals}


def _writable(s: N.Stmt) -> bool:
    return isinstance(s, N.Assign) and (bool(s.target.indices) or isinstance(s.value, _WRITTEN))


def _value(c: Compiling, e: N.Expr) -> Recipe | None:
    if not isinstance(e, _WRITTEN):
        return None
    w = _Writer(c)
    w.src.emit(f"return {w.value(e)}")
    return w.src.recipe()


def _unset(name: str) -> None:
    raise V.URError(f"variable {name} has no value") from None


class _Writer:
    """Writes one statement's nodes into its :class:`Source`."""

    def __init__(self, c: Compiling):
        self.c = c
        self.known: dict[str, type] = {}  # bound constants' types
        self.src = Source(
            {
                "_URError": V.URError,
                "_copy": V.copy_value,
                "_element": V.element,
                "_position": V.position,
                "_negative": V.negative,
                "_number": V.number,
                "_truth": V.truth,
                "_unset": _unset,
                "_i32": V.i32,
                "_fmod": V.fmod,
            }
        )

    def assign(self, s: N.Assign) -> None:
        """Emit the assignment ``s``, its line set first."""
        self.src.emit(f"I.where = {self.constant(s.line)}")
        if not s.target.indices:
            store = f"{self.scope(s.target.name)}[{self.constant(s.target.name)}]"
            v = self.value(s.value)
            self.src.emit(f"{store} = {v} if type({v}) is float else _copy({v})")
            return
        container = self.read(s.target.name)
        for ix in s.target.indices[:-1]:
            container = self.src.let(f"_element({container}, {self.value(ix)})")
        k = self.position(container, self.value(s.target.indices[-1]))
        v = self.value(s.value)
        self.src.emit(f"{container}[{k}] = {v} if type({v}) is float else _copy({v})")

    def scope(self, name: str) -> str:
        """Return the dictionary holding the variable ``name``: the globals or the frame."""
        return "G" if self.c.is_global(name) else "f"

    def read(self, name: str) -> str:
        """Emit the read of a variable (no value: the closures' error); return its local."""
        t, key = self.src.temp(), self.constant(name)
        with self.src.block("try:"):
            self.src.emit(f"{t} = {self.scope(name)}[{key}]")
        with self.src.block("except KeyError:"):
            self.src.emit(f"_unset({key})")
        return t

    def position(self, container: str, index: str) -> str:
        """Emit the check of ``index`` into the list ``container``; return the position."""
        k = self.src.temp()
        fast = f"type({index}) is int and type({container}) is list"
        with self.src.block(f"if {fast} and 0 <= {index} < len({container}):"):
            self.src.emit(f"{k} = {index}")
        with self.src.block("else:"):
            self.src.emit(f"{k} = _position({container}, {index})")
        return k

    def condition(self, v: str) -> None:
        """Emit the check that ``v`` is a boolean (the closures' ``values.truth``)."""
        self.src.emit(f"if type({v}) is not bool: _truth({v})")

    def constant(self, v: Any) -> str:
        """Bind a constant; its type is known when the code is written."""
        name = self.src.bind(v)
        self.known[name] = type(v)
        return name

    def is_float(self, *names: str) -> str | None:
        """Return the test that every one of ``names`` is a float.

        "" where each is known to be one, None where one is known not to be.
        """
        if any(self.known.get(n, float) is not float for n in names):
            return None
        return " and ".join(f"type({n}) is float" for n in names if n not in self.known)

    @node_method
    def value(self, e: N.Expr) -> str:
        """Emit ``e``; return the local (or bound name) holding its value."""
        self.src.flush()  # the closure may count, or read the counts (sync)
        return self.src.let(f"{self.src.make(lambda c: c.expr(e))}(f)")

    @value.register
    def _(self, e: N.Num) -> str:
        return self.constant(e.value if e.is_int else f32(e.value))

    @value.register
    def _(self, e: N.Bool) -> str:
        return self.constant(e.value)

    @value.register
    def _(self, e: N.Str) -> str:
        return self.constant(e.text)

    @value.register
    def _(self, e: N.Var) -> str:
        return self.read(e.name)

    @value.register
    def _(self, e: N.Index) -> str:
        base = self.value(e.base)
        return self.src.let(f"{base}[{self.position(base, self.value(e.index))}]")

    @value.register
    def _(self, e: N.Neg) -> str:
        v = self.value(e.expr)
        return self.src.let(f"-{v} if type({v}) is float else _negative({v})")

    @value.register
    def _(self, e: N.Not) -> str:
        v = self.value(e.expr)
        self.condition(v)
        return self.src.let(f"not {v}")

    @value.register
    def _(self, e: N.Logic) -> str:
        a = self.value(e.left)
        self.condition(a)
        if e.op == "xor":
            b = self.value(e.right)
            self.condition(b)
            return self.src.let(f"{a} != {b}")
        r = self.src.let(a)
        with self.src.block(f"if {'' if e.op == 'and' else 'not '}{r}:"):
            b = self.value(e.right)
            self.condition(b)
            self.src.emit(f"{r} = {b}")
        return r

    @value.register
    def _(self, e: N.Compare) -> str:
        x, y = self.value(e.left), self.value(e.right)
        floats = self.is_float(x, y)
        if e.op not in ("==", "!=") and floats != "":
            with self.src.block(f"if not ({floats}):" if floats else "if True:"):
                self.src.emit(f"_number({x}, {e.op!r})", f"_number({y}, {e.op!r})")
        return self.src.let(f"{x} {e.op} {y}")

    @value.register
    def _(self, e: N.BinOp) -> str:
        x, y = self.value(e.left), self.value(e.right)
        src, op, r, kind = self.src, e.op, self.src.temp(), V.COUNTED[e.op]
        floats, head = self.is_float(x, y), "if"
        if floats is not None:
            with src.block(f"if {floats}:" if floats else "if True:"):
                src.count(kind)
                if op in "/%" and self.known.get(y) is not float:
                    src.emit(f'if {y} == 0: raise _URError("division by zero")')
                elif op in "/%" and self.src.bound[y] == 0:
                    src.emit('raise _URError("division by zero")')
                src.single(src.let(f"_fmod({x}, {y})" if op == "%" else f"{x} {op} {y}"), r)
            head = "elif"
        if op in _INT_FAST and all(self.known.get(n, int) is int for n in (x, y)):
            ints = " and ".join(f"type({n}) is int" for n in (x, y) if n not in self.known)
            with src.block(f"{head} {ints or 'True'}:"):
                src.count(kind)
                src.emit(f"{r} = {x} {op} {y}")
                src.emit(f"if not -2147483648 <= {r} <= 2147483647: {r} = _i32({r})")
            head = "elif"
        with src.block("else:" if head == "elif" else "if True:"):
            src.flush()
            src.emit(f"{r} = {src.make(lambda c: V.mixed(op, c.i.ops))}({x}, {y})")
        return r
