"""A parser of the V+ subset wirecal emits, with the checks a controller makes on load.

The module text is split into ``.PROGRAM … .END`` blocks; each step (line) is parsed by
the lark grammar ``vplus.lark`` into compact tuples, and IF/FOR/WHILE/CASE blocks are
assembled from them. :func:`parse_module` rejects, with ``file:line: program: problem``:
a missing ``.END``, declarations after executable steps, names that share their first
15 characters, unknown keywords or functions, wrong argument counts, CALLs to programs
not in the module, GOTO to a missing label, and type-prefix misuse ($ string, # location,
% belt). Rules: V+ Language User's Guide v17 p. 35–36 (program format), 99–111 (names,
types, classes).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from functools import cache
from importlib import resources

from lark import Lark, Token, Transformer, v_args
from lark.exceptions import LarkError, UnexpectedCharacters, UnexpectedToken

from wirecal.solver.errors import WirecalError

SIGNIFICANT = 15
_HEADER = re.compile(r"^\.PROGRAM\s+([A-Za-z][A-Za-z0-9._]*)\s*\((.*)\)\s*(;.*)?$", re.I)
_LABEL = re.compile(r"^(\d+)(?:\s+|$)")
_PARAM = re.compile(r"^([$#%]?)([A-Za-z][A-Za-z0-9._]*)(\[\])?$")

# name → (argument kinds, result kind); kinds: n number, s string, l location,
# b belt, v a variable of any kind (DEFINED), nv a numeric variable (written to).
FUNCTIONS: dict[str, tuple[tuple[str, ...], str]] = {
    "int": (("n",), "n"),
    "abs": (("n",), "n"),
    "sqrt": (("n",), "n"),
    "sin": (("n",), "n"),
    "cos": (("n",), "n"),
    "atan2": (("n", "n"), "n"),
    "min": (("n", "n"), "n"),
    "max": (("n", "n"), "n"),
    "iostat": (("n",), "n"),
    "$error": (("n",), "s"),
    "$chr": (("n",), "s"),
    "len": (("s",), "n"),
    "defined": (("v",), "n"),
    "belt": (("b", "n"), "n"),
    "device": (("n", "n", "nv", "n"), "n"),
    "#ppoint": (("n",) * 6, "l"),
    "trans": (("n",) * 6, "t"),
    "sig": (("n",), "n"),
}


@dataclass
class Program:
    name: str
    params: list[tuple[str, str, bool]]  # (kind, name, is_array)
    body: list
    line: int
    declared: dict[str, tuple[str, str]] = field(default_factory=dict)  # name→(class,type)


@dataclass
class Module:
    source: str
    programs: dict[str, Program]


@cache
def _parser() -> Lark:
    grammar = resources.files(__package__).joinpath("vplus.lark").read_text(encoding="utf-8")
    return Lark(grammar, parser="lalr", maybe_placeholders=True)


def _kind(token: str) -> str:
    return {"$": "s", "#": "l", "%": "b"}.get(token[:1], "n")


def _loc(token) -> tuple[str, str]:
    """A location operand: a precision point (#name, kind l) or a transformation (t)."""
    name = str(token).lower()
    return ("l" if name.startswith("#") else "t"), name


@v_args(inline=True)
class _Build(Transformer):
    """Parse tree of one step → tuples (see the interpreter for their meaning)."""

    def number(self, t):
        return ("num", float(t), False)

    def dnumber(self, t):
        return ("num", float(int(str(t)[2:])), True)

    def string(self, t):
        return ("str", str(t)[1:-1])

    def true(self):
        return ("num", -1.0, False)

    def false(self):
        return ("num", 0.0, False)

    def paren(self, e):
        # kept: "(x)" passes x by value in a CALL (User's Guide p. 42–45)
        return ("paren", e)

    def anyname(self, t):
        return str(t)

    def index(self, *exprs):
        return list(exprs)

    def varref(self, name, index=None):
        return ("var", _kind(name), name.lower(), index)

    def funcall(self, name, *args):
        return ("fn", name.lower(), [a for a in args if a is not None])

    def neg(self, e):
        return ("neg", e)

    def not_(self, e):
        return ("not", e)

    def binop(self, a, op, b):
        return ("bin", str(op).upper(), a, b)

    def compare(self, a, op, b):
        return ("cmp", str(op), a, b)

    def and_(self, a, b):
        return ("and", a, b)

    def or_(self, a, b):
        return ("or", a, b)

    def num_target(self, name, index=None):
        return ("var", "n", str(name).lower(), index)

    def str_target(self, name, index=None):
        return ("var", "s", str(name).lower(), index)

    def arg_array(self, name):
        return ("array", _kind(str(name)), str(name).lower())

    def arg(self, e):
        return e

    def dims(self, *ints):
        return [int(i) for i in ints]

    def declitem(self, name, dims=None):
        return (name.lower(), dims)

    def decl(self, cls, *rest):
        dtype = "REAL"
        if rest and isinstance(rest[0], Token) and rest[0].type == "DECLTYPE":
            dtype, rest = str(rest[0]).upper(), rest[1:]
        return ("decl", str(cls).upper(), dtype, list(rest))

    def assign(self, target, expr):
        return ("assign", target, expr)

    def call(self, name, *args):
        return ("call", str(name).lower(), [a for a in args if a is not None])

    def if_start(self, c):
        return ("if", c)

    def else_(self):
        return ("else",)

    def end_(self):
        return ("end",)

    def for_start(self, var, a, b, step=None):
        return ("for", str(var).lower(), a, b, step)

    def while_start(self, c):
        return ("while", c)

    def case_start(self, e):
        return ("case", e)

    def value_(self, *vals):
        return ("value", list(vals))

    def any_(self):
        return ("any",)

    def goto(self, label):
        return ("goto", int(label))

    def return_(self):
        return ("return",)

    def halt(self):
        return ("halt",)

    def pause(self):
        return ("pause",)

    def set_loc(self, name, e):
        return ("set", *_loc(name), e)

    def move(self, kind, name):
        return ("move", *_loc(name), str(kind).upper())

    def break_(self):
        return ("break",)

    def here(self, name):
        return ("here", *_loc(name))

    def decompose(self, name, index, loc):
        return ("decompose", str(name).lower(), index, *_loc(loc))

    def config(self, word):
        return ("config", str(word).upper())

    def shift(self, loc, dx, dy, dz):
        return ("fn", "shift", [loc, dx, dy, dz])

    def speed(self, e):
        return ("speed", e)

    def accel(self, prof, a, d):
        return ("accel", prof, a, d)

    def type_(self, *items):
        return ("type", list(items))

    def prompt(self, e, target):
        return ("prompt", e, ("var", _kind(target), target.lower(), None))

    def wait_event(self, e):
        return ("wait", e)

    def attach(self, lun, mode, device):
        return ("attach", str(lun).lower(), mode, device)

    def detach(self, lun):
        return ("detach", lun)

    def fopen(self, kind, lun, name):
        return ("fopen", str(kind).upper(), lun, name)

    def fclose(self, lun):
        return ("fclose", lun)

    def write_(self, lun, e):
        return ("write", lun, e)

    def tool_null(self):
        return ("tool_null",)

    def enable(self, name):
        return ("enable", str(name).upper())

    def defbelt(self, name, enc, scale):
        return ("defbelt", str(name).lower(), enc, scale)


_BLOCK_OPEN = {"if", "for", "while", "case"}
_DECL = "decl"


def parse_module(text: str, source: str = "<module>") -> Module:
    """Parse and check a module; raise :class:`WirecalError` listing every problem."""
    problems: list[str] = []
    programs: dict[str, Program] = {}
    lines = text.split("\n")
    current: tuple[str, int, list, list] | None = None  # name, line, params, steps
    for n, raw in enumerate(lines, 1):
        line = _strip_comment(raw).strip()
        if not line:
            continue
        if line.upper().startswith(".PROGRAM"):
            m = _HEADER.match(raw.strip())
            if not m:
                problems.append(f"{source}:{n}: malformed .PROGRAM line")
                continue
            if current:
                problems.append(
                    f"{source}:{n}: {current[0]}: missing .END before the next .PROGRAM"
                )
                _finish(current, programs, source, problems)
            params = _params(m.group(2), source, n, m.group(1).lower(), problems)
            current = (m.group(1).lower(), n, params, [])
            continue
        if line.upper() == ".END":
            if not current:
                problems.append(f"{source}:{n}: .END without .PROGRAM")
                continue
            _finish(current, programs, source, problems)
            current = None
            continue
        if not current:
            problems.append(f"{source}:{n}: code outside a program: {line}")
            continue
        label = None
        m = _LABEL.match(line)
        if m:
            label, line = int(m.group(1)), line[m.end() :].strip()
            current[3].append((n, ("label", label)))
            if not line:
                continue
        try:
            step = _Build().transform(_parser().parse(line))
        except (UnexpectedToken, UnexpectedCharacters) as exc:
            problems.append(f"{source}:{n}: {current[0]}: {_explain(line, exc)}")
            continue
        except LarkError as exc:  # pragma: no cover - grammar-level failure
            problems.append(f"{source}:{n}: {current[0]}: cannot parse: {exc}")
            continue
        current[3].append((n, step))
    if current:
        problems.append(
            f"{source}: {current[0]}: missing .END (program starts on line {current[1]})"
        )
        _finish(current, programs, source, problems)
    _check_module(programs, source, problems)
    if problems:
        raise WirecalError(problems)
    return Module(source, programs)


def _strip_comment(line: str) -> str:
    out, quoted = [], False
    for ch in line:
        if ch == '"':
            quoted = not quoted
        if ch == ";" and not quoted:
            break
        out.append(ch)
    return "".join(out)


def _params(text: str, source: str, n: int, prog: str, problems: list[str]):
    params = []
    for p in [x.strip() for x in text.split(",") if x.strip()]:
        m = _PARAM.match(p)
        if not m:
            problems.append(f"{source}:{n}: {prog}: bad parameter {p!r}")
            continue
        params.append(
            (_kind(m.group(1) or "n"), (m.group(1) + m.group(2)).lower(), bool(m.group(3)))
        )
    return params


def _explain(line: str, exc) -> str:
    word = line.split()[0].split("(")[0] if line.split() else line
    if isinstance(exc, UnexpectedToken) and exc.token.type == "$END":
        return f"incomplete step: {line}"
    if re.fullmatch(r"[A-Za-z][A-Za-z0-9._]*", word) and not re.match(
        r"^[A-Za-z][A-Za-z0-9._]*(\[.*\])?\s*=", line
    ):
        return f"unknown keyword or bad syntax: {word.upper()} ({line})"
    return f"bad syntax: {line}"


def _finish(current, programs, source, problems):
    name, start, params, steps = current
    if name in programs:
        problems.append(f"{source}:{start}: program {name} is defined twice")
    body, declared = _blocks(name, steps, source, problems)
    programs[name] = Program(name, params, body, start, declared)


def _blocks(prog: str, steps, source: str, problems: list[str]):
    """Nest the line statements into blocks; check declarations come first."""
    declared: dict[str, tuple[str, str]] = {}
    root: list = []
    stack: list[tuple[tuple, list, int]] = []  # (opening step, its list, line)
    target = root
    executable = False
    for n, step in steps:
        kind = step[0]
        where = f"{source}:{n}: {prog}"
        if kind == _DECL:
            if executable:
                problems.append(f"{where}: declaration after executable steps")
            for name, _dims in step[3]:
                declared[name] = (step[1], step[2])
            continue
        if kind != "label":
            executable = True
        if kind == "label" and stack:
            problems.append(
                f"{where}: label {step[1]} inside a block; put labels at the program's top level"
            )
            continue
        if kind in _BLOCK_OPEN:
            node = [kind, n, step, [], []] if kind != "case" else [kind, n, step, []]
            target.append(node)
            stack.append((node, target, n))
            target = node[3] if kind != "case" else None
            continue
        if kind == "else":
            if not stack or stack[-1][0][0] != "if":
                problems.append(f"{where}: ELSE without IF")
                continue
            target = stack[-1][0][4]
            continue
        if kind in ("value", "any"):
            if not stack or stack[-1][0][0] != "case":
                problems.append(f"{where}: {kind.upper()} outside CASE")
                continue
            branch = (None if kind == "any" else step[1], [])
            stack[-1][0][3].append(branch)
            target = branch[1]
            continue
        if kind == "end":
            if not stack:
                problems.append(f"{where}: END without IF, FOR, WHILE or CASE")
                continue
            node, target, _ = stack.pop()
            continue
        if target is None:
            problems.append(f"{where}: a step between CASE and its first VALUE")
            continue
        target.append((kind, n, *step[1:]))
    for node, _, n in stack:
        problems.append(f"{source}:{n}: {prog}: {node[0].upper()} is never closed with END")
    return root, declared


def _check_module(programs: dict[str, Program], source: str, problems: list[str]) -> None:
    names: dict[str, str] = {}

    def register(name: str, where: str) -> None:
        bare = name.lstrip("$#%")
        key = bare[:SIGNIFICANT]
        other = names.setdefault(key, bare)
        if other != bare:
            problems.append(
                f"{where}: {bare!r} and {other!r} share their first {SIGNIFICANT} characters"
            )

    transforms = transformation_names(programs)
    for prog in programs.values():
        register(prog.name, f"{source}:{prog.line}: {prog.name}")
        labels = {s[2] for s in prog.body if s[0] == "label"}
        _Checker(prog, programs, source, problems, register, labels, transforms).block(prog.body)


def transformation_names(programs: dict[str, Program]) -> set[str]:
    """Names without a prefix that hold transformations (targets of SET or HERE)."""
    names: set[str] = set()

    def walk(steps):
        for s in steps:
            if not isinstance(s, list):
                if s[0] in ("set", "here") and s[2] == "t":
                    names.add(s[3])
            elif s[0] == "case":
                for _values, body in s[3]:
                    walk(body)
            else:
                walk(s[3])
                if len(s) > 4:
                    walk(s[4])

    for prog in programs.values():
        walk(prog.body)
    return names


class _Checker:
    """Walks one program: names, functions, argument counts, GOTOs and kinds."""

    def __init__(self, prog, programs, source, problems, register, labels, transforms):
        self.prog, self.programs, self.source = prog, programs, source
        self.problems, self.register, self.labels = problems, register, labels
        self.transforms = transforms

    def err(self, line, message):
        self.problems.append(f"{self.source}:{line}: {self.prog.name}: {message}")

    def block(self, steps):
        for s in steps:
            self.step(s)

    def step(self, s):
        kind, line = s[0], s[1]
        if isinstance(s, list):  # a block node
            if kind == "if":
                self.need(line, s[2][1], "n")
                self.block(s[3])
                self.block(s[4])
            elif kind == "for":
                _, var, a, b, st = s[2]
                self.register(var, f"{self.source}:{line}: {self.prog.name}")
                for e in (a, b, st):
                    if e is not None:
                        self.need(line, e, "n")
                self.block(s[3])
            elif kind == "while":
                self.need(line, s[2][1], "n")
                self.block(s[3])
            elif kind == "case":
                self.need(line, s[2][1], "n")
                for values, body in s[3]:
                    for v in values or []:
                        self.need(line, v, "n")
                    self.block(body)
            return
        args = s[2:]
        if kind == "assign":
            target, expr = args
            self.var(line, target)
            self.need(line, expr, target[1])
        elif kind == "call":
            name, actual = args
            prog = self.programs.get(name)
            if prog is None:
                self.err(line, f"CALL {name}: no such program in the module")
                return
            if len(actual) > len(prog.params):
                self.err(
                    line, f"CALL {name}: {len(actual)} arguments; {name} takes {len(prog.params)}"
                )
            for a, (pkind, _pname, is_array) in zip(actual, prog.params, strict=False):
                if a[0] == "array":
                    if not is_array or a[1] != pkind:
                        self.err(
                            line, f"CALL {name}: argument {a[2]}[] does not match the parameter"
                        )
                    self.register(a[2], f"{self.source}:{line}: {self.prog.name}")
                else:
                    got = self.kind(line, a)
                    if got is not None and got != pkind:
                        self.err(
                            line, f"CALL {name}: a {_word(got)} where {name} takes a {_word(pkind)}"
                        )
        elif kind == "goto":
            if args[0] not in self.labels:
                self.err(line, f"GOTO {args[0]}: no such label in {self.prog.name}")
        elif kind in ("set",):
            self.register(args[1], f"{self.source}:{line}: {self.prog.name}")
            self.need(line, args[2], args[0])
        elif kind in ("move", "here"):
            self.register(args[1], f"{self.source}:{line}: {self.prog.name}")
        elif kind == "decompose":
            self.register(args[0], f"{self.source}:{line}: {self.prog.name}")
            for e in args[1]:
                self.need(line, e, "n")
        elif kind in ("speed", "wait", "detach", "fclose"):
            self.need(line, args[0], "n")
        elif kind == "accel":
            for e in args:
                self.need(line, e, "n")
        elif kind == "type":
            for e in args[0]:
                got = self.kind(line, e)
                if got not in (None, "n", "s"):
                    self.err(line, f"TYPE cannot print a {_word(got)}")
        elif kind == "prompt":
            self.need(line, args[0], "s")
            self.var(line, args[1])
        elif kind == "attach":
            self.register(args[0], f"{self.source}:{line}: {self.prog.name}")
            self.need(line, args[1], "n")
            self.need(line, args[2], "s")
        elif kind == "fopen":
            self.need(line, args[1], "n")
            self.need(line, args[2], "s")
        elif kind == "write":
            self.need(line, args[0], "n")
            self.need(line, args[1], "s")
        elif kind == "defbelt":
            self.register(args[0], f"{self.source}:{line}: {self.prog.name}")
            self.need(line, args[1], "n")
            self.need(line, args[2], "n")

    def var(self, line, v):
        self.register(v[2], f"{self.source}:{line}: {self.prog.name}")
        for e in v[3] or []:
            self.need(line, e, "n")

    def need(self, line, expr, want):
        got = self.kind(line, expr)
        if got is not None and got != want:
            self.err(line, f"type-prefix misuse: a {_word(got)} where a {_word(want)} is needed")

    def kind(self, line, e):
        """The kind of an expression (n, s, l, b), or None after reporting a problem."""
        tag = e[0]
        if tag == "paren":
            return self.kind(line, e[1])
        if tag == "num":
            return "n"
        if tag == "str":
            return "s"
        if tag == "var":
            self.var(line, e)
            return "t" if e[1] == "n" and e[2] in self.transforms else e[1]
        if tag == "fn":
            name, args = e[1], e[2]
            if name == "shift":
                self.need(line, args[0], "t")
                for a in args[1:]:
                    self.need(line, a, "n")
                return "t"
            spec = FUNCTIONS.get(name)
            if spec is None:
                self.err(line, f"unknown function {name.upper()}")
                return None
            kinds, result = spec
            if len(args) != len(kinds):
                self.err(
                    line,
                    f"{name.upper()} takes {len(kinds)} argument"
                    f"{'s' if len(kinds) != 1 else ''}, not {len(args)}",
                )
                return result
            for a, k in zip(args, kinds, strict=True):
                if k == "v":
                    if a[0] != "var":
                        self.err(line, f"{name.upper()} needs a variable")
                    else:
                        self.var(line, a)
                elif k == "nv":
                    if a[0] != "var" or a[1] != "n":
                        self.err(line, f"{name.upper()} needs a numeric variable there")
                    else:
                        self.var(line, a)
                else:
                    self.need(line, a, k)
            return result
        if tag in ("neg", "not"):
            self.need(line, e[1], "n")
            return "n"
        if tag == "bin":
            a, b = self.kind(line, e[2]), self.kind(line, e[3])
            if e[1] == "+" and a == "s" and b == "s":
                return "s"
            for k in (a, b):
                if k not in (None, "n"):
                    self.err(line, f"type-prefix misuse: '{e[1]}' on a {_word(k)}")
                    return None
            return "n"
        if tag == "cmp":
            a, b = self.kind(line, e[2]), self.kind(line, e[3])
            if None not in (a, b) and (a != b or a not in ("n", "s")):
                self.err(line, f"type-prefix misuse: comparing a {_word(a)} with a {_word(b)}")
            return "n"
        if tag in ("and", "or"):
            self.need(line, e[1], "n")
            self.need(line, e[2], "n")
            return "n"
        raise AssertionError(tag)  # pragma: no cover


def _word(kind: str) -> str:
    return {
        "n": "number",
        "s": "string ($)",
        "l": "location (#)",
        "b": "belt (%)",
        "t": "transformation",
        "v": "variable",
    }.get(kind, kind)
