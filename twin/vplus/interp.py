"""An interpreter of the V+ subset wirecal emits, with V+ semantics.

Programs are compiled into Python closures once. Semantics (V+ Language User's Guide
v17): REAL is IEEE single precision and DOUBLE double (p. 102) — an operation whose
operands are all single is rounded to single, a store into a REAL rounds to single, and a
GLOBAL DOUBLE read or written by a program that does not declare it DOUBLE is treated as
single (p. 107); TRUE is −1 (p. 103); arrays grow on demand (p. 105); AUTO variables
belong to one call, LOCAL to the program, GLOBAL to all (p. 107); a CALL passes a variable
by reference and an expression by value (p. 42–45); reading an undefined variable is an
error (p. 110). Everything the program does to the outside world — motion, the encoder,
the disk, the terminal — goes through a :class:`Cell` (see :mod:`wirecal.twin.cell`).
"""

from __future__ import annotations

import math
import struct
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

from wirecal.solver import pose
from wirecal.twin.vplus.parser import Module, Program, transformation_names

_S = struct.Struct("f")


def f32(x: float) -> float:
    """Round to IEEE single precision (a V+ REAL)."""
    try:
        return _S.unpack(_S.pack(x))[0]
    except OverflowError:
        raise VError(-405, "*Floating-point overflow*") from None


class Trans:
    """A V+ transformation: x, y, z (mm), yaw, pitch, roll (deg; see :mod:`pose`)."""

    __slots__ = ("pitch", "roll", "x", "y", "yaw", "z")

    def __init__(self, x, y, z, yaw, pitch, roll):
        self.x, self.y, self.z = float(x), float(y), float(z)
        self.yaw, self.pitch, self.roll = float(yaw), float(pitch), float(roll)

    def matrix(self):
        return pose.matrix(*self.values())

    @classmethod
    def from_matrix(cls, R, p):
        return cls(*pose.values(R, p))

    def values(self):
        return (self.x, self.y, self.z, self.yaw, self.pitch, self.roll)

    def shifted(self, dx, dy, dz):
        return Trans(self.x + dx, self.y + dy, self.z + dz, self.yaw, self.pitch, self.roll)


class VError(Exception):
    """A V+ run-time error: the program stops with this code and message."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code, self.message = code, message


class _Return(Exception):
    pass


class Halt(Exception):
    pass


class Pause(Exception):
    pass


class _Goto(Exception):
    def __init__(self, label: int):
        self.label = label


@dataclass
class Outcome:
    """How a program ended: "completed", "halted", "paused" or "error"."""

    status: str
    program: str = ""
    line: int = 0
    message: str = ""
    console: list[str] = field(default_factory=list)


class _Ref:
    """A variable passed by reference (or a by-value copy): get/set and whether it is
    double precision."""

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
        except VError as e:
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
        if index is None:
            return self.gvals[name.lower()]
        return self.garr[name.lower()][index]


class _Compiler:
    """Compiles one program into a closure taking the list of argument refs."""

    def __init__(self, interp: Interpreter, prog: Program):
        self.i, self.prog = interp, prog
        self.params = {p[1]: k for k, p in enumerate(prog.params)}
        self.autos: dict[str, int] = {}
        self.double: set[str] = set()
        self.local_vals, self.local_arr = interp._locals[prog.name]
        self.locals: set[str] = set()
        for name, (cls, dtype) in prog.declared.items():
            if dtype == "DOUBLE":
                self.double.add(name)
            if cls == "AUTO":
                self.autos[name] = len(self.params) + len(self.autos)
            elif cls == "LOCAL":
                self.locals.add(name)
        self.nslots = len(self.params) + len(self.autos)

    def compile(self) -> Callable:
        body, labels = self.top(self.prog.body)
        nparams, nslots, name = len(self.params), self.nslots, self.prog.name

        def run(args):
            frame = [None] * nslots
            for k in range(nparams):
                frame[k] = args[k] if k < len(args) else None
            pc = 0
            n = len(body)
            while pc < n:
                try:
                    while pc < n:
                        body[pc](frame)
                        pc += 1
                except _Goto as g:
                    if g.label not in labels:  # pragma: no cover - checked on load
                        raise VError(-403, f"*Undefined label* {g.label} in {name}") from None
                    pc = labels[g.label]
                except _Return:
                    return

        return run

    def top(self, steps):
        body, labels = [], {}
        for s in steps:
            if s[0] == "label":
                labels[s[2]] = len(body)
                continue
            body.append(self.stmt(s))
        return body, labels

    def block(self, steps) -> Callable:
        fns = [self.stmt(s) for s in steps if s[0] != "label"]
        if len(fns) == 1:
            return fns[0]

        def run(frame):
            for f in fns:
                f(frame)

        return run

    # ---------- variables ----------
    def is_double(self, name: str) -> bool:
        if name in self.params:
            return False  # decided by the reference at run time; see ref_double
        return name in self.double

    def storage(self, kind: str, name: str, index_fns):
        """(getter, setter, double?) for a variable, compiled."""
        interp = self.i
        if kind == "n" and name in interp.transforms:
            kind = "t"
        rounding = kind == "n" and not self.is_double(name)

        def undefined():
            raise VError(-406, f"*Undefined value* {name}")

        if name in self.params:
            slot = self.params[name]
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
        if name in self.autos:
            slot = self.autos[name]
            if index_fns is None:

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
        vals, arrs = (
            (self.local_vals, self.local_arr)
            if name in self.locals
            else (interp.gvals, interp.garr)
        )
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
        arr = arrs.setdefault(name, {})

        def aget(frame):
            try:
                v = arr[ix(frame)]
            except KeyError:
                undefined()
            return f32(v) if rounding else v

        def aput(frame, v):
            arr[ix(frame)] = f32(v) if rounding else v

        return aget, aput

    def _indexer(self, index_fns):
        if len(index_fns) == 1:
            f = index_fns[0]

            def ix(frame):
                k = math.floor(f(frame) + 0.5)
                if k < 0:
                    raise VError(-407, f"*Illegal array index* {k}")
                return k

            return ix

        def ixs(frame):
            return tuple(math.floor(g(frame) + 0.5) for g in index_fns)

        return ixs

    def ref_of(self, e) -> Callable:
        """A CALL argument: a reference for a variable, a copy for an expression."""
        interp = self.i
        if e[0] == "array":
            name = e[2]
            if name in self.params:
                slot = self.params[name]
                return lambda frame: frame[slot]
            if name in self.autos:
                slot = self.autos[name]

                def auto_arr(frame):
                    if frame[slot] is None:
                        frame[slot] = {}
                    arr = frame[slot]
                    return _Ref(lambda: arr, None, name in self.double)

                return auto_arr
            arrs = self.local_arr if name in self.locals else interp.garr
            double = name in self.double
            return lambda frame: _Ref(lambda: arrs.setdefault(name, {}), None, double)
        if e[0] == "var":
            get, put = self.storage(e[1], e[2], [self.expr(x)[0] for x in e[3]] if e[3] else None)
            if e[2] in self.params and not e[3]:
                slot = self.params[e[2]]
                return lambda frame: frame[slot]
            double = self.is_double(e[2]) or e[1] != "n"
            return lambda frame: _Ref(lambda: get(frame), lambda v: put(frame, v), double)
        f, _ = self.expr(e)
        return lambda frame: _Ref(*interp._value_cell(f(frame)))

    # ---------- expressions: (function, is_double) ----------
    def expr(self, e):
        tag = e[0]
        if tag == "paren":
            return self.expr(e[1])
        if tag == "num":
            v = e[1] if e[2] else f32(e[1])
            return (lambda frame: v), e[2]
        if tag == "str":
            s = e[1]
            return (lambda frame: s), True
        if tag == "var":
            get, _ = self.storage(e[1], e[2], [self.expr(x)[0] for x in e[3]] if e[3] else None)
            return get, self.is_double(e[2]) or e[2] in self.params
        if tag == "neg":
            f, d = self.expr(e[1])
            return (lambda frame: -f(frame)), d
        if tag == "not":
            f, _ = self.expr(e[1])
            return (lambda frame: -1.0 if f(frame) == 0 else 0.0), False
        if tag == "and":
            a, _ = self.expr(e[1])
            b, _ = self.expr(e[2])
            return (lambda frame: -1.0 if a(frame) != 0 and b(frame) != 0 else 0.0), False
        if tag == "or":
            a, _ = self.expr(e[1])
            b, _ = self.expr(e[2])
            return (lambda frame: -1.0 if a(frame) != 0 or b(frame) != 0 else 0.0), False
        if tag == "cmp":
            a, _ = self.expr(e[2])
            b, _ = self.expr(e[3])
            op = {
                "==": lambda x, y: x == y,
                "<>": lambda x, y: x != y,
                "<": lambda x, y: x < y,
                ">": lambda x, y: x > y,
                "<=": lambda x, y: x <= y,
                ">=": lambda x, y: x >= y,
            }[e[1]]
            return (lambda frame: -1.0 if op(a(frame), b(frame)) else 0.0), False
        if tag == "bin":
            return self.binop(e)
        if tag == "fn":
            return self.function(e)
        raise AssertionError(tag)  # pragma: no cover

    def binop(self, e):
        op = e[1]
        a, da = self.expr(e[2])
        b, db = self.expr(e[3])
        double = da or db
        interp = self.i
        if op == "+":

            def f(frame):
                interp.ops["add"] += 1
                return a(frame) + b(frame)
        elif op == "-":

            def f(frame):
                interp.ops["add"] += 1
                return a(frame) - b(frame)
        elif op == "*":

            def f(frame):
                interp.ops["mul"] += 1
                return a(frame) * b(frame)
        elif op == "/":

            def f(frame):
                interp.ops["div"] += 1
                d = b(frame)
                if d == 0:
                    raise VError(-409, "*Division by zero*")
                return a(frame) / d
        else:  # MOD

            def f(frame):
                d = b(frame)
                if d == 0:
                    raise VError(-409, "*Division by zero*")
                return math.fmod(a(frame), d)

        return (f, True) if double else (self._single(f), False)

    @staticmethod
    def _single(f):
        def g(frame):
            v = f(frame)
            return v if isinstance(v, str) else f32(v)

        return g

    def function(self, e):
        name, args = e[1], e[2]
        cell = self.i.cell
        fns = [self.expr(a) for a in args if a[0] != "var" or name not in ("defined",)]
        double = any(d for _, d in fns)
        if name == "defined":
            v = args[0]
            get, _ = self.storage(v[1], v[2], [self.expr(x)[0] for x in v[3]] if v[3] else None)

            def defined(frame):
                try:
                    get(frame)
                    return -1.0
                except VError:
                    return 0.0

            return defined, False
        if name == "device":
            unit = self.expr(args[1])[0]
            sel = self.expr(args[3])[0]
            _, put_err = self.storage("n", args[2][2], None)

            def device(frame):
                value, err = cell.device(int(unit(frame)), int(sel(frame)))
                put_err(frame, err)
                return value

            return device, False
        f = [x for x, _ in fns]
        interp = self.i
        if name == "int":
            return (lambda frame: float(math.trunc(f[0](frame)))), double
        if name == "abs":
            return (lambda frame: abs(f[0](frame))), double
        if name == "sqrt":

            def sqrt(frame):
                v = f[0](frame)
                if v < 0:
                    raise VError(-413, "*Negative square root*")
                interp.ops["sqrt"] += 1
                return math.sqrt(v)

            return (sqrt if double else self._single(sqrt)), double
        if name == "min":
            return (lambda frame: min(f[0](frame), f[1](frame))), double
        if name == "max":
            return (lambda frame: max(f[0](frame), f[1](frame))), double
        if name in ("sin", "cos"):
            trig = math.sin if name == "sin" else math.cos
            return (lambda frame: trig(math.radians(f[0](frame)))), double
        if name == "atan2":
            return (lambda frame: math.degrees(math.atan2(f[0](frame), f[1](frame)))), double
        if name == "iostat":
            return (lambda frame: cell.iostat(int(f[0](frame)))), False
        if name == "$error":
            return (lambda frame: cell.error_text(int(f[0](frame)))), True
        if name == "$chr":

            def chr_(frame):
                c = int(f[0](frame))
                if not 0 <= c <= 255:
                    raise VError(-410, f"*Illegal value* $CHR({c})")
                return chr(c)

            return chr_, True
        if name == "len":
            return (lambda frame: float(len(f[0](frame)))), False
        if name == "belt":
            belt = args[0][2]
            return (lambda frame: cell.belt(belt, int(f[1](frame)))), False
        if name == "#ppoint":
            return (lambda frame: tuple(f32(g(frame)) for g in f)), True
        if name == "trans":
            return (lambda frame: Trans(*(f32(g(frame)) for g in f))), True
        if name == "shift":
            return (lambda frame: f[0](frame).shifted(f[1](frame), f[2](frame), f[3](frame))), True
        if name == "sig":
            return (lambda frame: cell.sig(int(f[0](frame)))), False
        raise AssertionError(name)  # pragma: no cover - rejected on load

    # ---------- statements ----------
    def stmt(self, s):
        prog = self.prog.name
        interp = self.i
        line = s[1]
        inner = self._stmt(s)

        def run(frame):
            interp.where = (prog, line)
            inner(frame)

        return run

    def _stmt(self, s):
        kind = s[0]
        cell = self.i.cell
        interp = self.i
        if isinstance(s, list):
            return self._block_stmt(s)
        a = s[2:]
        if kind == "assign":
            target, expr = a
            _, put = self.storage(
                target[1], target[2], [self.expr(x)[0] for x in target[3]] if target[3] else None
            )
            f, _ = self.expr(expr)
            return lambda frame: put(frame, f(frame))
        if kind == "call":
            callee = a[0]
            refs = [self.ref_of(x) for x in a[1]]

            def call(frame):
                interp._program(callee)([r(frame) for r in refs])

            return call
        if kind == "goto":
            label = a[0]

            def goto(frame):
                raise _Goto(label)

            return goto
        if kind == "return":

            def ret(frame):
                raise _Return()

            return ret
        if kind == "halt":

            def halt(frame):
                raise Halt("HALT")

            return halt
        if kind == "pause":

            def pause(frame):
                if not cell.on_pause():
                    raise Pause("PAUSE")

            return pause
        if kind == "set":
            _, put = self.storage(a[0], a[1], None)
            f, _ = self.expr(a[2])
            return lambda frame: put(frame, f(frame))
        if kind == "move":
            get, _ = self.storage(a[0], a[1], None)
            straight = a[2] == "MOVES"
            return lambda frame: cell.move(get(frame), straight)
        if kind == "break":
            return lambda frame: cell.break_()
        if kind == "here":
            _, put = self.storage(a[0], a[1], None)
            transform = a[0] == "t"
            return lambda frame: put(frame, cell.here(transform))
        if kind == "config":
            word = a[0]
            return lambda frame: cell.configure(word)
        if kind == "decompose":
            name, index, lkind, loc = a
            start = self.expr(index[0])[0]
            get_loc, _ = self.storage(lkind, loc, None)

            def getloc(frame):
                v = get_loc(frame)
                return v.values() if isinstance(v, Trans) else v

            at = [0]
            _, put = self.storage("n", name, [lambda frame: at[0]])

            def decompose(frame):
                first = round(start(frame))
                for k, v in enumerate(getloc(frame)):
                    at[0] = first + k
                    put(frame, v)

            return decompose
        if kind == "speed":
            f = self.expr(a[0])[0]
            return lambda frame: cell.speed(f(frame))
        if kind == "accel":
            fs = [self.expr(x)[0] for x in a]
            return lambda frame: cell.accel(*(g(frame) for g in fs))
        if kind == "type":
            fs = [self.expr(x)[0] for x in a[0]]
            return lambda frame: cell.type_("".join(_text(g(frame)) for g in fs))
        if kind == "prompt":
            text = self.expr(a[0])[0]
            target = a[1]
            _, put = self.storage(target[1], target[2], None)

            def prompt(frame):
                answer = cell.prompt(text(frame))
                put(frame, answer if target[1] == "s" else float(answer))

            return prompt
        if kind == "wait":
            f = self.expr(a[0])[0]
            return lambda frame: cell.wait(f(frame))
        if kind == "attach":
            _, put = self.storage("n", a[0], None)
            device = self.expr(a[2])[0]
            return lambda frame: put(frame, cell.attach(device(frame)))
        if kind == "detach":
            f = self.expr(a[0])[0]
            return lambda frame: cell.detach(int(f(frame)))
        if kind == "fopen":
            mode = a[0]
            lun = self.expr(a[1])[0]
            name = self.expr(a[2])[0]
            return lambda frame: cell.fopen(mode, int(lun(frame)), name(frame))
        if kind == "fclose":
            f = self.expr(a[0])[0]
            return lambda frame: cell.fclose(int(f(frame)))
        if kind == "write":
            lun = self.expr(a[0])[0]
            f = self.expr(a[1])[0]
            return lambda frame: cell.write(int(lun(frame)), f(frame))
        if kind == "enable":
            switch = a[0]
            return lambda frame: cell.enable(switch)
        if kind == "defbelt":
            name = a[0]
            enc, scale = self.expr(a[1])[0], self.expr(a[2])[0]
            return lambda frame: cell.defbelt(name, int(enc(frame)), scale(frame))
        raise AssertionError(kind)  # pragma: no cover

    def _block_stmt(self, s):
        kind = s[0]
        if kind == "if":
            cond = self.expr(s[2][1])[0]
            then, other = self.block(s[3]), self.block(s[4]) if s[4] else None

            def if_(frame):
                if cond(frame) != 0:
                    then(frame)
                elif other is not None:
                    other(frame)

            return if_
        if kind == "for":
            _, var, a, b, st = s[2]
            _, put = self.storage("n", var, None)
            get, _ = self.storage("n", var, None)
            fa, fb = self.expr(a)[0], self.expr(b)[0]
            fs = self.expr(st)[0] if st is not None else (lambda frame: 1.0)
            body = self.block(s[3])

            def for_(frame):
                step = fs(frame)
                end = fb(frame)
                put(frame, fa(frame))
                while (get(frame) <= end) if step > 0 else (get(frame) >= end):
                    body(frame)
                    put(frame, get(frame) + step)

            return for_
        if kind == "while":
            cond = self.expr(s[2][1])[0]
            body = self.block(s[3])

            def while_(frame):
                while cond(frame) != 0:
                    body(frame)

            return while_
        if kind == "case":
            sel = self.expr(s[2][1])[0]
            branches = [
                (
                    [self.expr(v)[0] for v in values] if values is not None else None,
                    self.block(body),
                )
                for values, body in s[3]
            ]

            def case(frame):
                x = sel(frame)
                for values, body in branches:
                    if values is None or any(x == v(frame) for v in values):
                        body(frame)
                        return

            return case
        raise AssertionError(kind)  # pragma: no cover


def _text(v) -> str:
    """TYPE's text of a value: strings as they are, numbers in a short general format."""
    if isinstance(v, str):
        return v
    if isinstance(v, float) and v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return f"{v:.7g}"
