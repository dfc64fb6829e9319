"""An interpreter of V+ programs, with V+ semantics.

It covers the instructions and functions the digital twin models (see
:mod:`wirecal.lang.vplus.forms`); any other instruction or function, valid V+ as it may
be, stops the program with a run-time error naming it.

Programs are compiled into Python closures once, dispatching on the node types of
:mod:`wirecal.lang.vplus.nodes`. Semantics (V+ Language User's Guide
v17): REAL is IEEE single precision and DOUBLE double (p. 102) — an operation whose
operands are all single is rounded to single, a store into a REAL rounds to single, and a
GLOBAL DOUBLE read or written by a program that does not declare it DOUBLE is treated as
single (p. 107); TRUE is −1 (p. 103); arrays grow on demand (p. 105); AUTO variables
belong to one call, LOCAL to the program, GLOBAL to all (p. 107); a CALL passes a variable
by reference and an expression by value (p. 42–45); reading an undefined variable is an
error (p. 110). Everything the program does to the outside world — motion, the encoder,
the disk, the terminal — goes through a controller
(:class:`wirecal.twin.vplus.controller.VplusController`).
"""

from __future__ import annotations

import math
import operator
from collections import Counter
from collections.abc import Callable

from wirecal.lang.syntax import node_method
from wirecal.lang.vplus import nodes as N
from wirecal.lang.vplus.forms import FormError, operands
from wirecal.lang.vplus.keywords import keyword
from wirecal.lang.vplus.parser import CONSTANTS, FUNCTIONS, Module, Program, transformation_names
from wirecal.solver import pose
from wirecal.twin.machine import Halt, Outcome, RunError, f32
from wirecal.twin.vplus.errors import (
    VError,
    array_index,
    division_by_zero,
    illegal_index,
    undefined,
)
from wirecal.twin.vplus.fused import fused_steps, fused_value, single_result


class Trans:
    """A V+ transformation: x, y, z (mm), yaw, pitch, roll (deg; see :mod:`pose`)."""

    __slots__ = ("pitch", "roll", "x", "y", "yaw", "z")

    def __init__(self, x, y, z, yaw, pitch, roll):
        self.x, self.y, self.z = float(x), float(y), float(z)
        self.yaw, self.pitch, self.roll = float(yaw), float(pitch), float(roll)

    def matrix(self):
        """Return the rotation matrix and position (see :mod:`pose`)."""
        return pose.matrix(*self.values())

    @classmethod
    def from_matrix(cls, R, p):
        """Build a transformation from a rotation matrix and a position."""
        return cls(*pose.values(R, p))

    def values(self):
        """Return x, y, z, yaw, pitch, roll."""
        return (self.x, self.y, self.z, self.yaw, self.pitch, self.roll)

    def shifted(self, dx, dy, dz):
        """Return SHIFT(t BY dx, dy, dz): the position moved, the orientation kept."""
        return Trans(self.x + dx, self.y + dy, self.z + dz, self.yaw, self.pitch, self.roll)


class _Return(Exception):
    pass


class Pause(Exception):
    """PAUSE: the program stops and may be resumed."""


class _Goto(Exception):
    def __init__(self, label: int):
        self.label = label


class _Ref:
    """A variable passed by reference (or a by-value copy).

    Get/set and whether it is double precision.
    """

    __slots__ = ("double", "get", "set")

    def __init__(self, get, set_, double):
        self.get, self.set, self.double = get, set_, double


class Interpreter:
    """Runs a parsed module against a cell; state (globals) persists across runs."""

    def __init__(self, module: Module, cell):
        self.module, self.cell = module, cell
        self.gvals: dict[str, object] = {}
        self.garr: dict[str, dict] = {}
        self._compiled: dict[str, Callable] = {}
        self._locals: dict[str, tuple[dict, dict]] = {}
        self.where = ("", 0)
        self.ops: Counter[str] = Counter()  # arithmetic executed: add (+ −), mul, div, sqrt
        self.transforms = transformation_names(module.programs)
        for name in module.programs:
            self._locals[name] = ({}, {})

    # ---------- running ----------
    def execute(self, name: str, *args) -> Outcome:
        """Run a program (EXECUTE); its outcome and the console lines it typed."""
        start = len(self.cell.console)
        try:
            self._program(name.lower())([_Ref(*self._value_cell(a)) for a in args])
            status, message = "completed", ""
        except Halt as h:
            status, message = "halted", str(h)
        except Pause as p:
            status, message = "paused", str(p)
        except RunError as e:
            status, message = "error", f"{e.message} ({e.code})"
        except RecursionError:
            status, message = "error", "*Stack overflow*"
        prog, line = self.where
        return Outcome(status, prog, line, message, self.cell.console[start:])

    def _value_cell(self, value):
        box = [value]
        return (lambda: box[0], lambda v: box.__setitem__(0, v), True)

    def _program(self, name: str) -> Callable:
        fn = self._compiled.get(name)
        if fn is None:
            prog = self.module.programs[name]
            fn = _Compiler(self, prog).compile()
            self._compiled[name] = fn
        return fn

    def set_global(self, name: str, value, index=None) -> None:
        """Preset a global (the twin loads readings as a run would have left them)."""
        if index is None:
            self.gvals[name.lower()] = value
        else:
            self.garr.setdefault(name.lower(), {})[index] = value

    def get_global(self, name: str, index=None):
        """Return a global (an element if ``index`` is given)."""
        if index is None:
            return self.gvals[name.lower()]
        return self.garr[name.lower()][index]


#: error code of a valid V+ instruction or function the twin does not model
UNMODELLED = -800


def _refuse(what: str) -> Callable:
    def refuse(frame):
        raise VError(UNMODELLED, f"*Not executed by the digital twin* {what}")

    return refuse


class _Compiler:
    """Compiles one program into a closure taking the list of argument refs."""

    def __init__(self, interp: Interpreter, prog: Program):
        self.i, self.prog = interp, prog
        self.params = {p.name: k for k, p in enumerate(prog.params)}
        self.autos: dict[str, int] = {}
        self.double: set[str] = set()
        self.local_vals, self.local_arr = interp._locals[prog.name]
        self.locals: set[str] = set()
        for name, decl in prog.declared.items():
            if decl.dtype == "DOUBLE":
                self.double.add(name)
            if decl.scope == "AUTO":
                self.autos[name] = len(self.params) + len(self.autos)
            elif decl.scope == "LOCAL":
                self.locals.add(name)
        self.nslots = len(self.params) + len(self.autos)
        self.slot_of: dict[Callable, int] = {}  # a DOUBLE AUTO scalar's setter → its slot
        self.place = (prog, interp.module)  # what fixes a node's meaning (fused_code.recipe_of)
        for name in ("expr", "_stmt"):  # bound once: each lookup of a dispatcher wraps anew
            setattr(self, name, vars(_Compiler)[name].__get__(self, _Compiler))

    def compile(self) -> Callable:
        body = self.body(self.prog.body)
        nparams, nslots, name = len(self.params), self.nslots, self.prog.name

        def run(args):
            frame = [None] * nslots
            for k in range(nparams):
                frame[k] = args[k] if k < len(args) else None
            try:
                body(frame)
            except _Goto as g:
                raise VError(
                    -403,
                    f"*Undefined label* {g.label} in {name} (not in this or an enclosing block)",
                ) from None
            except _Return:
                return

        return run

    def body(self, steps: list[N.Stmt]) -> Callable:
        """Compile a statement list.

        A GOTO to one of its labels continues there, a GOTO to any other label leaves it
        (to an enclosing list that has the label). Each statement's place (program, line)
        goes into the interpreter's ``where`` as it starts, by the list's own loop.
        """
        interp, name = self.i, self.prog.name
        if any(isinstance(s, N.Label) for s in steps):
            return self._labelled(steps)
        # each run of assignments written out as one function, which sets their places
        steps_at = [((name, s.line), f) for s, f in fused_steps(self, steps, self._stmt)]
        if len(steps_at) == 1:
            ((where, f),) = steps_at

            def one(frame):
                interp.where = where
                f(frame)

            return one

        def run(frame):
            for where, f in steps_at:
                interp.where = where
                f(frame)

        return run

    def _labelled(self, steps: list[N.Stmt]) -> Callable:
        """Compile a statement list with labels, statement by statement (:func:`_labelled`)."""
        steps_at: list[tuple[tuple[str, int], Callable]] = []
        labels: dict[int, int] = {}
        for s in steps:
            if isinstance(s, N.Label):
                labels[s.number] = len(steps_at)
            else:
                steps_at.append(((self.prog.name, s.line), self._stmt(s)))
        return _labelled(self.i, steps_at, labels)

    def condition(self, e: N.Expr | None) -> Callable:
        """Compile a condition: written out as one function where it can be (``fused``)."""
        written = None if e is None else fused_value(self, e)
        return written[0] if written is not None else self.expr(e)[0]

    # ---------- variables ----------
    def is_double(self, name: str) -> bool:
        if name in self.params:
            return False  # decided by the reference at run time; see ref_double
        return name in self.double

    def storage(self, kind: str, name: str, index_fns):
        """Compile the (getter, setter) of a variable."""
        if kind == "n" and name in self.i.transforms:
            kind = "t"

        def undefined_():
            undefined(name)

        if name in self.params:
            return self._param_storage(kind, self.params[name], index_fns, undefined_)
        rounding = kind == "n" and not self.is_double(name)
        if name in self.autos:
            return self._auto_storage(rounding, self.autos[name], index_fns, undefined_)
        return self._shared_storage(rounding, name, index_fns, undefined_)

    def _param_storage(self, kind: str, slot: int, index_fns, undefined):
        """Compile the access to a parameter: a reference in the frame."""
        interp = self.i
        if index_fns is None:

            def get(frame):
                ref = frame[slot]
                if ref is None:
                    undefined()
                return ref.get()

            def put(frame, v):
                ref = frame[slot]
                if ref is None:
                    ref = frame[slot] = _Ref(*interp._value_cell(None))
                ref.set(v if ref.double or kind != "n" else f32(v))

            return get, put
        ix = self._indexer(index_fns)

        def aget(frame):
            arr = frame[slot].get()
            try:
                return arr[ix(frame)]
            except KeyError:
                undefined()

        def aput(frame, v):
            frame[slot].get()[ix(frame)] = v if kind != "n" else f32(v)

        return aget, aput

    def _auto_storage(self, rounding: bool, slot: int, index_fns, undefined):
        """Compile the access to an AUTO variable: a value in the frame."""
        if index_fns is None:
            get, put = self._auto_scalar(rounding, slot, undefined)
            if not rounding:
                self.slot_of[put] = slot  # written in place by an assignment to it
            return get, put
        ix = self._indexer(index_fns)

        def aget(frame):
            arr = frame[slot]
            try:
                return arr[ix(frame)]
            except (KeyError, TypeError):
                undefined()

        def aput(frame, v):
            if frame[slot] is None:
                frame[slot] = {}
            frame[slot][ix(frame)] = f32(v) if rounding else v

        return aget, aput

    @staticmethod
    def _auto_scalar(rounding: bool, slot: int, undefined):
        """Compile the access to an AUTO variable without index."""

        def get(frame):
            v = frame[slot]
            if v is None:
                undefined()
            return v

        if rounding:

            def put(frame, v):
                frame[slot] = f32(v)
        else:

            def put(frame, v):
                frame[slot] = v

        return get, put

    def _shared_storage(self, rounding: bool, name: str, index_fns, undefined):
        """Compile the access to a LOCAL or global variable: a value in a dictionary."""
        vals = self.local_vals if name in self.locals else self.i.gvals
        if index_fns is None:

            def get(frame):
                try:
                    v = vals[name]
                except KeyError:
                    undefined()
                return f32(v) if rounding and v is not None else v

            def put(frame, v):
                vals[name] = f32(v) if rounding else v

            return get, put
        ix = self._indexer(index_fns)
        arr = self.array(name)

        def aget(frame):
            try:
                v = arr[ix(frame)]
            except KeyError:
                undefined()
            return f32(v) if rounding else v

        def aput(frame, v):
            arr[ix(frame)] = f32(v) if rounding else v

        return aget, aput

    def array(self, name: str) -> dict:
        """Return the elements of the LOCAL or global array ``name`` (kept from now on)."""
        return (self.local_arr if name in self.locals else self.i.garr).setdefault(name, {})

    def _indexer(self, index_fns):
        if len(index_fns) == 1:
            f = index_fns[0]

            def ix(frame):
                k = array_index(f(frame))
                if k < 0:
                    illegal_index(k)
                return k

            return ix

        def ixs(frame):
            return tuple(array_index(g(frame)) for g in index_fns)

        return ixs

    def var(self, v: N.Var):
        """(getter, setter) of a variable node."""
        return self.storage(v.kind, v.name, [self.expr(x)[0] for x in v.index] if v.index else None)

    def ref_of(self, e: N.Expr | None) -> Callable:
        """Compile a CALL argument.

        A reference for a variable or array element, a copy for an expression (User's
        Guide p. 42–45); ``None`` for an omitted argument.
        """
        interp = self.i
        if e is None:
            return lambda frame: None
        if isinstance(e, N.ArrayArg):
            name = e.name
            if name in self.params:
                slot = self.params[name]
                return lambda frame: frame[slot]
            if name in self.autos:
                slot = self.autos[name]
                double = name in self.double

                def auto_arr(frame):
                    if frame[slot] is None:
                        frame[slot] = {}
                    arr = frame[slot]
                    return _Ref(lambda: arr, None, double)

                return auto_arr
            arrs = self.local_arr if name in self.locals else interp.garr
            double = name in self.double
            return lambda frame: _Ref(lambda: arrs.setdefault(name, {}), None, double)
        if isinstance(e, N.Var) and e.name not in CONSTANTS and not _is_keyword_value(e):
            get, put = self.var(e)
            if e.name in self.params and not e.index:
                slot = self.params[e.name]
                return lambda frame: frame[slot]
            double = self.is_double(e.name) or e.kind != "n"
            return lambda frame: _Ref(lambda: get(frame), lambda v: put(frame, v), double)
        f, _ = self.expr(e)
        return lambda frame: _Ref(*interp._value_cell(f(frame)))

    # ---------- expressions: (function, is_double) ----------
    @node_method
    def expr(self, e: N.Expr):
        return _refuse(f"{type(e).__name__} as a value"), False

    @expr.register
    def _(self, e: N.Paren):
        return self.expr(e.expr)

    @expr.register
    def _(self, e: N.Num):
        v = e.value if e.double else f32(e.value)
        return (lambda frame: v), e.double

    @expr.register
    def _(self, e: N.Str):
        s = e.text
        return (lambda frame: s), True

    @expr.register
    def _(self, e: N.Var):
        if e.index is None and e.name in CONSTANTS:
            c = CONSTANTS[e.name]
            return (lambda frame: c), False
        if _is_keyword_value(e):
            return _refuse(e.name.upper()), False
        get, _ = self.var(e)
        return get, self.is_double(e.name) or e.name in self.params

    @expr.register
    def _(self, e: N.Neg):
        f, d = self.expr(e.expr)
        return (lambda frame: -f(frame)), d

    @expr.register
    def _(self, e: N.Not):
        f, _ = self.expr(e.expr)
        return (lambda frame: -1.0 if f(frame) == 0 else 0.0), False

    @expr.register
    def _(self, e: N.Com):
        f, _ = self.expr(e.expr)
        return (lambda frame: float(~round(f(frame)))), False

    @expr.register
    def _(self, e: N.Logic):
        a, _ = self.expr(e.left)
        b, _ = self.expr(e.right)
        op = e.op
        if op == "AND":
            return (lambda frame: -1.0 if a(frame) != 0 and b(frame) != 0 else 0.0), False
        if op == "OR":
            return (lambda frame: -1.0 if a(frame) != 0 or b(frame) != 0 else 0.0), False
        if op == "XOR":
            return (lambda frame: -1.0 if (a(frame) != 0) != (b(frame) != 0) else 0.0), False
        bitwise = {"BAND": int.__and__, "BOR": int.__or__, "BXOR": int.__xor__}[op]
        return (lambda frame: float(bitwise(round(a(frame)), round(b(frame))))), False

    @expr.register
    def _(self, e: N.Compare):
        a, _ = self.expr(e.left)
        b, _ = self.expr(e.right)
        op = _COMPARE[e.op]
        return (lambda frame: -1.0 if op(a(frame), b(frame)) else 0.0), False

    @expr.register
    def _(self, e: N.BinOp):
        written = fused_value(self, e)
        if written is not None:
            return written
        op = e.op
        a, da = self.expr(e.left)
        b, db = self.expr(e.right)
        if da or db:
            return _arithmetic(self.i, op, a, b), True
        if op in _SINGLE:
            return _single_arithmetic(self.i.ops, *_SINGLE[op], a, b), False
        return self._single(_arithmetic(self.i, op, a, b)), False

    @staticmethod
    def _single(f):
        def g(frame):
            v = f(frame)
            return v if isinstance(v, str) else f32(v)

        return g

    @expr.register
    def _(self, e: N.Shift):
        base = self.expr(e.base)[0]
        dx, dy, dz = (self.expr(x)[0] for x in (e.dx, e.dy, e.dz))
        return (lambda frame: base(frame).shifted(dx(frame), dy(frame), dz(frame))), True

    @expr.register
    def _(self, e: N.Func):
        """Compile a V+ function call."""
        name, args = e.name, e.args
        if name not in FUNCTIONS:
            return _refuse(f"function {name.upper()}"), False
        if name == "defined":
            if not isinstance(args[0], N.Var):
                return _refuse("DEFINED of anything but a variable"), False
            return self._defined(args[0]), False
        if name == "switch":
            if not isinstance(args[0], N.Var):
                return _refuse("SWITCH of anything but a switch name"), False
            switch, cell = args[0].name.upper(), self.i.cell
            return (lambda frame: cell.switch(switch)), False
        if name == "device":
            return self._device(args), False
        fns = [self.expr(a) if a is not None else (_zero, False) for a in args]
        double = any(d for _, d in fns)
        f = [x for x, _ in fns]
        if name in _MATH_FUNCTIONS:
            return self._math_function(name, f, double), double
        return self._controller_function(name, args, f)

    def _defined(self, var: N.Var) -> Callable:
        """Compile DEFINED(var): -1 if the variable has a value, else 0."""
        get, _ = self.var(var)

        def defined(frame):
            try:
                get(frame)
                return -1.0
            except VError:
                return 0.0

        return defined

    def _device(self, args: list) -> Callable:
        """Compile DEVICE(type, unit, error, select): the value, the error into its variable."""
        cell = self.i.cell
        unit = self.expr(args[1])[0]
        sel = self.expr(args[3])[0]
        _, put_err = self.var(args[2])

        def device(frame):
            value, err = cell.device(int(unit(frame)), int(sel(frame)))
            put_err(frame, err)
            return value

        return device

    def _math_function(self, name: str, f: list[Callable], double: bool) -> Callable:
        """Compile INT, ABS, SQRT, MIN, MAX, SIN, COS or ATAN2 (angles in degrees)."""
        if name == "int":
            return lambda frame: float(math.trunc(f[0](frame)))
        if name == "abs":
            return lambda frame: abs(f[0](frame))
        if name == "sqrt":
            sqrt = _sqrt(self.i, f[0])
            return sqrt if double else self._single(sqrt)
        if name == "min":
            return lambda frame: min(f[0](frame), f[1](frame))
        if name == "max":
            return lambda frame: max(f[0](frame), f[1](frame))
        if name in ("sin", "cos"):
            trig = math.sin if name == "sin" else math.cos
            return lambda frame: trig(math.radians(f[0](frame)))
        assert name == "atan2"
        return lambda frame: math.degrees(math.atan2(f[0](frame), f[1](frame)))

    def _controller_function(self, name: str, args: list, f: list[Callable]):
        """Compile a string, location or cell function: (function, is_double)."""
        cell = self.i.cell
        if name == "iostat":
            return (lambda frame: cell.iostat(int(f[0](frame)))), False
        if name == "$error":
            return (lambda frame: cell.error_text(int(f[0](frame)))), True
        if name == "$chr":
            return _chr(f[0]), True
        if name == "len":
            return (lambda frame: float(len(f[0](frame)))), False
        if name == "belt":
            belt = args[0].name
            return (lambda frame: cell.belt(belt, int(f[1](frame)))), False
        if name == "#ppoint":
            return (lambda frame: tuple(f32(g(frame)) for g in f)), True
        if name == "trans":
            f += [_zero] * (6 - len(f))
            return (lambda frame: Trans(*(f32(g(frame)) for g in f))), True
        if name == "sig":
            return (lambda frame: cell.sig(int(f[0](frame)))), False
        if name == "timer":
            return (lambda frame: cell.timer(int(f[0](frame)))), True
        raise AssertionError(name)  # pragma: no cover - FUNCTIONS and this list agree

    # ---------- statements ----------
    @node_method
    def _stmt(self, s: N.Stmt) -> Callable:  # pragma: no cover - every step type is registered
        raise AssertionError(type(s).__name__)

    @_stmt.register
    def _(self, s: N.Assign):
        _, put = self.var(s.target)
        f, _ = self.expr(s.value)
        slot = self.slot_of.get(put)
        if slot is not None:  # a DOUBLE AUTO scalar: its setter's store, in place

            def assign(frame):
                frame[slot] = f(frame)

            return assign
        return lambda frame: put(frame, f(frame))

    @_stmt.register
    def _(self, s: N.Call):
        interp = self.i
        callee = s.program
        if callee not in interp.module.programs:
            return _refuse(f"CALL {callee} (not in the module)")
        refs = [self.ref_of(x) for x in s.args]

        def call(frame):
            interp._program(callee)([r(frame) for r in refs])

        return call

    @_stmt.register
    def _(self, s: N.Goto):
        label = s.label

        def goto(frame):
            raise _Goto(label)

        return goto

    @_stmt.register
    def _(self, s: N.IfGoto):
        label = s.label
        cond = self.condition(s.cond)

        def if_goto(frame):
            if cond(frame) != 0:
                raise _Goto(label)

        return if_goto

    @_stmt.register
    def _(self, s: N.If):
        cond = self.condition(s.cond)
        then = self.body(s.then)
        other = self.body(s.orelse) if s.orelse else None

        def if_(frame):
            if cond(frame) != 0:
                then(frame)
            elif other is not None:
                other(frame)

        return if_

    @_stmt.register
    def _(self, s: N.For):
        get, put = self.var(s.var)
        fa, fb = self.expr(s.start)[0], self.expr(s.stop)[0]
        fs = self.expr(s.step)[0] if s.step is not None else (lambda frame: 1.0)
        body = self.body(s.body)

        def for_(frame):
            step = fs(frame)
            end = fb(frame)
            put(frame, fa(frame))
            while (get(frame) <= end) if step > 0 else (get(frame) >= end):
                body(frame)
                put(frame, get(frame) + step)

        return for_

    @_stmt.register
    def _(self, s: N.While):
        cond = self.condition(s.cond)
        body = self.body(s.body)

        def while_(frame):
            while cond(frame) != 0:
                body(frame)

        return while_

    @_stmt.register
    def _(self, s: N.DoUntil):
        cond = self.condition(s.cond)
        body = self.body(s.body)

        def do_until(frame):
            body(frame)
            while cond(frame) == 0:
                body(frame)

        return do_until

    @_stmt.register
    def _(self, s: N.Case):
        sel = self.expr(s.selector)[0]
        branches = [
            (
                [self.expr(v)[0] for v in b.values] if b.values is not None else None,
                self.body(b.body),
            )
            for b in s.branches
        ]

        def case(frame):
            x = sel(frame)
            for values, body in branches:
                if values is None or any(x == v(frame) for v in values):
                    body(frame)
                    return

        return case

    @_stmt.register
    def _(self, s: N.Instruction):
        try:
            ops = [e for _, e in operands(s)]
        except FormError as exc:
            return _refuse(str(exc))
        handler = getattr(self, "ins_" + s.name.replace(".", "_"))
        return handler(s, ops)

    # ---------- the instructions of forms.FORMS (operands in the order of the form) ----------
    def ins_move(self, s, ops):
        get = self.expr(ops[0])[0]
        straight = s.name == "moves"
        cell = self.i.cell
        return lambda frame: cell.move(get(frame), straight)

    ins_moves = ins_move

    def ins_break(self, s, ops):
        cell = self.i.cell
        return lambda frame: cell.break_()

    def ins_here(self, s, ops):
        _, put = self.var(ops[0])
        transform = ops[0].kind != "l"
        cell = self.i.cell
        return lambda frame: put(frame, cell.here(transform))

    def ins_set(self, s, ops):
        _, put = self.var(ops[0])
        f, _ = self.expr(ops[1])
        return lambda frame: put(frame, f(frame))

    def ins_decompose(self, s, ops):
        target, loc = ops
        if not target.index:
            return _refuse("DECOMPOSE into a whole array name (give its first element)")
        start = self.expr(target.index[0])[0]
        get_loc, _ = self.var(loc)

        def getloc(frame):
            v = get_loc(frame)
            return v.values() if isinstance(v, Trans) else v

        at = [0]
        _, put = self.storage("n", target.name, [lambda frame: at[0]])

        def decompose(frame):
            first = round(start(frame))
            for k, v in enumerate(getloc(frame)):
                at[0] = first + k
                put(frame, v)

        return decompose

    def _configure(self, s, ops):
        word = s.name.upper()
        cell = self.i.cell
        return lambda frame: cell.configure(word)

    ins_above = ins_below = ins_flip = ins_noflip = ins_lefty = ins_righty = _configure

    def ins_speed(self, s, ops):
        f = self.expr(ops[0])[0]
        cell = self.i.cell
        return lambda frame: cell.speed(f(frame))

    def ins_accel(self, s, ops):
        fs = [self.expr(x)[0] for x in ops]
        cell = self.i.cell
        return lambda frame: cell.accel(*(g(frame) for g in fs))

    def ins_type(self, s, ops):
        if any(c is not None and c.formats for c in s.clauses):
            return _refuse("TYPE with format specifiers")
        fs = [self.expr(x)[0] for x in ops]
        cell = self.i.cell
        return lambda frame: cell.type_("".join(_text(g(frame)) for g in fs))

    def ins_prompt(self, s, ops):
        text = self.expr(ops[0])[0]
        target = ops[1]
        _, put = self.var(target)
        string = target.kind == "s"
        cell = self.i.cell

        def prompt(frame):
            answer = cell.prompt(text(frame))
            put(frame, answer if string else float(answer))

        return prompt

    def ins_wait_event(self, s, ops):
        f = self.expr(ops[0])[0]
        cell = self.i.cell
        return lambda frame: cell.wait(f(frame))

    def ins_timer(self, s, ops):
        number, value = (self.expr(x)[0] for x in ops)
        cell = self.i.cell
        return lambda frame: cell.set_timer(int(number(frame)), value(frame))

    def ins_attach(self, s, ops):
        _, put = self.var(ops[0])
        device = self.expr(ops[2])[0]
        cell = self.i.cell
        return lambda frame: put(frame, cell.attach(device(frame)))

    def ins_detach(self, s, ops):
        f = self.expr(ops[0])[0]
        cell = self.i.cell
        return lambda frame: cell.detach(int(f(frame)))

    def ins_fopenw(self, s, ops):
        mode = s.name.upper()
        lun, name = self.expr(ops[0])[0], self.expr(ops[1])[0]
        cell = self.i.cell
        return lambda frame: cell.fopen(mode, int(lun(frame)), name(frame))

    ins_fopena = ins_fopenr = ins_fopenw

    def ins_fclose(self, s, ops):
        f = self.expr(ops[0])[0]
        cell = self.i.cell
        return lambda frame: cell.fclose(int(f(frame)))

    def ins_write(self, s, ops):
        lun, f = self.expr(ops[0])[0], self.expr(ops[1])[0]
        cell = self.i.cell
        return lambda frame: cell.write(int(lun(frame)), f(frame))

    def ins_enable(self, s, ops):
        switch = ops[0].name.upper()
        cell = self.i.cell
        return lambda frame: cell.enable(switch)

    def ins_defbelt(self, s, ops):
        name = ops[0].name
        enc, scale = self.expr(ops[1])[0], self.expr(ops[2])[0]
        cell = self.i.cell
        return lambda frame: cell.defbelt(name, int(enc(frame)), scale(frame))

    def ins_tool(self, s, ops):
        cell = self.i.cell
        return lambda frame: cell.tool_null()

    def ins_halt(self, s, ops):
        def halt(frame):
            raise Halt("HALT")

        return halt

    def ins_pause(self, s, ops):
        cell = self.i.cell

        def pause(frame):
            if not cell.on_pause():
                raise Pause("PAUSE")

        return pause

    def ins_return(self, s, ops):
        def ret(frame):
            raise _Return()

        return ret


_COMPARE = {
    "==": lambda x, y: x == y,
    "<>": lambda x, y: x != y,
    "<": lambda x, y: x < y,
    ">": lambda x, y: x > y,
    "<=": lambda x, y: x <= y,
    ">=": lambda x, y: x >= y,
}


def _labelled(
    interp: Interpreter, steps: list[tuple[tuple[str, int], Callable]], labels: dict[int, int]
) -> Callable:
    """Compile a statement list with labels: a GOTO to one of them continues there.

    ``steps``: each statement's place (set in ``interp.where`` as it starts) and closure.
    """
    n = len(steps)

    def run_labelled(frame):
        pc = 0
        while pc < n:
            try:
                while pc < n:
                    interp.where, f = steps[pc]
                    f(frame)
                    pc += 1
            except _Goto as g:
                if g.label not in labels:
                    raise
                pc = labels[g.label]

    return run_labelled


def _arithmetic(interp, op: str, a: Callable, b: Callable) -> Callable:
    """Compile ``a op b`` for +, -, *, / and MOD, counting the operations as executed."""
    ops = interp.ops  # cleared, never replaced
    if op == "+":

        def f(frame):
            ops["add"] += 1
            return a(frame) + b(frame)
    elif op == "-":

        def f(frame):
            ops["add"] += 1
            return a(frame) - b(frame)
    elif op == "*":

        def f(frame):
            ops["mul"] += 1
            return a(frame) * b(frame)
    else:
        f = _division(interp, op, a, b)
    return f


_SINGLE = {"+": ("add", operator.add), "-": ("add", operator.sub), "*": ("mul", operator.mul)}
"""The REAL operations :func:`_single_arithmetic` compiles: the counter and the operation."""


def _single_arithmetic(ops: Counter, counter: str, combine: Callable, a: Callable, b: Callable):
    """Compile ``a + b``, ``a - b`` or ``a * b`` of REALs, rounded, in one closure.

    :func:`_arithmetic` rounded to single precision as ``_Compiler._single`` rounds it (a
    string as it is): the commonest operations of the twin's runs, a call or two fewer each.
    """

    def f(frame):
        ops[counter] += 1
        return single_result(combine(a(frame), b(frame)))

    return f


def _division(interp, op: str, a: Callable, b: Callable) -> Callable:
    """Compile ``a / b`` or ``a MOD b``; a zero divisor is V+ error -409."""
    ops = interp.ops
    if op == "/":

        def f(frame):
            ops["div"] += 1
            d = b(frame)
            if d == 0:
                division_by_zero()
            return a(frame) / d
    else:  # MOD

        def f(frame):
            d = b(frame)
            if d == 0:
                division_by_zero()
            return math.fmod(a(frame), d)

    return f


_MATH_FUNCTIONS = frozenset({"int", "abs", "sqrt", "min", "max", "sin", "cos", "atan2"})


def _zero(frame) -> float:
    """Return 0: an omitted TRANS argument."""
    return 0.0


def _sqrt(interp, x: Callable) -> Callable:
    """Compile SQRT; a negative argument is V+ error -413."""

    def sqrt(frame):
        v = x(frame)
        if v < 0:
            raise VError(-413, "*Negative square root*")
        interp.ops["sqrt"] += 1
        return math.sqrt(v)

    return sqrt


def _chr(x: Callable) -> Callable:
    """Compile $CHR; a code outside 0..255 is V+ error -410."""

    def chr_(frame):
        c = int(x(frame))
        if not 0 <= c <= 255:
            raise VError(-410, f"*Illegal value* $CHR({c})")
        return chr(c)

    return chr_


def _is_keyword_value(v: N.Var) -> bool:
    """Tell whether a name is a V+ keyword used as a value.

    A name without index that is a V+ keyword is the keyword (the checker allows only
    value keywords there), never a variable.
    """
    return v.index is None and keyword(v.name) is not None


def _text(v) -> str:
    """TYPE's text of a value: strings as they are, numbers in a short general format."""
    if isinstance(v, str):
        return v
    if isinstance(v, float) and abs(v) < 1e15 and v == int(v):  # NaN, ±inf: the format
        return str(int(v))
    return f"{v:.7g}"
