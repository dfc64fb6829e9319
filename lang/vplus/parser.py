"""The V+ front end: a module's text → typed syntax trees.

The trees are checked as a controller's LOAD checks them.

The text (CRLF or LF) is split into ``.PROGRAM … .END`` blocks (data sections such as
``.LOCATIONS … .END`` are skipped); each step is parsed by the lark grammar
``vplus.lark`` and turned into the dataclass nodes of :mod:`wirecal.lang.vplus.nodes`;
IF/FOR/WHILE/DO/CASE blocks are assembled from the lines. :func:`parse_module` rejects,
as ``file:line: program: problem``: a V+ keyword (``keywords.csv``) used as a program,
variable or parameter name (User's Guide p. 99), a missing ``.END``, declarations after
executable steps, names that share their first 15 characters, unknown instructions or
functions, wrong argument counts of the functions the twin knows, CALLs to programs not
in the module (unless ``external_calls``), argument kinds that do not match a program's
parameters, GOTO to a missing label, type-prefix misuse ($ string, # precision point,
% belt), step labels beyond 65535 (p. 35), and constants beyond their ranges: strings over
128 characters (p. 100), integers beyond -16,777,216..16,777,215, ^B over 8 bits, ^D
beyond 2^53, reals beyond about 1E+307 (p. 102). Rules: User's Guide v17 p. 35–36
(program format), 99–111 (names, types, classes), 42–45 (CALL).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from functools import cache, lru_cache
from importlib import resources

from lark import Lark, Transformer, ast_utils
from lark.exceptions import LarkError, UnexpectedCharacters, UnexpectedToken

from wirecal.lang.syntax import (
    KEPT_LINES,
    NestingError,
    check_block_depth,
    check_line_depth,
    check_operator_run,
    kept_by_text,
    node_method,
    walk_tree,
)
from wirecal.lang.vplus import nodes as N
from wirecal.lang.vplus.forms import FormError, operands
from wirecal.lang.vplus.keywords import VALUE_KINDS, is_kind, keyword
from wirecal.solver.errors import WirecalError

SIGNIFICANT = 15
_HEADER = re.compile(r"^\.PROGRAM\s+([$#%]?[A-Za-z][A-Za-z0-9._]*)\s*(?:\((.*)\))?\s*$", re.I)
_LABEL = re.compile(r"^(\d+)(?:\s+|$)")
_PARAM = re.compile(r"^([$#%]?[A-Za-z][A-Za-z0-9._]*)\s*(\[[\s,]*\])?$")
_LINES = re.compile(r"\r\n|\n|\r")

# The functions the twin evaluates: name → (argument kinds, required count, result).
# Kinds: n number, s string, l precision point, b belt, t transformation, v any
# variable (DEFINED), nv a numeric variable (written to), w a system switch (SWITCH).
# TRANS: "if any parameter is omitted, its value is taken to be zero"; #PPOINT takes
# one value per joint (a SCARA has four). Any other function of the keyword table is
# accepted with any arguments and refused by the interpreter when run.
FUNCTIONS: dict[str, tuple[tuple[str, ...], int, str]] = {
    "int": (("n",), 1, "n"),
    "abs": (("n",), 1, "n"),
    "sqrt": (("n",), 1, "n"),
    "sin": (("n",), 1, "n"),
    "cos": (("n",), 1, "n"),
    "atan2": (("n", "n"), 2, "n"),
    "min": (("n", "n"), 2, "n"),
    "max": (("n", "n"), 2, "n"),
    "iostat": (("n",), 1, "n"),
    "$error": (("n",), 1, "s"),
    "$chr": (("n",), 1, "s"),
    "len": (("s",), 1, "n"),
    "defined": (("v",), 1, "n"),
    "belt": (("b", "n"), 2, "n"),
    "device": (("n", "n", "nv", "n"), 4, "n"),
    "#ppoint": (("n",) * 12, 1, "l"),
    "trans": (("n",) * 6, 0, "t"),
    "sig": (("n",), 1, "n"),
    "timer": (("n",), 1, "n"),
    "switch": (("w",), 1, "n"),
}
#: functions whose omitted arguments mean zero
OMITTABLE = {"trans"}
#: the value of the V+ constants (User's Guide p. 103, p. 128) and their kinds
CONSTANTS: dict[str, float] = {"true": -1.0, "on": -1.0, "false": 0.0, "off": 0.0}
_VALUE_WORD_KIND = {
    "true": "n",
    "on": "n",
    "false": "n",
    "off": "n",
    "pi": "n",
    "null": "t",
    "here": "t",
    "dest": "t",
}


@dataclass
class Param:
    """A program parameter: its name and whether it is an array."""

    name: str
    is_array: bool

    @property
    def kind(self) -> str:
        """Return the kind its prefix says: n, s ($), l (#) or b (%)."""
        return {"$": "s", "#": "l", "%": "b"}.get(self.name[:1], "n")


@dataclass
class Program:
    """A parsed program: header, nested statements and declarations."""

    name: str
    params: list[Param]
    body: list[N.Stmt]
    line: int
    declared: dict[str, N.Decl] = field(default_factory=dict)


@dataclass
class Module:
    """The parsed programs of a module file."""

    source: str
    programs: dict[str, Program]


@cache
def _parser() -> Lark:
    grammar = resources.files(__package__).joinpath("vplus.lark").read_text(encoding="utf-8")
    return Lark(grammar, parser="lalr", maybe_placeholders=True)


class _Terminals(Transformer):
    """Terminals and the rules whose children need shaping.

    The rules named after a node class are added by
    :func:`lark.ast_utils.create_transformer`.
    """

    def NAME(self, t):
        return str(t).lower()

    SNAME = LNAME = BNAME = NAME

    def INT(self, t):
        return int(t)

    def NUMBER(self, t):
        return N.Num(float(t), False)

    def DNUMBER(self, t):
        return N.Num(float(int(t[2:])), True)

    def RADIXNUMBER(self, t):
        base = {"h": 16, "b": 2}.get(t[1].lower())
        return N.Num(float(int(t[2:], base) if base else int(t[1:], 8)), False)

    def ASCII(self, t):
        return N.Num(float(ord(t[1])), False)

    def STRING(self, t):
        return N.Str(str(t)[1:-1])

    def FORMAT(self, t):
        return N.Format(str(t).upper())

    def anyname(self, children):
        return children[0]

    def target(self, children):
        return N.Var(*children)

    def index(self, children):
        return list(children)

    def compound_op(self, children):
        return N.Compound(children[0], children[2])

    def complement(self, children):
        return N.Com(children[1])

    def signed(self, children):
        op, e = children
        return N.Neg(e) if op == "-" else e

    def binop(self, children):
        a, op, b = children
        return N.BinOp(str(op).upper(), a, b)

    def logic_op(self, children):
        a, op, b = children
        return N.Logic(str(op).upper(), a, b)

    def compare_op(self, children):
        a, op, b = children
        return N.Compare({"=<": "<=", "=>": ">="}.get(str(op), str(op)), a, b)

    def funcall(self, children):
        name, *args = children
        return N.Func(name, [] if args == [None] else args)

    def operand_group(self, children):
        return N.Group(list(children))

    def declaration(self, children):
        scope, dtype, *items = children
        return N.Decl(str(scope).upper(), str(dtype).upper() if dtype else "", items)

    def dims(self, children):
        return [c for c in children if c is not None]

    def call_step(self, children):
        name, *args = children
        return N.Call(name, [] if args in ([None], [None, None]) else args)

    def value_step(self, children):
        return N.ValueLine(list(children))

    def any_step(self, children):
        return N.AnyLine()

    def instr(self, children):
        name, ops = children
        return N.Instruction(name, ops or [])

    def operands(self, children):
        return list(children)

    def operands_lead(self, children):
        return [None, *children]

    def formats(self, children):
        return [f.spec for f in children]

    def clause_formats(self, children):
        return N.Clause(children[0], [], None)

    def operand_clause(self, children):
        formats = children[0] if isinstance(children[0], list) else []
        items = children[1 if formats else 0 : -1]
        return N.Clause(formats, items, children[-1])


_build = ast_utils.create_transformer(N, _Terminals())


@kept_by_text
def parse_step(line: str) -> N.Stmt:
    """One step (no label, no comment) → its node; lark's exception when it is not V+."""
    tree = _parser().parse(line)
    check_line_depth(tree)
    return _build.transform(tree)


def parse_module(text: str, source: str = "<module>", *, external_calls: bool = False) -> Module:
    """Parse and check a module; raise :class:`WirecalError` listing every problem.

    ``external_calls``: CALLs to programs that are not in this module are allowed (they
    may be loaded from another file), as LOAD allows them. The last modules parsed are
    kept (nothing changes a parsed module): the demo and the benches run one module in
    several cells, the generator checks a module the twin then runs; 16 of them, so that
    modules checked in between do not push out a generated one (its lines are kept apart,
    :func:`~wirecal.lang.syntax.kept_by_text`, so a module kept holds little of its own).
    """
    return _parse_module(text, source, external_calls)


@lru_cache(maxsize=16)
def _parse_module(text: str, source: str, external_calls: bool) -> Module:
    """Parse and check a module (see :func:`parse_module`)."""
    problems, programs = read_programs(text, source)
    _check_module(programs, source, problems, external_calls)
    if not programs and not problems:
        problems.append(f"{source}: no .PROGRAM in the file")
    if problems:
        raise WirecalError(problems)
    return Module(source, programs)


def read_programs(text: str, source: str) -> tuple[list[str], dict[str, Program]]:
    """Read a module file's programs, unchecked: the problems found reading it and them."""
    reader = _ModuleReader(source)
    for n, raw in enumerate(_LINES.split(text), 1):
        reader.line(n, _strip_comment(raw).strip())
    return reader.close()


class _ModuleReader:
    """The line-by-line state of :func:`parse_module`: the program or data section being read."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.problems: list[str] = []
        self.programs: dict[str, Program] = {}
        self.current: tuple[str, int, list[Param], list[N.Stmt]] | None = None
        self.section: str | None = None  # inside a data section (.LOCATIONS, .REALS, ...)

    def line(self, n: int, line: str) -> None:
        """Read line ``n`` (comment stripped)."""
        if not line:
            return
        word = line.split()[0].upper()
        if self.section is not None:
            if word == ".END":
                self.section = None
        elif word == ".PROGRAM":
            self.start(n, line)
        elif word == ".END":
            self.end(n)
        elif self.current:
            self.step(n, line)
        elif word.startswith("."):
            self.section = word  # a data section: its values are not program steps
        else:
            self.problems.append(f"{self.source}:{n}: code outside a program: {line}")

    def start(self, n: int, line: str) -> None:
        """Read a .PROGRAM line."""
        m = _HEADER.match(line)
        if not m:
            self.problems.append(f"{self.source}:{n}: malformed .PROGRAM line")
            return
        if self.current:
            self.problems.append(
                f"{self.source}:{n}: {self.current[0]}: missing .END before the next .PROGRAM"
            )
            _finish(self.current, self.programs, self.source, self.problems)
        name = m.group(1).lower()
        params = _params(m.group(2) or "", self.source, n, name, self.problems)
        self.current = (name, n, params, [])

    def end(self, n: int) -> None:
        """Read the .END of a program."""
        if not self.current:
            self.problems.append(f"{self.source}:{n}: .END without .PROGRAM")
            return
        _finish(self.current, self.programs, self.source, self.problems)
        self.current = None

    def step(self, n: int, line: str) -> None:
        """Read a program step, with its label if it has one."""
        assert self.current is not None
        name, steps = self.current[0], self.current[3]
        m = _LABEL.match(line)
        if m:
            line = line[m.end() :].strip()
            steps.append(N.Label(int(m.group(1)), line=n))
            if int(m.group(1)) > MAX_LABEL:
                self.problems.append(
                    f"{self.source}:{n}: {name}: label {m.group(1)}: a step label is an "
                    f"integer 0 to {MAX_LABEL} (User's Guide p. 35)"
                )
            if not line:
                return
        try:
            check_operator_run(line)  # before the constants' check too, linear as it is
        except NestingError as exc:
            self.problems.append(f"{self.source}:{n}: {name}: {exc}")
            return
        self.problems += [f"{self.source}:{n}: {name}: {p}" for p in literal_problems(line)]
        try:
            step = parse_step(line)
        except (UnexpectedToken, UnexpectedCharacters) as exc:
            self.problems.append(f"{self.source}:{n}: {name}: {_explain(line, exc)}")
            return
        except NestingError as exc:
            self.problems.append(f"{self.source}:{n}: {name}: {exc}")
            return
        except LarkError as exc:  # pragma: no cover - grammar-level failure
            self.problems.append(f"{self.source}:{n}: {name}: cannot parse: {exc}")
            return
        step.line = n
        steps.append(step)

    def close(self) -> tuple[list[str], dict[str, Program]]:
        """Finish the file: return the problems and the programs read."""
        if self.current:
            self.problems.append(
                f"{self.source}: {self.current[0]}: missing .END "
                f"(program starts on line {self.current[1]})"
            )
            _finish(self.current, self.programs, self.source, self.problems)
        if self.section is not None:
            self.problems.append(
                f"{self.source}: data section {self.section} is never closed with .END"
            )
        return self.problems, self.programs


MAX_LABEL = 65535
"""A step label is "an integer (0 to 65535)" (User's Guide p. 35)."""
MAX_INTEGER = 16_777_215
"""Integers range from -16,777,216 to 16,777,215 (User's Guide p. 102)."""
MAX_DOUBLE = 1e307
"""Double-precision reals: approximately -1E+307 to 1E+307 (User's Guide p. 102)."""
MAX_EXACT_DOUBLE = 2**53
"""The largest whole number a 64-bit IEEE double (User's Guide p. 102) holds exactly."""
MAX_STRING = 128
"""A string holds 0 to 128 characters (User's Guide p. 100)."""

_LITERAL = re.compile(
    r'(?P<str>"[^"]*"?)|(?P<d>\^[Dd]\d+)|(?P<h>\^[Hh][0-9A-Fa-f]+)|(?P<b>\^[Bb][01]+)'
    r"|(?P<o>\^[0-7]+)|'.|[A-Za-z$#%][\w.]*"
    r"|(?P<num>(?P<whole>\d+)(?P<frac>\.\d*)?(?P<exp>[eE][-+]?\d+)?|\.\d+(?:[eE][-+]?\d+)?)"
)


@lru_cache(maxsize=KEPT_LINES)
def literal_problems(line: str) -> tuple[str, ...]:
    """Constants of a step outside the ranges of User's Guide pp. 100 and 102.

    Kept by the line's text, as its parse is (:func:`~wirecal.lang.syntax.kept_by_text`).
    """
    out = []
    for m in _LITERAL.finditer(line):
        before = m.start() - 1
        while before >= 0 and line[before].isspace():
            before -= 1
        out += _literal_problem(m, before >= 0 and line[before] == "-")
    return tuple(out)


def _literal_problem(m: re.Match, minus: bool) -> list[str]:
    """Check one token of :data:`_LITERAL` (``minus``: a ``-`` stands before it)."""
    text = m.group()
    if m.group("str") is not None:
        inner = text[1:-1] if len(text) > 1 and text.endswith('"') else text[1:]
        if len(inner) > MAX_STRING:
            return [
                f"a string constant of {len(inner)} characters (at most {MAX_STRING}, "
                "User's Guide p. 100)"
            ]
        return []
    if m.group("d"):
        if int(text[2:]) > MAX_EXACT_DOUBLE:
            return [
                f"{text}: beyond 2^53, which a 64-bit double holds exactly (User's Guide p. 102)"
            ]
        return []
    if m.group("b") and len(text) - 2 > 8:
        return [f"{text}: a ^B constant has at most 8 bits (User's Guide p. 102)"]
    value = _radix_value(m)
    if value is not None:
        return _integer_problem(text, value, minus)
    if m.group("num") is None:
        return []
    if m.group("whole") and not m.group("frac") and not m.group("exp"):
        return _integer_problem(text, int(text), minus)
    if float(text) > MAX_DOUBLE:
        return [f"{text}: beyond the double-precision range, about 1E+307 (User's Guide p. 102)"]
    return []


def _radix_value(m: re.Match) -> int | None:
    """Return the value of a ^H, ^B or ^ (octal) constant, or None for another token."""
    for group, base, skip in (("h", 16, 2), ("b", 2, 2), ("o", 8, 1)):
        if m.group(group):
            return int(m.group()[skip:], base)
    return None


def _integer_problem(text: str, value: int, minus: bool) -> list[str]:
    """Check a whole-number constant against the integer range (a ``-`` before it: -2^24)."""
    limit = MAX_INTEGER + 1 if minus else MAX_INTEGER
    if value <= limit:
        return []
    return [
        f"{text}: beyond the integer range -16,777,216 to 16,777,215 (User's Guide "
        f"p. 102); write it as a real ({value}.0) or a ^D constant"
    ]


def _strip_comment(line: str) -> str:
    if ";" not in line:
        return line
    out, quoted = [], False
    for ch in line:
        if ch == '"':
            quoted = not quoted
        if ch == ";" and not quoted:
            break
        out.append(ch)
    return "".join(out)


def _params(text: str, source: str, n: int, prog: str, problems: list[str]) -> list[Param]:
    params = []
    for p in [x.strip() for x in text.split(",")] if text.strip() else []:
        m = _PARAM.match(p)
        if not m:
            problems.append(f"{source}:{n}: {prog}: bad parameter {p!r}")
            continue
        params.append(Param(m.group(1).lower(), bool(m.group(2))))
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


_OPENERS = (N.IfStart, N.ForStart, N.WhileStart, N.DoStart, N.CaseStart)


def _blocks(prog: str, steps: list[N.Stmt], source: str, problems: list[str]):
    """Nest the line statements into blocks; check declarations come first."""
    nester = _Nester(prog, source, problems)
    for step in steps:
        nester.add(step)
    nester.unclosed()
    return nester.root, nester.declared


class _Nester:
    """The state of :func:`_blocks`: the open blocks and the statement list being filled."""

    def __init__(self, prog: str, source: str, problems: list[str]) -> None:
        self.prog, self.source, self.problems = prog, source, problems
        self.declared: dict[str, N.Decl] = {}
        self.root: list[N.Stmt] = []
        # (block node, the list it was appended to)
        self.stack: list[tuple[N.Stmt, list[N.Stmt]]] = []
        self.target: list[N.Stmt] | None = self.root  # the list now filled
        self.executable = False

    def add(self, step: N.Stmt) -> None:
        """Put one line statement in its place."""
        where = f"{self.source}:{step.line}: {self.prog}"
        if isinstance(step, N.Decl):
            self.declare(step, where)
            return
        if not isinstance(step, N.Label):
            self.executable = True
        if isinstance(step, _OPENERS):
            self.open(step, where)
        elif isinstance(step, N.ElseLine):
            self.orelse(where)
        elif isinstance(step, (N.ValueLine, N.AnyLine)):
            self.branch(step, where)
        elif isinstance(step, (N.EndLine, N.UntilLine)):
            self.close(step, where)
        elif self.target is None:
            self.problems.append(f"{where}: a step between CASE and its first VALUE")
        else:
            self.target.append(step)

    def declare(self, step: N.Decl, where: str) -> None:
        """Record a declaration; it must come before the executable steps."""
        if self.executable:
            self.problems.append(f"{where}: declaration after executable steps")
        for item in step.items:
            self.declared[item.name] = step

    def open(self, step: N.Stmt, where: str) -> None:
        """Open a block (IF, FOR, WHILE, DO, CASE)."""
        check_block_depth(len(self.stack), where)
        node = _open(step)
        if self.target is None:
            self.problems.append(f"{where}: a step between CASE and its first VALUE")
        else:
            self.target.append(node)
        self.stack.append((node, self.target if self.target is not None else []))
        self.target = _first_list(node)

    def orelse(self, where: str) -> None:
        """Continue an IF block with its ELSE list."""
        if not self.stack or not isinstance(self.stack[-1][0], N.If):
            self.problems.append(f"{where}: ELSE without IF")
            return
        self.target = self.stack[-1][0].orelse

    def branch(self, step: N.ValueLine | N.AnyLine, where: str) -> None:
        """Start a VALUE or ANY branch of a CASE block."""
        word = "VALUE" if isinstance(step, N.ValueLine) else "ANY"
        if not self.stack or not isinstance(self.stack[-1][0], N.Case):
            self.problems.append(f"{where}: {word} outside CASE")
            return
        branch = N.Branch(step.values if isinstance(step, N.ValueLine) else None, [])
        self.stack[-1][0].branches.append(branch)
        self.target = branch.body

    def close(self, step: N.EndLine | N.UntilLine, where: str) -> None:
        """Close the innermost block with END, or a DO block with UNTIL."""
        until = isinstance(step, N.UntilLine)
        top = self.stack[-1][0] if self.stack else None
        if until and not isinstance(top, N.DoUntil):
            self.problems.append(f"{where}: UNTIL without DO")
            return
        if not until and (top is None or isinstance(top, N.DoUntil)):
            self.problems.append(
                f"{where}: END inside a DO block (DO closes with UNTIL)"
                if top is not None
                else f"{where}: END without IF, FOR, WHILE or CASE"
            )
            return
        node, self.target = self.stack.pop()
        if isinstance(node, N.DoUntil) and isinstance(step, N.UntilLine):
            node.cond = step.cond

    def unclosed(self) -> None:
        """Report the blocks still open at the end of the program."""
        opener = {N.If: "IF", N.For: "FOR", N.While: "WHILE", N.DoUntil: "DO", N.Case: "CASE"}
        for node, _ in self.stack:
            closer = "UNTIL" if isinstance(node, N.DoUntil) else "END"
            self.problems.append(
                f"{self.source}:{node.line}: {self.prog}: "
                f"{opener[type(node)]} is never closed with {closer}"
            )


def _open(step: N.Stmt) -> N.Stmt:
    line = step.line
    if isinstance(step, N.IfStart):
        return N.If(step.cond, [], [], line=line)
    if isinstance(step, N.ForStart):
        return N.For(step.var, step.start, step.stop, step.step, [], line=line)
    if isinstance(step, N.WhileStart):
        return N.While(step.cond, [], line=line)
    if isinstance(step, N.DoStart):
        return N.DoUntil([], None, line=line)
    assert isinstance(step, N.CaseStart)
    return N.Case(step.selector, [], line=line)


def _first_list(node: N.Stmt) -> list[N.Stmt] | None:
    if isinstance(node, N.If):
        return node.then
    if isinstance(node, N.Case):
        return None  # steps go in its VALUE branches
    return node.body  # type: ignore[attr-defined]


def children(stmt: N.Stmt) -> list[list[N.Stmt]]:
    """Return the statement lists nested in a block statement."""
    if isinstance(stmt, N.If):
        return [stmt.then, stmt.orelse]
    if isinstance(stmt, (N.For, N.While, N.DoUntil)):
        return [stmt.body]
    if isinstance(stmt, N.Case):
        return [b.body for b in stmt.branches]
    return []


def walk(steps: list[N.Stmt]) -> Iterator[N.Stmt]:
    """Every statement of ``steps`` and of the blocks inside them, depth first."""
    return walk_tree(steps, children)


def transformation_names(programs: dict[str, Program]) -> set[str]:
    """Names without a prefix that hold transformations (targets of SET or HERE)."""
    names: set[str] = set()
    for prog in programs.values():
        for s in walk(prog.body):
            if isinstance(s, N.Instruction) and s.name in ("set", "here") and s.clauses:
                first = s.clauses[0]
                if first is not None and first.items and isinstance(first.items[0], N.Var):
                    if first.items[0].kind == "n":
                        names.add(first.items[0].name)
    return names


def check_programs(
    programs: dict[str, Program],
    source: str,
    problems: list[str],
    external_calls: bool,
    visible: dict[str, Program],
) -> None:
    """Check a file's ``programs`` with ``visible`` (theirs and other files') as callable."""
    _check_module(programs, source, problems, external_calls, visible)


def _check_module(programs, source, problems, external_calls, visible=None) -> None:
    visible = programs if visible is None else visible
    names: dict[str, str] = {}

    def register(name: str, where: str) -> None:
        bare = name.lstrip("$#%")
        key = bare[:SIGNIFICANT]
        other = names.setdefault(key, bare)
        if other != bare:
            problems.append(
                f"{where}: {bare!r} and {other!r} share their first {SIGNIFICANT} characters"
            )

    transforms = transformation_names(visible)
    for prog in programs.values():
        checker = _Checker(prog, visible, source, problems, register, transforms)
        checker.define(prog.line, prog.name, "program")
        for p in prog.params:
            checker.define(prog.line, p.name, "parameter")
        for name, decl in prog.declared.items():
            checker.define(decl.line, name, "variable")
        checker.external_calls = external_calls
        checker.block(prog.body)


class _Checker:
    """Walks one program: names, functions, argument counts, GOTOs and kinds."""

    def __init__(self, prog, programs, source, problems, register, transforms):
        self.prog, self.programs, self.source = prog, programs, source
        self.problems, self.register = problems, register
        self.transforms = transforms
        self.labels = {s.number for s in walk(prog.body) if isinstance(s, N.Label)}
        self.external_calls = False
        self.line = prog.line
        self.named: set[str] = set()  # keywords already reported as names

    def err(self, message: str, line: int | None = None) -> None:
        self.problems.append(f"{self.source}:{line or self.line}: {self.prog.name}: {message}")

    def define(self, line: int, name: str, what: str) -> None:
        """Check a name the program defines (program, parameter, variable, target)."""
        self.line = line
        self.no_keyword(name)
        self.register(name, f"{self.source}:{line}: {self.prog.name}")

    def block(self, steps: list[N.Stmt]) -> None:
        for s in steps:
            self.line = s.line
            self.stmt(s)

    # ---------- statements ----------
    @node_method
    def stmt(self, s: N.Stmt) -> None:  # pragma: no cover - every node type is registered
        raise AssertionError(type(s).__name__)

    @stmt.register
    def _(self, s: N.Label) -> None:
        pass

    @stmt.register
    def _(self, s: N.Assign) -> None:
        self.target(s.target)
        kind = self.var_kind(s.target)
        if kind in ("l", "t"):
            self.err(
                f"type-prefix misuse: a location is assigned with SET (p. 111): {s.target.name}"
            )
        self.need(s.value, kind)

    @stmt.register
    def _(self, s: N.Call) -> None:
        prog = self.programs.get(s.program)
        if prog is None:
            if not self.external_calls:
                self.err(f"CALL {s.program}: no such program in the module")
            for a in s.args:
                if a is not None:
                    self.argument(a)
            return
        if len(s.args) > len(prog.params):
            self.err(
                f"CALL {s.program}: {len(s.args)} arguments; {s.program} takes {len(prog.params)}"
            )
        for a, p in zip(s.args, prog.params, strict=False):
            if a is not None:  # omitted: undefined in the callee (p. 42–45)
                self.call_argument(s, a, p)

    def call_argument(self, s: N.Call, a: N.Expr, p: Param) -> None:
        """Check a CALL argument against the parameter it is passed to."""
        got = self.argument(a)
        if isinstance(a, N.ArrayArg):
            if not p.is_array or a.kind != p.kind:
                self.err(f"CALL {s.program}: argument {a.name}[] does not match the parameter")
        elif p.is_array:
            self.err(f"CALL {s.program}: {p.name} is an array; pass {p.name}[]")
        elif got not in ("?", p.kind) and not (got == "t" and p.kind == "n"):
            self.err(f"CALL {s.program}: a {_word(got)} where {s.program} takes a {_word(p.kind)}")

    def argument(self, a: N.Expr) -> str:
        if isinstance(a, N.ArrayArg):
            self.register(a.name, f"{self.source}:{self.line}: {self.prog.name}")
            self.no_keyword(a.name)
            return a.kind
        return self.kind(a)

    @stmt.register
    def _(self, s: N.Goto) -> None:
        self.goto(s.label)

    @stmt.register
    def _(self, s: N.IfGoto) -> None:
        self.need(s.cond, "n")
        self.goto(s.label)

    def goto(self, label: int) -> None:
        if label not in self.labels:
            self.err(f"GOTO {label}: no such label in {self.prog.name}")

    @stmt.register
    def _(self, s: N.If) -> None:
        self.need(s.cond, "n")
        self.block(s.then)
        self.block(s.orelse)

    @stmt.register
    def _(self, s: N.For) -> None:
        self.target(s.var)
        for e in (s.start, s.stop, s.step):
            if e is not None:
                self.need(e, "n")
        self.block(s.body)

    @stmt.register
    def _(self, s: N.While) -> None:
        self.need(s.cond, "n")
        self.block(s.body)

    @stmt.register
    def _(self, s: N.DoUntil) -> None:
        self.block(s.body)
        if s.cond is not None:
            self.line = s.line
            self.need(s.cond, "n")

    @stmt.register
    def _(self, s: N.Case) -> None:
        self.need(s.selector, "n")
        for b in s.branches:
            for v in b.values or []:
                self.need(v, "n")
            self.block(b.body)

    @stmt.register
    def _(self, s: N.Instruction) -> None:
        if not is_kind(s.name, "instruction"):
            self.err(f"unknown instruction {s.name.upper()} (not in the V+ keyword table)")
        try:
            ops = operands(s)
        except FormError:
            ops = None
        if ops is None:  # a form the twin does not execute: check names and functions
            self.unexecuted(s)
            return
        target_kind = "?"
        for code, e in ops:
            if e is None:
                continue
            if code in ("L", "V", "B"):
                target_kind = self.written_operand(s, code, e, target_kind)
            else:
                self.read_operand(s, code, e, target_kind)

    def unexecuted(self, s: N.Instruction) -> None:
        """Check the names and functions of an instruction the twin does not execute."""
        for c in s.clauses:
            if c is None:
                continue
            for e in c.items:
                self.operand(e)
            if c.value is not None:
                self.kind(c.value)

    def written_operand(self, s: N.Instruction, code: str, e: N.Expr, target_kind: str) -> str:
        """Check an operand the instruction writes (code L, V or B); return its kind."""
        if not isinstance(e, N.Var):
            self.err(f"{s.name.upper()} needs a variable there")
            return target_kind
        self.target(e)
        target_kind = self.var_kind(e)
        want = {"L": ("l", "t"), "B": ("b",), "V": (target_kind,)}[code]
        if target_kind not in want:
            self.err(
                f"type-prefix misuse: {s.name.upper()} needs a "
                f"{'location' if code == 'L' else 'belt (%)'} variable"
            )
        return target_kind

    def read_operand(self, s: N.Instruction, code: str, e: N.Expr, target_kind: str) -> None:
        """Check an operand the instruction reads (code W, e, l, * or a kind)."""
        if code == "W":
            if not isinstance(e, N.Var) or e.index is not None:
                self.err(f"{s.name.upper()} needs a word there")
        elif code == "e":
            self.need(e, target_kind)
        elif code == "l":
            got = self.kind(e)
            if got not in ("?", "l", "t"):
                self.err(f"type-prefix misuse: {s.name.upper()} needs a location")
        elif code == "*":
            got = self.kind(e)
            if got not in ("?", "n", "s"):
                self.err(f"{s.name.upper()} cannot print a {_word(got)}")
        else:
            self.need(e, code)

    def operand(self, e: N.Expr) -> None:
        """Check an operand of an instruction in a form the twin does not execute.

        A bare keyword is a word of the instruction (ALWAYS, POWER, ROBOT); a function
        call whose name is no function names a program (EXECUTE 1 a.main()).
        """
        if isinstance(e, N.Var) and e.index is None and keyword(e.name) is not None:
            return
        if isinstance(e, N.Func) and not is_kind(e.name, "function") and e.name not in FUNCTIONS:
            if e.name not in self.programs and not self.external_calls:
                self.err(f"{e.name}: no such program in the module, and no V+ function")
            for a in e.args:
                if a is not None:
                    self.argument(a)
            return
        if isinstance(e, N.Group):
            for x in e.items:
                if x is not None:
                    self.kind(x)
            return
        self.kind(e)

    # ---------- names ----------
    def no_keyword(self, name: str) -> None:
        """Report a V+ keyword used as a name (User's Guide p. 99), once per program."""
        k = keyword(name)
        if k is not None and name not in self.named:
            self.named.add(name)
            self.err(f"{name!r} is a V+ keyword ({k.describe()}) and cannot be a name")

    def target(self, v: N.Var) -> None:
        """Check a variable written to: no keyword; its indices are numbers."""
        self.no_keyword(v.name)
        self.register(v.name, f"{self.source}:{self.line}: {self.prog.name}")
        for e in v.index or []:
            self.need(e, "n")

    def var_kind(self, v: N.Var) -> str:
        if v.kind == "n" and v.name in self.transforms:
            return "t"
        return v.kind

    # ---------- expressions ----------
    def need(self, e: N.Expr, want: str) -> None:
        got = self.kind(e)
        if "?" not in (got, want) and got != want:
            self.err(f"type-prefix misuse: a {_word(got)} where a {_word(want)} is needed")

    @node_method
    def kind(self, e: N.Expr) -> str:
        """Return the kind of an expression: n, s, l, b, t, or ?.

        ``?`` means not known, or a problem already reported.
        """
        self.err(f"{type(e).__name__.lower()} is not a value here")
        return "?"

    @kind.register
    def _(self, e: N.Num) -> str:
        return "n"

    @kind.register
    def _(self, e: N.Str) -> str:
        return "s"

    @kind.register
    def _(self, e: N.Paren) -> str:
        return self.kind(e.expr)

    @kind.register
    def _(self, e: N.Format) -> str:
        return "?"

    @kind.register
    def _(self, e: N.Var) -> str:
        k = keyword(e.name)
        if k is not None and e.index is None:
            if not any(kind in k.kinds for kind in VALUE_KINDS):
                self.no_keyword(e.name)
                return "?"
            return _VALUE_WORD_KIND.get(e.name, "?")
        self.target(e)
        return self.var_kind(e)

    @kind.register
    def _(self, e: N.Compound) -> str:
        for side in (e.left, e.right):
            # a name without prefix may hold a transformation defined elsewhere (p. 310)
            if self.kind(side) not in ("?", "t", "b", "n"):
                self.err("type-prefix misuse: ':' joins transformations")
        return "t"

    @kind.register
    def _(self, e: N.ArrayArg) -> str:
        self.argument(e)
        return e.kind

    @kind.register
    def _(self, e: N.Shift) -> str:
        self.need(e.base, "t")
        for a in (e.dx, e.dy, e.dz):
            self.need(a, "n")
        return "t"

    @kind.register
    def _(self, e: N.Func) -> str:
        spec = FUNCTIONS.get(e.name)
        if spec is None:
            return self.unknown_function(e)
        kinds, required, result = spec
        given = len(e.args)
        if not required <= given <= len(kinds):
            count = f"{required}" if required == len(kinds) else f"{required} to {len(kinds)}"
            self.err(
                f"{e.name.upper()} takes {count} argument{'s' if len(kinds) != 1 else ''}, "
                f"not {given}"
            )
            return result
        for k, (a, want) in enumerate(zip(e.args, kinds, strict=False), 1):
            self.function_argument(e, k, a, want)
        return result

    def unknown_function(self, e: N.Func) -> str:
        """Check a function the twin does not know; return the kind its name prefix says."""
        if not is_kind(e.name, "function"):
            self.err(f"unknown function {e.name.upper()}")
        for a in e.args:
            if a is not None:
                self.kind(a)
        return {"$": "s", "#": "l"}.get(e.name[:1], "?")

    def function_argument(self, e: N.Func, k: int, a: N.Expr | None, want: str) -> None:
        """Check argument ``k`` of a known function against the kind it wants."""
        if a is None:
            if e.name not in OMITTABLE:
                self.err(f"{e.name.upper()}: argument {k} is missing")
        elif want == "v":
            if not isinstance(a, N.Var):
                self.err(f"{e.name.upper()} needs a variable")
            else:
                self.target(a)
        elif want == "w":
            if not (isinstance(a, N.Var) and is_kind(a.name, "switch")):
                self.err(f"{e.name.upper()} needs a system switch name (e.g. BELT)")
        elif want == "nv":
            if not isinstance(a, N.Var) or a.kind != "n":
                self.err(f"{e.name.upper()} needs a numeric variable there")
            else:
                self.target(a)
        else:
            self.need(a, want)

    @kind.register
    def _(self, e: N.Neg) -> str:
        self.need(e.expr, "n")
        return "n"

    @kind.register
    def _(self, e: N.Not | N.Com) -> str:
        self.need(e.expr, "n")
        return "n"

    @kind.register
    def _(self, e: N.Logic) -> str:
        self.need(e.left, "n")
        self.need(e.right, "n")
        return "n"

    @kind.register
    def _(self, e: N.BinOp) -> str:
        a, b = self.kind(e.left), self.kind(e.right)
        if e.op == "+" and "s" in (a, b) and {a, b} <= {"s", "?"}:
            return "s"
        for k in (a, b):
            if k not in ("?", "n"):
                self.err(f"type-prefix misuse: '{e.op}' on a {_word(k)}")
                return "?"
        return "n"

    @kind.register
    def _(self, e: N.Compare) -> str:
        a, b = self.kind(e.left), self.kind(e.right)
        if "?" not in (a, b) and (a != b or a not in ("n", "s")):
            self.err(f"type-prefix misuse: comparing a {_word(a)} with a {_word(b)}")
        return "n"


def _word(kind: str) -> str:
    return {
        "n": "number",
        "s": "string ($)",
        "l": "location (#)",
        "b": "belt (%)",
        "t": "transformation",
        "v": "variable",
        "w": "system switch",
    }.get(kind, kind)
