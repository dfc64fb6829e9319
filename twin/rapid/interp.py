r"""An interpreter of wirecal's RAPID subset, with the IRC5's numbers.

A module is checked (:class:`wirecal.lang.rapid.checker.Checker` with ``subset=True``:
RAPID the twin does not run — TRAP, RECORD, handlers, GOTO, MoveL, sockets … — is refused
by line and name before anything runs), then its routines are compiled into Python
closures; the checker's :class:`~wirecal.lang.rapid.checker.Typer` gives every expression
its static type, so the arithmetic is the controller's:

* num is a 32-bit IEEE float (RAPID kernel, built-in data types, read in translation): every
  num literal, result and stored value is rounded to single precision (:func:`f32`), so
  integers beyond 2^24 = 16777216 lose exactness (the manual promises exact integers only to
  8388608, and the checker holds num literals to that); dnum is a 64-bit float;
* a numeric literal takes the type it is used as (a num or a dnum);
* ``/`` by zero, DIV or MOD of non-integers or by zero, a string over 80 characters, an index
  outside an array, reading an optional argument that is not present and routine calls
  nested more than :data:`MAX_CALL_DEPTH` deep are run-time errors that stop the program
  (the controller's error numbers are unconfirmed); DIV truncates toward zero and MOD takes
  the dividend's sign (unconfirmed);
* a FOR loop without STEP counts by 1, or by -1 when it starts above its end (unconfirmed);
* ``NumToStr``/``DnumToStr`` write fixed decimals, rounding half away from zero, and a
  negative zero as 0; ``TPWrite``/``Write`` ``\Num`` write an integer when the fraction is
  within 0.000005 of one, else up to 6 significant digits (``\Dnum``: 15) — all unconfirmed;
* ``ClkRead`` reads whole milliseconds (``\HighRes``: the clock as it is; unconfirmed).

What touches the robot, the encoder, files and the FlexPendant goes through a
:class:`RapidController`. INOUT arguments are copied in and back out on return.

The arithmetic executed is counted in :attr:`Interpreter.ops`, as the V+ and URScript
twins count theirs: ``+`` and ``-`` of numbers as add, ``*`` as mul, ``/``, ``DIV`` and
``MOD`` as div, ``Sqrt``/``SqrtDnum`` as sqrt; a negation, a comparison, a string's ``+``
and a FOR loop's own step are not counted.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

from wirecal.lang.rapid import nodes as N
from wirecal.lang.rapid import tables as T
from wirecal.lang.rapid.checker import (
    BOOL,
    DNUM,
    LITERAL,
    NUM,
    STRING,
    Checker,
    Problems,
    Symbol,
    Type,
    Typer,
)
from wirecal.lang.rapid.parser import SyntaxProblem, parse_module
from wirecal.lang.syntax import node_method
from wirecal.solver.errors import WirecalError
from wirecal.twin.machine import Kept, Outcome, RunError, f32, rounded
from wirecal.twin.rapid.controller_protocol import RapidController
from wirecal.twin.rapid.fused import fused_steps, fused_value
from wirecal.twin.rapid.values import (
    COUNTED,
    FAST,
    RapidError,
    arith,
    element_holder,
    position,
    string,
)

__all__ = ["Interpreter", "RapidController", "load_module", "run_module"]

MAX_CALL_DEPTH = 40
"""Deepest chain of routine calls the twin runs (wirecal's bound; the controller's is
unconfirmed): deeper, the program stops, as a recursion without end would."""

Frame = dict[str, Any]
Eval = Callable[[Frame], Any]


class _Raise(Exception):
    """RAISE; in an ERROR handler: the error goes on to the caller."""


class _Return(Exception):
    def __init__(self, value: Any):
        self.value = value


class _Exit(Exception):
    """EXIT: the program ends."""


class _Stop(Exception):
    """Stop: the program halts (the operator may start it again)."""


@dataclass
class Clock:
    """A RAPID clock: the time it has run, and since when it runs (None: stopped)."""

    total_s: float = 0.0
    since_s: float | None = None


def coerce(value: Any, want: Type) -> Any:
    """Return ``value`` as data of type ``want`` (a num rounded to single precision)."""
    if want.dims:
        return [coerce(v, Type(want.name, want.dims[1:])) for v in value]
    if want == NUM:
        return f32(float(value))
    if want == DNUM:
        return float(value)
    if want.name in T.RECORDS and isinstance(value, dict):
        return {k: coerce(value[k], Type(t)) for k, t in T.RECORDS[want.name]}
    return value


def _num(value: Any) -> float:
    """Return ``value`` as a num (single precision)."""
    return f32(float(value))


_SCALAR: dict[Type, Callable[[Any], Any]] = {
    NUM: _num,
    DNUM: float,
    BOOL: lambda v: v,
    STRING: lambda v: v,
}
"""What :func:`coerce` of a copy does to data of these types, without its type tests."""


def default(t: Type) -> Any:
    """Return the value data of type ``t`` starts with (0, FALSE, "", zeros)."""
    if t.dims:
        size = t.dims[0] or 0
        return [default(Type(t.name, t.dims[1:])) for _ in range(size)]
    if t in (NUM, DNUM):
        return 0.0
    if t == BOOL:
        return False
    if t == STRING:
        return ""
    if t.name == "clock":
        return Clock()
    if t.name in T.RECORDS:
        return {k: default(Type(v)) for k, v in T.RECORDS[t.name]}
    return None  # iodev: not open


def _tool0() -> dict[str, Any]:
    """Return tool0: robot-held, the flange's frame, no tool load (T.TOOLDATA_PAGE)."""
    tool = default(Type("tooldata"))
    tool["robhold"] = True
    tool["tframe"]["rot"]["q1"] = tool["tload"]["aom"]["q1"] = 1.0
    return tool


def copy(value: Any) -> Any:
    """Return a copy of a value (records and arrays are values in RAPID)."""
    if isinstance(value, list):
        return [copy(v) for v in value]
    if isinstance(value, dict):
        return {k: copy(v) for k, v in value.items()}
    return value


def _finite(value: float, what: str) -> None:
    """Stop the run where ``value``, about to be written as text, is infinite or NaN.

    A controller's num cannot be written so (what it does instead is unconfirmed); Python's
    rounding would end the twin in a traceback.
    """
    if not math.isfinite(value):
        raise RapidError(f"{what}: {value} is not a finite number (unconfirmed on a controller)")


def fixed(value: float, decimals: int) -> str:
    """Write ``value`` with ``decimals`` decimals (NumToStr, DnumToStr: module docstring)."""
    _finite(value, "NumToStr")
    scaled = abs(value) * 10**decimals
    rounded = math.floor(scaled + 0.5) / 10**decimals
    text = f"{rounded:.{decimals}f}"
    return text if value >= 0 or rounded == 0 else "-" + text


def number_text(value: float, digits: int) -> str:
    r"""Write a number as TPWrite and Write ``\Num``/``\Dnum`` do (module docstring)."""
    _finite(value, "a written number")
    if abs(value - round(value)) < 0.000005:
        return str(round(value))
    return f"{value:.{digits}g}"


_COMPARE: dict[str, Callable[[Any, Any], bool]] = {
    "=": lambda a, b: a == b,
    "<>": lambda a, b: a != b,
    "<": lambda a, b: a < b,
    ">": lambda a, b: a > b,
    "<=": lambda a, b: a <= b,
    ">=": lambda a, b: a >= b,
}


class Interpreter:
    """A checked module, compiled, ready to run routines on a controller."""

    def __init__(self, module: N.Module, checker: Checker, controller: RapidController):
        self.module, self.controller = module, controller
        self.routines_sig = checker.user
        self.global_scope = checker.globals
        self.globals: Frame = {}
        self.line = 0
        self.depth = 0
        self.ops: Counter[str] = Counter()  # arithmetic executed: add (+ −), mul, div, sqrt
        self.compiled: dict[str, Callable[[list[Any]], tuple[Any, Frame]]] = {}
        self.sources = {r.name.lower(): r for r in module.routines}
        typer = Typer(self.global_scope, Problems(), self.routines_sig)
        for k, v in T.PREDEFINED.items():
            if k in T.SUBSET_ERRORS:  # ERRNO 0; each error its own number (the twin's)
                self.globals[k] = float(T.SUBSET_ERRORS.index(k))
            elif k == "pi":
                self.globals[k] = f32(3.1415926)
            elif v == "loaddata":  # load0: no payload (the twin's; ABB's value: unconfirmed)
                self.globals[k] = default(Type(v))
            elif v == "tooldata":  # tool0: the flange, no tool load (T.TOOLDATA_PAGE)
                self.globals[k] = _tool0()
            elif v == "speeddata":
                self.globals[k] = dict(
                    zip(("v_tcp", "v_ori", "v_leax", "v_reax"), T.speed_values(k), strict=True)
                )
            else:
                self.globals[k] = k
        for d in module.data:
            t = self.global_scope[d.name.lower()].type
            self.globals[d.name.lower()] = (
                coerce(_Compiler(self, typer, {}).expr(d.init, t)({}), t)
                if d.init is not None
                else default(t)
            )

    def routine(self, name: str) -> Callable[[list[Any]], tuple[Any, Frame]]:
        """Return the compiled routine ``name`` (compiled on first use)."""
        key = name.lower()
        if key not in self.compiled:
            self.compiled[key] = _Compiler.routine(self, self.sources[key])
        return self.compiled[key]

    def execute(self, entry: str = "main") -> Outcome:
        """Run the PROC ``entry`` without arguments; return how the run ended."""
        if entry.lower() not in self.sources:
            raise WirecalError([f"{self.module.name}: no routine {entry} to run"])
        try:
            self.routine(entry)([])
        except _Exit:
            self.controller.stop(f"EXIT at line {self.line}")
            return Outcome("halted", entry, self.line)
        except _Stop:
            self.controller.stop(f"Stop at line {self.line}")
            return Outcome("paused", entry, self.line)
        except RunError as e:
            self.controller.stop(f"line {self.line}: {e.message}")
            return Outcome("error", entry, self.line, e.message)
        except RecursionError:
            why = "blocks and routine calls nested deeper than the twin runs"
            self.controller.stop(f"line {self.line}: {why}")
            return Outcome("error", entry, self.line, why)
        return Outcome("completed", entry, self.line)


def _check_subset(module: N.Module, source: str) -> list[str]:
    """Refuse what the checker accepts and the twin does not run (named, before running)."""
    refused = {
        "moveabsj": ("Conc", "V", "T", "Z", "WObj"),
        "open": ("Read", "Bin"),
        "cjointt": ("TaskRef", "TaskName"),
    }
    out = []
    for r in module.routines:
        for call in _calls(r.body):
            for a in call.args:
                if a.name and a.name in refused.get(call.name.lower(), ()):
                    out.append(
                        f"{source}:{call.line}: {call.name} \\{a.name}: the twin does not run it"
                    )
    return out


def _calls(stmts: list[N.Stmt]) -> list[N.Call]:
    out: list[N.Call] = []
    for s in stmts:
        if isinstance(s, N.Call):
            out.append(s)
        elif isinstance(s, N.If):
            for _, body in s.branches:
                out += _calls(body)
            out += _calls(s.orelse)
        elif isinstance(s, N.For | N.While):
            out += _calls(s.body)
        elif isinstance(s, N.Test):
            for _, body in s.cases:
                out += _calls(body)
            out += _calls(s.default)
    return out


def load_module(
    text: str, source: str, controller: RapidController, *, appended: str = ""
) -> Interpreter:
    """Check a module and ready it to run; WirecalError lists the checker's problems.

    ``appended``: routines to run as if written before the module's ENDMODULE (the
    twin's own, :mod:`~wirecal.twin.rapid.solver_run`), parsed apart from the module.
    """
    try:
        module = parse_module(text)  # kept for its several runs (wc_mount, wc_run)
        if appended:
            module = _with_appended(module, text, appended)
    except SyntaxProblem as e:
        raise WirecalError([f"{source}:{e.line}: {e.message}"]) from None
    checker, found = _checked(module)
    problems = [f"{source}:{line}: {m}" for line, m in found]
    if not problems:
        problems = _check_subset(module, source)
    if problems:
        raise WirecalError(problems)
    return Interpreter(module, checker, controller)


CHECKS_KEPT = 8
"""Modules whose check is kept (a module's parse is kept by its text: a measurement is a
mounting run and a measuring run of one module, and a test runs the same module often)."""

_CHECKED = Kept(CHECKS_KEPT)
_JOINED = Kept(CHECKS_KEPT)
"""Modules with routines appended, kept for the two parses joined (so is their check)."""


def _check(module: N.Module) -> tuple[Checker, list[tuple[int, str]]]:
    checker = Checker(module, subset=True)
    return checker, checker.run()


def _checked(module: N.Module) -> tuple[Checker, list[tuple[int, str]]]:
    """Return :func:`_check` of ``module``, kept for the same parsed module (CHECKS_KEPT).

    Neither the module (a kept parse) nor the checker's tables change once checked: the
    interpreter reads the checker's routines and global data, and copies the scope.
    """
    checked: tuple[Checker, list[tuple[int, str]]] = _CHECKED.get(lambda: _check(module), module)
    return checked


def _with_appended(module: N.Module, text: str, appended: str) -> N.Module:
    """Return ``module`` (the parse of ``text``) with the routines of ``appended`` added.

    The module's own parse is the one kept for ``text`` (the generator's check and the
    twin's runs parse that text too); ``appended`` is parsed alone, on the lines it has in
    ``text`` with it inserted before ENDMODULE, so every line number is the joined text's.
    The joined module is kept for the two parses (its check with it: :func:`_checked`).
    """
    before = text[: text.rindex("ENDMODULE")]
    alone = parse_module(
        f"MODULE {module.name}\n" + "\n" * (before.count("\n") - 1) + appended + "ENDMODULE\n"
    )
    joined: N.Module = _JOINED.get(
        lambda: replace(
            module,
            data=[*module.data, *alone.data],
            routines=[*module.routines, *alone.routines],
            unsupported=[*module.unsupported, *alone.unsupported],
        ),
        module,
        alone,
    )
    return joined


def run_module(text: str, source: str, controller: RapidController, entry: str = "main") -> Outcome:
    """Check a module (:func:`load_module`), then run its PROC ``entry``."""
    return load_module(text, source, controller).execute(entry)


class _Compiler:
    """Compile one routine's statements and expressions into closures."""

    def __init__(
        self,
        interp: Interpreter,
        typer: Typer,
        local: dict[str, Symbol],
        returns: Type | None = None,
    ):
        self.interp, self.typer, self.local, self.returns = interp, typer, local, returns
        self.place: object = interp.module  # a node is in one routine of it (fused_code.recipe_of)

    @staticmethod
    def routine(interp: Interpreter, r: N.Routine) -> Callable[[list[Any]], tuple[Any, Frame]]:
        """Compile a PROC or FUNC: a callable taking the argument values."""
        scope = dict(interp.global_scope)
        local: dict[str, Symbol] = {}
        for p in r.params:
            kind = "OPT" if p.optional else "IN"
            sym = Symbol(p.name, Type(p.type.lower(), (None,) * p.dims), kind)
            scope[p.name.lower()] = local[p.name.lower()] = sym
        returns = Type(r.type.lower()) if r.type else None
        c = _Compiler(interp, Typer(scope, Problems(), interp.routines_sig), local, returns)
        names = [p.name.lower() for p in r.params]
        body = c.handled(c.block(r.body), r.handler)
        is_func = r.kind == "FUNC"

        def run(args: list[Any]) -> tuple[Any, Frame]:
            frame: Frame = dict(zip(names, args, strict=True))
            try:
                body(frame)
            except _Return as ret:
                return ret.value, frame
            if is_func:
                raise RapidError(f"the FUNC {r.name} ended without RETURN")
            return None, frame

        return run

    def handled(
        self, body: Callable[[Frame], None], handler: list[N.Stmt] | None
    ) -> Callable[[Frame], None]:
        """Wrap a routine's body with its ERROR handler: an error with an ERRNO runs it.

        ERRNO is set; the handler's ``RAISE;`` passes the error on to the caller, its
        RETURN ends the routine (RAPID reference manual, error recovery: unconfirmed).
        """
        if handler is None:
            return body
        run_handler, globals_ = self.block(handler), self.interp.globals

        def guarded(frame: Frame) -> None:
            try:
                body(frame)
            except RapidError as error:
                if error.errno is None:
                    raise
                globals_["errno"] = globals_[error.errno]
                try:
                    run_handler(frame)
                except _Raise:
                    raise error from None

        return guarded

    # ---- statements ----
    def block(self, stmts: list[N.Stmt]) -> Callable[[Frame], None]:
        """Compile statements in order (declarations enter the scope as they come)."""
        steps = fused_steps(self, stmts, self.stmt)

        def run(frame: Frame) -> None:
            for step in steps:
                step(frame)

        return run

    def stmt(self, s: N.Stmt) -> Callable[[Frame], None]:
        """Compile one statement; each one sets the interpreter's current line."""
        self.typer.line = s.line
        return self.compile_stmt(s)

    @node_method
    def compile_stmt(self, s: N.Stmt) -> Callable[[Frame], None]:
        """EXIT (the only statement left once the subset check passed)."""
        assert isinstance(s, N.Exit), s
        interp, line = self.interp, s.line

        def exit_(frame: Frame) -> None:
            interp.line = line
            raise _Exit

        return exit_

    @compile_stmt.register
    def _(self, s: N.Data) -> Callable[[Frame], None]:
        return self.declare(s)

    @compile_stmt.register
    def _(self, s: N.Assign) -> Callable[[Frame], None]:
        interp, line = self.interp, s.line
        want = self.typer.type(s.target)
        assert want is not None
        value, store = self.expr(s.value, want), self.store(s.target)
        scalar = _SCALAR.get(want)
        if scalar is not None:  # a scalar is no record nor array: nothing to copy

            def assign_scalar(frame: Frame) -> None:
                interp.line = line
                store(frame, scalar(value(frame)))

            return assign_scalar

        def assign(frame: Frame) -> None:
            interp.line = line
            store(frame, coerce(copy(value(frame)), want))

        return assign

    @compile_stmt.register
    def _(self, s: N.Call) -> Callable[[Frame], None]:
        return self.call_stmt(s)

    @compile_stmt.register
    def _(self, s: N.If) -> Callable[[Frame], None]:
        return self.if_(s)

    @compile_stmt.register
    def _(self, s: N.For) -> Callable[[Frame], None]:
        return self.for_(s)

    @compile_stmt.register
    def _(self, s: N.While) -> Callable[[Frame], None]:
        interp, line = self.interp, s.line
        cond, body = self.condition(s.cond), self.block(s.body)

        def while_(frame: Frame) -> None:
            interp.line = line
            while cond(frame):
                body(frame)
                interp.line = line

        return while_

    @compile_stmt.register
    def _(self, s: N.Test) -> Callable[[Frame], None]:
        return self.test(s)

    @compile_stmt.register
    def _(self, s: N.Return) -> Callable[[Frame], None]:
        return self.ret(s)

    @compile_stmt.register
    def _(self, s: N.Raise) -> Callable[[Frame], None]:
        return _raise

    def declare(self, d: N.Data) -> Callable[[Frame], None]:
        """Compile a routine's data: (re)initialized each time the routine runs."""
        t = Type(d.type.lower(), tuple(int(x.value) for x in d.dims if isinstance(x, N.Num)))
        sym = Symbol(d.name, t, d.storage)
        key = d.name.lower()
        self.typer.scope[key] = self.local[key] = sym
        init = self.expr(d.init, t) if d.init is not None else None

        def declare(frame: Frame) -> None:
            frame[key] = coerce(init(frame), t) if init else default(t)

        return declare

    def if_(self, s: N.If) -> Callable[[Frame], None]:
        branches = [(self.condition(c), self.block(b)) for c, b in s.branches]
        orelse, interp, line = self.block(s.orelse), self.interp, s.line

        def if_(frame: Frame) -> None:
            interp.line = line
            for cond, body in branches:
                if cond(frame):
                    body(frame)
                    return
            orelse(frame)

        return if_

    def for_(self, s: N.For) -> Callable[[Frame], None]:
        start, stop = self.expr(s.start, NUM), self.expr(s.stop, NUM)
        step = self.expr(s.step, NUM) if s.step else None
        key = s.var.lower()
        saved = self.typer.scope.get(key), self.local.get(key)
        self.typer.scope[key] = self.local[key] = Symbol(s.var, NUM, "FOR")
        body = self.block(s.body)
        for table, old in zip((self.typer.scope, self.local), saved, strict=True):
            if old is None:
                table.pop(key, None)
            else:
                table[key] = old
        interp, line = self.interp, s.line

        def for_(frame: Frame) -> None:
            interp.line = line
            i, end = f32(start(frame)), f32(stop(frame))
            by = f32(step(frame)) if step else (1.0 if i <= end else -1.0)
            outer = frame.get(key)
            while (i <= end) if by > 0 else (i >= end):
                frame[key] = i
                body(frame)
                i = f32(frame[key] + by)
            frame[key] = outer

        return for_

    def test(self, s: N.Test) -> Callable[[Frame], None]:
        got = self.typer.type(s.expr) or NUM
        want = NUM if got == LITERAL else got
        value = self.expr(s.expr, want)
        cases = [([self.expr(v, want) for v in vs], self.block(b)) for vs, b in s.cases]
        default_, interp, line = self.block(s.default), self.interp, s.line

        def test(frame: Frame) -> None:
            interp.line = line
            x = coerce(value(frame), want)
            for values, body in cases:
                if any(coerce(v(frame), want) == x for v in values):
                    body(frame)
                    return
            default_(frame)

        return test

    def ret(self, s: N.Return) -> Callable[[Frame], None]:
        """Compile RETURN: a FUNC's value becomes data of its declared type."""
        want = self.returns
        value = self.expr(s.value, want) if s.value is not None and want else None
        interp, line = self.interp, s.line

        def ret(frame: Frame) -> None:
            interp.line = line
            raise _Return(coerce(copy(value(frame)), want) if value and want else None)

        return ret

    def call_stmt(self, s: N.Call) -> Callable[[Frame], None]:
        """Compile a call of a PROC of the module, or of an instruction of the subset."""
        key, interp, line = s.name.lower(), self.interp, s.line
        if key in interp.sources:
            call = self.user_call(s.name, s.args)

            def proc(frame: Frame) -> None:
                interp.line = line
                call(frame)

            return proc
        run = _INSTRUCTIONS[key](self, s.args)

        def instruction(frame: Frame) -> None:
            interp.line = line
            run(frame)

        return instruction

    def user_call(self, name: str, args: list[N.Arg]) -> Callable[[Frame], Any]:
        """Call a routine of the module: values in, INOUT values back out."""
        sig = self.interp.routines_sig[name.lower()]
        source = self.interp.sources[name.lower()]
        positional = [a for a in args if a.name is None]
        named = {a.name.lower(): a for a in args if a.name is not None}
        getters: list[Eval] = []
        writebacks: list[tuple[int, Callable[[Frame, Any], None]]] = []
        pos = iter(positional)
        for i, (p, decl) in enumerate(zip(sig.params, source.params, strict=True)):
            ptype = Type(p.type, (None,) * decl.dims)
            a = named.get(p.name.lower()) if p.optional else next(pos)
            if a is None or a.value is None:
                getters.append(_constant(True if a is not None else None))
                continue
            getters.append(self.expr(a.value, ptype))
            if p.var:
                writebacks.append((i, self.store(a.value)))
        interp = self.interp

        def call(frame: Frame) -> Any:
            values = [copy(g(frame)) for g in getters]
            if interp.depth >= MAX_CALL_DEPTH:
                raise RapidError(f"routine calls nested more than {MAX_CALL_DEPTH} deep")
            interp.depth += 1
            try:
                result, inner = interp.routine(name)(values)
            finally:
                interp.depth -= 1
            for i, store in writebacks:
                store(frame, inner[source.params[i].name.lower()])
            return result

        return call

    # ---- stores: the left of := and INOUT arguments ----
    def store(self, target: N.Expr) -> Callable[[Frame, Any], None]:
        """Compile a data reference into a setter."""
        if isinstance(target, N.Name):
            key = target.name.lower()
            if key in self.local:

                def set_local(frame: Frame, v: Any) -> None:
                    frame[key] = v

                return set_local
            globals_ = self.interp.globals

            def set_global(frame: Frame, v: Any) -> None:
                globals_[key] = v

            return set_global
        if isinstance(target, N.Component):
            base, name = self.expr(target.base, None), target.field.lower()

            def set_component(frame: Frame, v: Any) -> None:
                base(frame)[name] = v

            return set_component
        assert isinstance(target, N.Index)
        base = self.expr(target.base, None)
        indices = [self.expr(i, NUM) for i in target.indices]

        def set_element(frame: Frame, v: Any) -> None:
            holder, last = element_holder(base(frame), [i(frame) for i in indices])
            holder[last] = v

        return set_element

    # ---- expressions ----
    def condition(self, e: N.Expr) -> Eval:
        """Compile a condition: written out as one function where it can be (``fused``)."""
        return fused_value(self, e) or self.expr(e, BOOL)

    @node_method
    def expr(self, e: N.Expr, want: Type | None) -> Eval:
        """Compile an expression; ``want`` is the type its context needs (literals, aggregates).

        A function call when no case is its own.
        """
        assert isinstance(e, N.FuncCall), e
        return self.function(e)

    @expr.register
    def _(self, e: N.Num, want: Type | None) -> Eval:
        return _constant(coerce(e.value, want) if want in (NUM, DNUM) else e.value)

    @expr.register(N.Str)
    @expr.register(N.Bool)
    def _(self, e: N.Str | N.Bool, want: Type | None) -> Eval:
        return _constant(e.value)

    @expr.register
    def _(self, e: N.Name, want: Type | None) -> Eval:
        return self.name(e.name)

    @expr.register
    def _(self, e: N.Component, want: Type | None) -> Eval:
        base, name = self.expr(e.base, None), e.field.lower()
        return lambda f: base(f)[name]

    @expr.register
    def _(self, e: N.Index, want: Type | None) -> Eval:
        base = self.expr(e.base, None)
        indices = [self.expr(i, NUM) for i in e.indices]
        if len(indices) == 1:  # the common case, without the list of indices
            index = indices[0]

            def element_1(frame: Frame) -> Any:
                array = base(frame)
                return array[position(array, index(frame))]

            return element_1

        def element(frame: Frame) -> Any:
            holder, last = element_holder(base(frame), [i(frame) for i in indices])
            return holder[last]

        return element

    @expr.register
    def _(self, e: N.Aggregate, want: Type | None) -> Eval:
        return self.aggregate(e, want)

    @expr.register
    def _(self, e: N.Neg, want: Type | None) -> Eval:
        t = self.static(e, want)
        a = self.expr(e.a, t)
        return lambda f: coerce(-a(f), t)

    @expr.register
    def _(self, e: N.Not, want: Type | None) -> Eval:
        a = self.expr(e.a, BOOL)
        return lambda f: not a(f)

    @expr.register
    def _(self, e: N.BinOp, want: Type | None) -> Eval:
        return self.binop(e, want)

    def static(self, e: N.Expr, want: Type | None) -> Type:
        """Return the expression's type; a literal one takes the context's (else dnum)."""
        t = self.typer.type(e, want)
        if t == LITERAL or t is None:
            return want if want in (NUM, DNUM) else DNUM
        return t

    def name(self, name: str) -> Eval:
        key = name.lower()
        if key in self.local and self.local[key].kind == "OPT":

            def optional(f: Frame) -> Any:
                if f[key] is None:
                    raise RapidError(f"the optional argument {name} is not present")
                return f[key]

            return optional
        if key in self.local:
            return lambda f: f[key]
        globals_ = self.interp.globals
        return lambda f: globals_[key]

    def aggregate(self, e: N.Aggregate, want: Type | None) -> Eval:
        assert want is not None
        if want.dims:
            inner = Type(want.name, want.dims[1:])
            items = [self.expr(x, inner) for x in e.items]
            return lambda f: [coerce(i(f), inner) for i in items]
        parts = T.RECORDS[want.name]
        fields = [
            (k, Type(t), self.expr(x, Type(t))) for (k, t), x in zip(parts, e.items, strict=True)
        ]
        return lambda f: {k: coerce(g(f), t) for k, t, g in fields}

    def binop(self, e: N.BinOp, want: Type | None) -> Eval:
        op = e.op
        if op in ("AND", "OR", "XOR"):
            a, b = self.expr(e.a, BOOL), self.expr(e.b, BOOL)
            if op == "AND":
                return lambda f: a(f) and b(f)
            if op == "OR":
                return lambda f: a(f) or b(f)
            return lambda f: a(f) != b(f)
        ta, tb = self.typer.type(e.a), self.typer.type(e.b)
        if ta == tb == STRING and op == "+":
            sa, sb = self.expr(e.a, STRING), self.expr(e.b, STRING)
            return lambda f: string(sa(f) + sb(f))
        if op in _COMPARE:
            operand = next((t for t in (ta, tb) if t not in (LITERAL, None)), DNUM)
            a, b = self.expr(e.a, operand), self.expr(e.b, operand)
            compare = _COMPARE[op]
            return lambda f: compare(a(f), b(f))
        t = self.static(e, want)
        a, b = self.expr(e.a, t), self.expr(e.b, t)
        fn = FAST.get(op) or (lambda x, y: arith(op, x, y))
        ops, kind = self.interp.ops, COUNTED[op]
        if t == NUM:
            fn = rounded(fn)

        def arithmetic(f: Frame) -> Any:
            x, y = a(f), b(f)
            ops[kind] += 1
            return fn(x, y)

        return arithmetic

    def function(self, e: N.FuncCall) -> Eval:
        key = e.name.lower()
        if key in self.interp.sources:
            call, interp, line = self.user_call(e.name, e.args), self.interp, self.typer.line

            def func(frame: Frame) -> Any:
                result = call(frame)
                interp.line = line
                return result

            return func
        return _FUNCTIONS[key](self, e.args)

    def args(self, name: str, args: list[N.Arg]) -> tuple[list[Eval], dict[str, Eval | None]]:
        """Compile a builtin's arguments: positional by parameter type, optional by name."""
        routine = T.INSTRUCTIONS.get(name) or T.FUNCTIONS[name]
        required = [p for p in routine.params if not p.optional]
        types = {p.name.lower(): p for p in routine.params}
        pos = [
            self.expr(a.value, Type(p.type)) if a.value is not None else _constant(None)
            for p, a in zip(required, [a for a in args if a.name is None], strict=True)
        ]
        opt: dict[str, Eval | None] = {}
        for a in args:
            if a.name is not None:
                p = types[a.name.lower()]
                opt[p.name.lower()] = None if a.value is None else self.expr(a.value, Type(p.type))
        return pos, opt


def _raise(frame: Frame) -> None:
    raise _Raise


def _constant(v: Any) -> Eval:
    return lambda f: v


def _positional(args: list[N.Arg], n: int) -> N.Expr:
    """Return the ``n``-th required argument's expression."""
    value = [a for a in args if a.name is None][n].value
    assert value is not None
    return value


# ---- the instructions and functions of the subset ----
Builder = Callable[[_Compiler, list[N.Arg]], Callable[[Frame], Any]]


def _move_abs_j(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, _ = c.args("moveabsj", args)
    target, speed, zone, tool = pos[0], pos[1], pos[2], pos[3]
    ctl = c.interp.controller

    def run(frame: Frame) -> None:
        jt, v = target(frame), speed(frame)
        joints = tuple(jt["robax"][f"rax_{i}"] for i in range(1, 7))
        speeds = (v["v_tcp"], v["v_ori"], v["v_leax"], v["v_reax"])
        ctl.move_abs_j(joints, speeds, zone(frame), float(tool(frame)["tload"]["mass"]))

    return run


def _text_with_number(opt: dict[str, Eval | None], frame: Frame) -> str:
    num, dnum, flag = opt.get("num"), opt.get("dnum"), opt.get("bool")
    if num is not None:
        return number_text(num(frame), 6)
    if dnum is not None:
        return number_text(dnum(frame), 15)
    if flag is not None:
        return "TRUE" if flag(frame) else "FALSE"
    return ""


def _tp_write(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, opt = c.args("tpwrite", args)
    ctl = c.interp.controller
    return lambda f: ctl.tp_write(string(pos[0](f) + _text_with_number(opt, f)))


def _write(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, opt = c.args("write", args)
    ctl, newline = c.interp.controller, "nonewline" not in opt

    def run(frame: Frame) -> None:
        handle = pos[0](frame)
        if handle is None:
            raise RapidError("Write: the iodev is not open", "err_fileacc")
        text = string(pos[1](frame) + _text_with_number(opt, frame))
        _file_call("err_fileacc", lambda: ctl.write_file(handle, text, newline))

    return run


def _file_call(errno: str, call: Callable[[], Any]) -> Any:
    """Make a controller's file call; its refusal is a RAPID error with ``errno``."""
    try:
        return call()
    except RapidError:
        raise
    except RunError as e:
        raise RapidError(e.message, errno) from None


def _open(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, opt = c.args("open", args)
    device, file, store = pos[0], opt.get("file"), c.store(_positional(args, 1))
    ctl, append = c.interp.controller, "append" in opt

    def run(frame: Frame) -> None:
        path = device(frame) + ("/" + file(frame) if file else "")
        store(frame, _file_call("err_fileopen", lambda: ctl.open_file(path, append)))

    return run


def _close(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, _ = c.args("close", args)
    store, ctl = c.store(_positional(args, 0)), c.interp.controller

    def run(frame: Frame) -> None:
        handle = pos[0](frame)
        store(frame, None)
        if handle is not None:
            _file_call("err_fileacc", lambda: ctl.close_file(handle))

    return run


def _tp_read_num(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, _ = c.args("tpreadnum", args)
    store, ctl = c.store(_positional(args, 0)), c.interp.controller
    return lambda f: store(f, f32(ctl.tp_read_num(pos[1](f))))


def _step(c: _Compiler, args: list[N.Arg], by: float) -> Callable[[Frame], None]:
    pos, _ = c.args("incr", args)
    store = c.store(_positional(args, 0))
    return lambda f: store(f, f32(pos[0](f) + by))


def _clock(action: str) -> Builder:
    def build(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
        pos, _ = c.args("clk" + action, args)
        ctl = c.interp.controller

        def run(frame: Frame) -> None:
            clock: Clock = pos[0](frame)
            now = ctl.now_s()
            if action == "reset":
                clock.total_s, clock.since_s = 0.0, None
            elif action == "start" and clock.since_s is None:
                clock.since_s = now
            elif action == "stop" and clock.since_s is not None:
                clock.total_s, clock.since_s = clock.total_s + now - clock.since_s, None

        return run

    return build


def _wait_time(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    pos, _ = c.args("waittime", args)
    ctl = c.interp.controller

    def run(frame: Frame) -> None:
        t = pos[0](frame)
        if t < 0:
            raise RapidError(f"WaitTime {t:g}: a negative time")
        ctl.wait_time(t)

    return run


def _stop(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    def run(frame: Frame) -> None:
        raise _Stop

    return run


def _alias_io(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    """AliasIO "name", var: the variable reads the configured signal ``name``.

    A signal the I/O configuration lacks is ERR_ALIASIO_DEF (its ERROR handler runs).
    """
    pos, _ = c.args("aliasio", args)
    store, ctl = c.store(_positional(args, 1)), c.interp.controller

    def run(frame: Frame) -> None:
        name = pos[0](frame)
        if not ctl.has_group_input(name):
            raise RapidError(
                f"AliasIO: no signal {name} in the I/O configuration", "err_aliasio_def"
            )
        store(frame, name)

    return run


def _grip_load(c: _Compiler, args: list[N.Arg]) -> Callable[[Frame], None]:
    """GripLoad load: the controller is told the payload's mass (kg) and centre (mm)."""
    pos, _ = c.args("gripload", args)
    ctl = c.interp.controller

    def run(frame: Frame) -> None:
        load = pos[0](frame)
        cog = load["cog"]
        ctl.grip_load(float(load["mass"]), (cog["x"], cog["y"], cog["z"]))

    return run


_INSTRUCTIONS: dict[str, Builder] = {
    "moveabsj": _move_abs_j,
    "tpwrite": _tp_write,
    "write": _write,
    "open": _open,
    "close": _close,
    "tpreadnum": _tp_read_num,
    "tperase": lambda c, a: lambda f: c.interp.controller.tp_erase(),
    "incr": lambda c, a: _step(c, a, 1.0),
    "decr": lambda c, a: _step(c, a, -1.0),
    "clkreset": _clock("reset"),
    "clkstart": _clock("start"),
    "clkstop": _clock("stop"),
    "waittime": _wait_time,
    "stop": _stop,
    "aliasio": _alias_io,
    "gripload": _grip_load,
}


def _math(name: str, fn: Callable[..., float], result: Type, counted: str | None = None) -> Builder:
    """Return the builder of a function of numbers; ``counted``: the operation kind it counts."""

    def build(c: _Compiler, args: list[N.Arg]) -> Eval:
        pos, _ = c.args(name, args)
        ops = c.interp.ops

        def run(frame: Frame) -> Any:
            values = [p(frame) for p in pos]
            try:
                value = coerce(fn(*values), result)
            except (ValueError, ZeroDivisionError):
                raise RapidError(f"{name}: argument outside its domain") from None
            if counted:
                ops[counted] += 1
            return value

        return run

    return build


def _rounding(name: str, fn: Callable[[float], float], result: Type) -> Builder:
    def build(c: _Compiler, args: list[N.Arg]) -> Eval:
        pos, opt = c.args(name, args)
        dec = opt.get("dec")

        def run(frame: Frame) -> Any:
            d = int(dec(frame)) if dec else 0
            return coerce(fn(pos[0](frame) * 10**d) / 10**d, result)

        return run

    return build


def _round_half_away(x: float) -> float:
    return math.copysign(math.floor(abs(x) + 0.5), x)


def _to_str(name: str) -> Builder:
    def build(c: _Compiler, args: list[N.Arg]) -> Eval:
        pos, _ = c.args(name, args)
        return lambda f: string(fixed(pos[0](f), int(pos[1](f))))

    return build


def _group(name: str, result: Type) -> Builder:
    def build(c: _Compiler, args: list[N.Arg]) -> Eval:
        signal = _positional(args, 0)
        assert isinstance(signal, N.Name)
        ctl, key = c.interp.controller, signal.name.lower()
        if key not in c.interp.global_scope and key not in c.local:
            return lambda f: coerce(ctl.group_input(signal.name), result)
        bound = c.name(signal.name)  # a signalgi variable: the name AliasIO bound it to

        def read(frame: Frame) -> Any:
            alias = bound(frame)
            if alias is None:
                raise RapidError(
                    f"{name}: the signal variable {signal.name} is not bound (AliasIO)"
                )
            return coerce(ctl.group_input(alias), result)

        return read

    return build


def _clk_read(c: _Compiler, args: list[N.Arg]) -> Eval:
    pos, opt = c.args("clkread", args)
    ctl, high_res = c.interp.controller, "highres" in opt

    def run(frame: Frame) -> float:
        clock: Clock = pos[0](frame)
        t = clock.total_s + (ctl.now_s() - clock.since_s if clock.since_s is not None else 0.0)
        return f32(t if high_res else math.floor(t * 1000 + 1e-9) / 1000)

    return run


def _cjointt(c: _Compiler, args: list[N.Arg]) -> Eval:
    ctl = c.interp.controller

    def run(frame: Frame) -> Any:
        joints = ctl.joints_deg()
        robax = {f"rax_{i + 1}": f32(q) for i, q in enumerate(joints)}
        return {"robax": robax, "extax": {f"eax_{x}": f32(9e9) for x in "abcdef"}}

    return run


def _present(c: _Compiler, args: list[N.Arg]) -> Eval:
    key = _positional(args, 0).name.lower()  # type: ignore[union-attr]
    return lambda f: f.get(key) is not None


_FUNCTIONS: dict[str, Builder] = {
    "present": _present,
    "ginputdnum": _group("ginputdnum", DNUM),
    "ginput": _group("ginput", NUM),
    "clkread": _clk_read,
    "cjointt": _cjointt,
    "sqrt": _math("sqrt", math.sqrt, NUM, "sqrt"),
    "sqrtdnum": _math("sqrtdnum", math.sqrt, DNUM, "sqrt"),
    "abs": _math("abs", abs, NUM),
    "absdnum": _math("absdnum", abs, DNUM),
    "round": _rounding("round", _round_half_away, NUM),
    "rounddnum": _rounding("rounddnum", _round_half_away, DNUM),
    "trunc": _rounding("trunc", math.trunc, NUM),
    "truncdnum": _rounding("truncdnum", math.trunc, DNUM),
    "numtostr": _to_str("numtostr"),
    "dnumtostr": _to_str("dnumtostr"),
    "numtodnum": _math("numtodnum", float, DNUM),
    "dnumtonum": _math("dnumtonum", float, NUM),
    "strlen": _math("strlen", len, NUM),
    "sin": _math("sin", lambda d: math.sin(math.radians(d)), NUM),
    "cos": _math("cos", lambda d: math.cos(math.radians(d)), NUM),
    "tan": _math("tan", lambda d: math.tan(math.radians(d)), NUM),
    "asin": _math("asin", lambda x: math.degrees(math.asin(x)), NUM),
    "acos": _math("acos", lambda x: math.degrees(math.acos(x)), NUM),
    "atan": _math("atan", lambda x: math.degrees(math.atan(x)), NUM),
    "atan2": _math("atan2", lambda y, x: math.degrees(math.atan2(y, x)), NUM),
    "exp": _math("exp", math.exp, NUM),
    "pow": _math("pow", math.pow, NUM),
}
