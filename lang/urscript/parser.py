"""The URScript front end: a ``.script`` file's text → a checked, typed syntax tree.

Each statement (its ``#`` comment removed; lines joined while a bracket is open or after a
trailing operator) is parsed by the lark grammar ``urscript.lark`` into the dataclass
nodes of :mod:`wirecal.lang.urscript.nodes`; ``def``/``thread``/``sec``/``while``/``if``
blocks are assembled from the lines. The language is the Script Manual's: poses
``p[…]``, threads with ``run``/``join``/``kill`` and critical sections (SW5.20,
"Threads"), default and named arguments, ``break``/``continue`` (unconfirmed: used by
Universal Robots' client library, no page read). :func:`parse_program` rejects, as
``file:line: problem``:

* the layout of a script sent to the controller (Script Manual SW10.6, "Connecting to
  URControl", confirmed): the first line is ``def`` or ``sec`` in the first column, every
  other line is indented, the last line is ``end`` in the first column — one program per
  file;
* syntax errors, unclosed blocks, ``elif``/``else``/``end`` without their block,
  ``break``/``continue`` outside a ``while``, ``run`` of what is not a thread;
* calls to functions that are neither defined in the program nor in the function table
  (:data:`BUILTINS`, ``functions.csv``), wrong argument counts, unknown keyword arguments;
* constants the controller cannot hold: ints beyond 32 bits (and int results of constants
  that overflow), floats beyond float32 (UR16e User Manual p. 181); an encoder index
  other than 0 or 1 and ``opt`` other than "" or "raw" (SW5.20 encoder_get_tick_count); a
  constant index beyond a list whose every assignment is a literal;
* a function defined twice; a variable read but never assigned, nor a parameter;
* a character beyond extended ASCII (SW10.6, confirmed); a pose literal of other than 6
  numbers, a list of other than 6 given as a motion's joint positions (SW10.13 Module
  motion, confirmed); a list literal mixing types (unconfirmed).

It accepts the remote procedure call ``handle.method(…)`` and ``!`` for ``not`` (SW5.20,
"Remote Procedure Call (RPC)", confirmed), and a statement ur_rtde puts after another on
one joined text (:func:`_split_joined`).

The twin runs a subset of this language (:mod:`wirecal.twin.urscript.interp` refuses the
rest before running).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache, lru_cache
from importlib import resources

from lark import Lark, Transformer, ast_utils
from lark.exceptions import LarkError

from wirecal.lang.syntax import (
    NestingError,
    check_block_depth,
    check_line_depth,
    check_operator_run,
    kept_by_text,
    node_method,
    walk_tree,
)
from wirecal.lang.urscript import nodes as N
from wirecal.lang.urscript.versions import refusal, too_new, version_of
from wirecal.solver.errors import WirecalError


@dataclass(frozen=True)
class Builtin:
    """A URScript function: its parameters, how many are required, where it was read.

    ``source`` is the manual page its signature was read on (``functions.csv``), or
    "unconfirmed"; ``any_keywords`` marks ``struct(name=value, …)``.
    """

    params: tuple[str, ...]
    required: int
    source: str = "unconfirmed"
    any_keywords: bool = False


def _load_functions() -> dict[str, Builtin]:
    """Read ``functions.csv`` (name; parameters with defaults; source) into Builtins."""
    text = resources.files(__package__).joinpath("functions.csv").read_text(encoding="utf-8")
    rows = [r.split(";") for r in text.splitlines() if r.strip() and not r.startswith("#")]
    out: dict[str, Builtin] = {}
    for name, params, source in rows[1:]:
        names = [p.split("=")[0].strip() for p in _split_params(params)]
        required = sum("=" not in p for p in _split_params(params))
        if names == ["**fields"]:
            out[name] = Builtin((), 0, source, any_keywords=True)
        else:
            out[name] = Builtin(tuple(names), required, source)
    return out


def _split_params(params: str) -> list[str]:
    """Split a parameter list at the commas outside brackets."""
    parts, depth, cur = [], 0, ""
    for ch in params:
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    return [p.strip() for p in [*parts, cur] if p.strip()]


#: the URScript functions the checker knows (``functions.csv``)
BUILTINS: dict[str, Builtin] = _load_functions()

INT32 = (-(2**31), 2**31 - 1)
"""The int range: 32-bit whole numbers (UR16e User Manual p. 181; CB3 3.4.5 manual II-69)."""

FLOAT32_MAX = 3.4028234663852886e38
"""The largest 32-bit float (the controller's floats are 32-bit: UR16e User Manual p. 181)."""

ENCODER_INDICES = (0, 1)
"""encoder_index "Must be either 0 or 1" (SW5.20 encoder_get_tick_count page)."""

TICK_COUNT_OPTS = ("", "raw")
"""encoder_get_tick_count's opt: "" (filtered) or "raw" (SW5.20 encoder_get_tick_count page)."""

POSE_SIZE = 6
"""Joint positions, joint speeds and poses are 6 floats (:data:`MOTION_PAGE`)."""

MOTION_PAGE = "Script Manual SW10.13, Module motion"
"""Where "lists of 6 floats, one for each robot joint" and "poses … of 6 floats" are read:
https://www.universal-robots.com/manuals/EN/HTML/SW10_13/Content/prod-scriptmanual/all_scripts/Module_otion.htm"""

JOINT_VECTORS = {
    "movej": "q",
    "movel": "pose",
    "movep": "pose",
    "servoj": "q",
    "speedj": "qd",
    "optimovej": "q",
    "optimovel": "pose",
}
"""The motion functions' parameter that takes joint positions or speeds (or a pose)."""

EXTENDED_ASCII = 0xFF
"""The highest character a script may hold: "the text can only consist of extended ASCII
characters" (Script Manual SW10.6, Connecting to URControl)."""

_LINES = re.compile(r"\r\n|\n|\r")

_Block = N.Def | N.While | N.If
"""A statement that holds a body, opened by its first line and closed by ``end``."""


@dataclass
class Program:
    """A parsed URScript program: its name, its body and the functions defined in it."""

    source: str
    name: str
    body: list[N.Stmt]
    functions: dict[str, N.Def]


@cache
def _parser() -> Lark:
    grammar = resources.files(__package__).joinpath("urscript.lark").read_text(encoding="utf-8")
    return Lark(grammar, parser="lalr", maybe_placeholders=True)


class _Terminals(Transformer):
    """Terminals and the rules whose children need shaping (the rest by ``create_transformer``)."""

    def NAME(self, t):
        return str(t)

    def int_lit(self, c):
        return N.Num(int(c[0]), True)

    def float_lit(self, c):
        return N.Num(float(c[0]), False)

    def str_lit(self, c):
        return N.Str(str(c[0])[1:-1])

    def true_lit(self, c):
        return N.Bool(True)

    def false_lit(self, c):
        return N.Bool(False)

    def var(self, c):
        return N.Var(c[0])

    def list_expr(self, c):
        return N.ListLit([x for x in c if x is not None])

    def subscript(self, c):
        base, *items = c
        if len(items) == 1:
            return N.Index(base, items[0])
        if base == N.Var("p"):  # p[x, y, z, rx, ry, rz]: a pose literal
            return N.Pose(items)
        raise _LineError(
            "a list index is one expression (a pose literal is p[x, y, z, rx, ry, rz])"
        )

    def member(self, c):
        return str(c[0])

    def run_thread(self, c):
        return N.RunThread(c[0])

    def negate(self, c):
        return N.Neg(c[0])

    def not_op(self, c):
        return N.Not(c[0])

    def binop(self, c):
        return N.BinOp(str(c[1]), c[0], c[2])

    def comparison_op(self, c):
        return N.Compare(str(c[1]), c[0], c[2])

    def or_op(self, c):
        return N.Logic("or", c[0], c[1])

    def and_op(self, c):
        return N.Logic("and", c[0], c[1])

    def xor_op(self, c):
        return N.Logic("xor", c[0], c[1])

    def kwarg(self, c):
        return (c[0], c[1])

    def funcall(self, c):
        name, *items = c
        args = [a for a in items if a is not None and not isinstance(a, tuple)]
        kwargs = [a for a in items if isinstance(a, tuple)]
        call = N.Call(name, args, dict(kwargs))
        if len(call.kwargs) < len(kwargs):
            raise _LineError(f"{name}: a keyword argument given twice")
        return call

    def remote_call(self, c):
        base, method, *items = c
        call = self.funcall([method, *items])
        return N.RpcCall(base, method, call.args, call.kwargs)

    def call_line(self, c):
        return N.CallStmt(c[0])

    def assign_target(self, c):
        return N.Target(c[0], list(c[1:]))

    def assignment(self, c):
        scope, target, value = c
        return N.Assign(str(scope) if scope else "", target, value)

    def param(self, c):
        return (c[0], c[1])

    def def_line(self, c):
        params = [p for p in c[1:] if p is not None]
        defaults = {name: d for name, d in params if d is not None}
        names = [name for name, _ in params]
        first = next((k for k, (_, d) in enumerate(params) if d is not None), len(params))
        if any(d is None for _, d in params[first:]):
            raise _LineError(f"{c[0]}: a parameter without a default follows one with a default")
        return N.DefStart(c[0], names, defaults)

    def thread_line(self, c):
        return N.DefStart(c[0], [], kind="thread")

    def sec_line(self, c):
        return N.DefStart(c[0], [], kind="sec")

    def jump_line(self, c):
        return N.Jump(str(c[0]))

    def critical_line(self, c):
        return N.Critical(str(c[0]))

    def thread_op_line(self, c):
        return N.ThreadOp(str(c[0]), c[1])

    def return_line(self, c):
        return N.Return(c[0])

    def halt_line(self, c):
        return N.HaltStmt()


class _LineError(Exception):
    """A line that parses but is not URScript (e.g. a keyword argument given twice)."""


_build = ast_utils.create_transformer(N, _Terminals())


@kept_by_text
def parse_line(line: str) -> N.Stmt:
    """One line (no comment) → its node; lark's exception when it is not URScript."""
    check_operator_run(line)
    tree = _parser().parse(line)
    check_line_depth(tree)
    return _build.transform(tree)


def strip_comment(line: str) -> str:
    """Return ``line`` without its ``#`` comment (a ``#`` inside a string is kept)."""
    if "#" not in line:
        return line
    quote = ""
    for k, ch in enumerate(line):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:k]
    return line


def parse_program(text: str, source: str = "<script>", software: str | None = None) -> Program:
    """Parse and check one ``.script`` program; raise :class:`WirecalError` listing problems.

    With ``software`` ("5.20"), a call that version's manual pages do not document is a
    problem too (:mod:`wirecal.lang.urscript.versions`). The last programs parsed are kept
    (nothing changes a parsed program): a generated program is checked by the generator,
    then run in the twin, and each twin run parses its two programs again.
    """
    return _parse_program(text, source, software)


@lru_cache(maxsize=16)
def _parse_program(text: str, source: str, software: str | None) -> Program:
    """Parse and check one program (see :func:`parse_program`); one that fails is not kept."""
    problems: list[str] = []
    steps: list[N.Stmt] = []
    raw_lines = _LINES.split(text)
    problems += _not_extended_ascii(source, raw_lines)
    lines = [(n, strip_comment(raw).rstrip()) for n, raw in enumerate(raw_lines, 1)]
    joined = _statements([(n, s) for n, s in lines if s.strip()])
    if not joined:
        raise WirecalError([f"{source}: no program in the file (a script starts with def)"])
    for k, (n, raw, breaks) in enumerate(joined):
        _layout(source, n, raw, k == 0, k == len(joined) - 1, problems)
        for line, piece in _split_joined(raw.strip(), n, breaks):
            step = _step(source, line, piece, problems)
            if step is not None:
                step.line = line
                steps.append(step)
    program = _nest(steps, source, problems)
    if program is not None:
        _Checker(program, source, problems, software).check()
    if problems:
        raise WirecalError(problems)
    assert program is not None
    return program


def program_problems(text: str, source: str, software: str | None = None) -> list[str]:
    """Return :func:`parse_program`'s problems with ``text`` ('FILE:LINE: what'), none if clean."""
    try:
        parse_program(text, source, software)
    except WirecalError as exc:
        return list(exc.problems)
    return []


_CONTINUES = re.compile(r"(\b(and|or|xor|not)|[-+*/%,=<>(\[])\s*$")
"""A line ending in an operator, a comma or an opening bracket goes on on the next line."""


_Joined = tuple[int, str, list[tuple[int, int]]]
"""A statement's first line, its text and where each joined line starts in the stripped text."""


def _statements(lines: list[tuple[int, str]]) -> list[_Joined]:
    """Join the lines of one statement (open brackets, a trailing operator).

    The public scripts of Universal Robots' client library split long ``str_cat`` calls
    and ``or`` chains over lines this way.
    """
    out: list[_Joined] = []
    for n, line in lines:
        if out and _goes_on(out[-1][1]):
            first, text, breaks = out[-1]
            joined = text + " " + line.strip()
            breaks.append((len(joined.strip()) - len(line.strip()), n))
            out[-1] = (first, joined, breaks)
        else:
            out.append((n, line, []))
    return out


_STARTS = re.compile(
    r"(global|local|def|thread|sec|if|while|return|halt|end|elif|else)\b|[A-Za-z_]\w*\s*[=(\[.]"
)
"""What a statement after another on the same joined text starts with."""


def _split_joined(text: str, n: int, breaks: list[tuple[int, int]]) -> list[tuple[int, str]]:
    """Return the statements of a joined text as (line, text).

    The controller reads statements from the text, not from its lines: ur_rtde sends
    ``global reg_offset_float = # float register offset`` with the value it injects, e.g.
    ``24``, at the start of the next line, before that line's own statement (ur_rtde
    ``src/script_client.cpp``, ``scanAndInjectAdditionalScriptCode``; the controller runs
    it). A joined text that does not parse is split where a statement starts after a line
    break, if every piece then parses; otherwise it stays whole (and is reported).
    """
    if not breaks or _parses(text):
        return [(n, text)]
    pieces = _pieces(text, breaks[0][0])
    if pieces is None:
        return [(n, text)]
    return [(max([n] + [m for at, m in breaks if at <= start]), piece) for start, piece in pieces]


MAX_SPLIT_TRIES = 200
"""Parses :func:`_pieces` tries at most on one joined text (a bound for hostile input)."""


def _pieces(text: str, first_break: int) -> list[tuple[int, str]] | None:
    """Split ``text`` into statements that each parse: (offset in the text, statement).

    Left to right, each piece ends at the first statement start after a line break where
    what comes before parses; None when that fails or takes over :data:`MAX_SPLIT_TRIES`.
    """
    pieces: list[tuple[int, str]] = []
    start, tries = 0, 0
    while not _parses(text[start:]):
        for m in re.finditer(r"\s+", text[start:]):
            at = start + m.end()
            if at <= first_break or not _STARTS.match(text, at):
                continue
            tries += 1
            if tries > MAX_SPLIT_TRIES:
                return None
            if _parses(text[start : start + m.start()]):
                pieces.append((start, text[start : start + m.start()]))
                start = at
                break
        else:
            return None
    return [*pieces, (start, text[start:])]


def _parses(text: str) -> bool:
    try:
        parse_line(text)
    except (_LineError, NestingError, LarkError):
        return False
    return True


def _not_extended_ascii(source: str, lines: list[str]) -> list[str]:
    """Report a character beyond extended ASCII (:data:`EXTENDED_ASCII`), once per line."""
    out = []
    for n, line in enumerate(lines, 1):
        if line.isascii():
            continue
        bad = next((ch for ch in line if ord(ch) > EXTENDED_ASCII), None)
        if bad is not None:
            out.append(
                f"{source}:{n}: {bad!r} (U+{ord(bad):04X}) is not an extended ASCII character: "
                "a script's text can only be extended ASCII (Script Manual SW10.6, "
                "Connecting to URControl)"
            )
    return out


def _goes_on(text: str) -> bool:
    """Whether a statement's text goes on: brackets left open or a trailing operator."""
    return _open_brackets(text) > 0 or (
        bool(_CONTINUES.search(text)) and not text.rstrip().endswith(":")
    )


def _open_brackets(text: str) -> int:
    """Return how many ``(``/``[`` outside strings are not closed in ``text`` (<0: too many closed).

    Without a quote every bracket counts, so the count is ``str.count``'s (a generated
    program's statements are mostly without strings, and this is asked line by line).
    """
    if '"' not in text and "'" not in text:
        return text.count("(") + text.count("[") - text.count(")") - text.count("]")
    depth = 0
    quote = ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        else:
            depth += (ch in "([") - (ch in ")]")
    return depth


def _layout(source: str, n: int, raw: str, first: bool, last: bool, problems: list[str]) -> None:
    """Check the column rules of a script (Script Manual SW10.6, confirmed)."""
    column1 = not raw[:1].isspace()
    if first and not (column1 and re.match(r"(def|sec)\s", raw)):
        problems.append(f"{source}:{n}: a script starts with 'def' or 'sec' in the first column")
    elif last and not (column1 and raw.strip() == "end"):
        problems.append(f"{source}:{n}: a script ends with 'end' in the first column")
    elif not first and not last and column1:
        problems.append(f"{source}:{n}: every line but the first and the last is indented")


def _step(source: str, n: int, line: str, problems: list[str]) -> N.Stmt | None:
    try:
        return parse_line(line)
    except (_LineError, NestingError) as exc:
        problems.append(f"{source}:{n}: {exc}")
    except LarkError as exc:
        cause = exc.orig_exc if hasattr(exc, "orig_exc") else exc
        if isinstance(cause, _LineError):
            problems.append(f"{source}:{n}: {cause}")
        else:
            problems.append(f"{source}:{n}: bad syntax: {line}")
    return None


def _nest(steps: list[N.Stmt], source: str, problems: list[str]) -> Program | None:
    """Assemble the line statements into blocks; the one top-level def is the program."""
    root: list[N.Stmt] = []
    stack: list[tuple[_Block, list[N.Stmt]]] = []  # open block and the list it fills
    with_else: set[int] = set()  # ids of the If blocks whose else line has come
    target = root
    for s in steps:
        where = f"{source}:{s.line}"
        if isinstance(s, (N.DefStart, N.WhileStart, N.IfStart)):
            check_block_depth(len(stack), where)
            block = _open(s)
            target.append(block)
            stack.append((block, target))
            target = _first_body(block)
        elif isinstance(s, (N.ElifLine, N.ElseLine)):
            open_if = stack[-1][0] if stack else None
            if not isinstance(open_if, N.If) or id(open_if) in with_else:
                problems.append(f"{where}: '{_word(s)}' without an open 'if'")
                continue
            if isinstance(s, N.ElseLine):
                with_else.add(id(open_if))
                target = open_if.orelse
            else:
                target = []
                open_if.branches.append((s.cond, target))
        elif isinstance(s, N.EndLine):
            if not stack:
                problems.append(f"{where}: 'end' without an open block")
                continue
            _, target = stack.pop()
        else:
            target.append(s)
    for block, _ in stack:
        problems.append(f"{source}:{block.line}: '{_word(block)}' is not closed by 'end'")
    tops = [s for s in root if isinstance(s, N.Def)]
    if len(root) != 1 or len(tops) != 1:
        problems.append(f"{source}: one program per file: a single top-level def … end")
        return None
    main = tops[0]
    return Program(source, main.name, main.body, _functions(main, source, problems))


def _open(s: N.Stmt) -> _Block:
    if isinstance(s, N.DefStart):
        return N.Def(s.name, s.params, [], s.defaults, s.kind, line=s.line)
    if isinstance(s, N.WhileStart):
        return N.While(s.cond, [], line=s.line)
    assert isinstance(s, N.IfStart)
    return N.If([(s.cond, [])], [], line=s.line)


def _first_body(block: _Block) -> list[N.Stmt]:
    if isinstance(block, N.If):
        return block.branches[0][1]
    return block.body


def _word(s: N.Stmt) -> str:
    if isinstance(s, N.Def):
        return s.kind
    return {
        N.While: "while",
        N.ElifLine: "elif",
        N.ElseLine: "else",
    }.get(type(s), "if")


def _functions(main: N.Def, source: str, problems: list[str]) -> dict[str, N.Def]:
    """Every def of the program (the main one and those inside it), by name."""
    found: dict[str, N.Def] = {}
    for d in [main, *(s for s in walk(main.body) if isinstance(s, N.Def))]:
        if d.name in found:
            problems.append(f"{source}:{d.line}: function {d.name} is defined twice")
        elif d.name in BUILTINS:
            problems.append(
                f"{source}:{d.line}: {d.name} is a URScript function; choose another name"
            )
        found[d.name] = d
    return found


def children(s: N.Stmt) -> list[list[N.Stmt]]:
    """Return the statement lists directly inside a block statement."""
    if isinstance(s, (N.Def, N.While)):
        return [s.body]
    if isinstance(s, N.If):
        return [b for _, b in s.branches] + [s.orelse]
    return []


def walk(steps: list[N.Stmt]) -> Iterator[N.Stmt]:
    """Every statement of ``steps`` and of the blocks inside them, depth first."""
    return walk_tree(steps, children)


class _Checker:
    """Checks calls, literals and variables of one program (module docstring)."""

    def __init__(
        self, program: Program, source: str, problems: list[str], software: str | None = None
    ):
        self.p, self.source, self.problems = program, source, problems
        self.software = software
        self.version = None if software is None else version_of(software)
        assigns = [s for s in walk(program.body) if isinstance(s, N.Assign)]
        params = {name for d in program.functions.values() for name in d.params}
        self.assigned = {s.target.name for s in assigns} | params
        self.lengths = _literal_lengths(assigns, params)

    def check(self) -> None:
        for s in walk(self.p.body):
            self.stmt(s)
        self.jumps(self.p.body, in_loop=False)
        for d in self.p.functions.values():
            for value in d.defaults.values():
                self.expr(value, d.line)

    def err(self, line: int, message: str) -> None:
        self.problems.append(f"{self.source}:{line}: {message}")

    def jumps(self, steps: list[N.Stmt], in_loop: bool) -> None:
        """``break``/``continue`` only inside a ``while`` (of the same function or thread)."""
        for s in steps:
            if isinstance(s, N.Jump) and not in_loop:
                self.err(s.line, f"'{s.word}' outside a while loop")
            inner = isinstance(s, N.While) or (in_loop and not isinstance(s, N.Def))
            for body in children(s):
                self.jumps(body, inner)

    @node_method
    def stmt(self, s: N.Stmt) -> None:
        pass  # Def, HaltStmt, Jump, Critical: nothing to check on the line itself

    @stmt.register
    def _(self, s: N.Assign) -> None:
        for e in s.target.indices:
            self.expr(e, s.line)
        self.index(s.target.name, s.target.indices[:1], s.line)
        self.expr(s.value, s.line)

    @stmt.register
    def _(self, s: N.CallStmt) -> None:
        self.expr(s.call, s.line)

    @stmt.register
    def _(self, s: N.Return) -> None:
        if s.value is not None:
            self.expr(s.value, s.line)

    @stmt.register
    def _(self, s: N.While) -> None:
        self.expr(s.cond, s.line)

    @stmt.register
    def _(self, s: N.If) -> None:
        for cond, _ in s.branches:
            self.expr(cond, s.line)

    @stmt.register
    def _(self, s: N.ThreadOp) -> None:
        if s.handle not in self.assigned:
            self.err(s.line, f"{s.word} {s.handle}: no thread handle {s.handle} is assigned")

    def expr(self, e: N.Expr, line: int) -> None:
        """Check an expression and everything inside it."""
        if isinstance(e, N.Var) and e.name not in self.assigned:
            self.err(line, f"variable {e.name} is read but never assigned")
        elif isinstance(e, N.Call):
            self.call(e, line)
        elif isinstance(e, N.RunThread):
            self.run(e, line)
        elif isinstance(e, N.Index) and isinstance(e.base, N.Var):
            self.index(e.base.name, [e.index], line)
        self.literal(e, line)
        for sub in operands(e):
            if not (isinstance(e, N.Neg) and sub == N.Num(2**31, True)):  # -2147483648
                self.expr(sub, line)

    def literal(self, e: N.Expr, line: int) -> None:
        """Literals the controller cannot hold (module docstring)."""
        if isinstance(e, N.Pose) and len(e.items) != POSE_SIZE:
            self.err(
                line,
                f"a pose has {POSE_SIZE} numbers p[x, y, z, rx, ry, rz], not {len(e.items)} "
                f"({MOTION_PAGE})",
            )
        elif isinstance(e, N.ListLit) and len(kinds := _kinds(e.items)) > 1:
            self.err(
                line,
                f"a list mixes {' and '.join(kinds)}: a list holds one type (unconfirmed: "
                "no manual page read states it)",
            )
        elif isinstance(e, N.Num) and e.is_int and not INT32[0] <= e.value <= INT32[1]:
            self.err(line, f"{e.value} is outside the 32-bit int range [-2^31, 2^31-1]")
        elif isinstance(e, N.Num) and not e.is_int and abs(e.value) > FLOAT32_MAX:
            self.err(line, f"{e.value:g} is beyond the largest 32-bit float (3.4e38)")
        elif isinstance(e, N.BinOp):
            value = _constant(e)
            if isinstance(value, int) and not INT32[0] <= value <= INT32[1]:
                self.err(
                    line,
                    f"the int result {value} overflows 32 bits (not stated what the "
                    "controller does then: use a float or smaller numbers)",
                )

    def index(self, name: str, indices: list[N.Expr], line: int) -> None:
        """Check a constant index into a list whose length its literal assignments fix."""
        size = self.lengths.get(name)
        if size is None or not indices:
            return
        k = _constant(indices[0])
        if isinstance(k, int) and not 0 <= k < size:
            self.err(line, f"{name}[{k}]: index out of range ({name} has {size} elements)")

    def run(self, e: N.RunThread, line: int) -> None:
        d = self.p.functions.get(e.name)
        if d is None or d.kind != "thread":
            self.err(line, f"run {e.name}(): no thread {e.name} is defined in the program")

    def call(self, e: N.Call, line: int) -> None:
        user = self.p.functions.get(e.name)
        if user is not None:
            if user.kind != "def":
                self.err(line, f"{e.name} is a {user.kind}; start it with run {e.name}()")
                return
            b = Builtin(tuple(user.params), len(user.params) - len(user.defaults))
        else:
            found = BUILTINS.get(e.name)
            if found is None:
                self.err(
                    line,
                    f"unknown function {e.name} (not defined in the program, and not "
                    "a function of the URScript manual)",
                )
                return
            b = found
            self.arguments(e, line)
            self.vector(e, line)
            self.documented(e, line)
        if not b.any_keywords:
            self.signature(e, b, line)

    def signature(self, e: N.Call, b: Builtin, line: int) -> None:
        given = list(b.params[: len(e.args)]) + list(e.kwargs)
        if len(e.args) > len(b.params):
            self.err(
                line, f"{e.name} takes at most {len(b.params)} argument(s), given {len(e.args)}"
            )
        for k in e.kwargs:
            if k not in b.params:
                self.err(line, f"{e.name} has no parameter {k}")
            elif k in b.params[: len(e.args)]:
                self.err(line, f"{e.name}: {k} given by position and by name")
        missing = [p for p in b.params[: b.required] if p not in given]
        if missing:
            self.err(line, f"{e.name} needs {', '.join(missing)}")

    def vector(self, e: N.Call, line: int) -> None:
        """Check that a list given as a motion's joint positions or speeds has 6 elements."""
        param = JOINT_VECTORS.get(e.name)
        given = dict(zip(BUILTINS[e.name].params, e.args, strict=False)) | e.kwargs
        value = given.get(param) if param else None
        size = None
        if isinstance(value, N.ListLit):
            size = len(value.items)
        elif isinstance(value, N.Var):
            size = self.lengths.get(value.name)
        if size is not None and size != POSE_SIZE:
            self.err(
                line,
                f"{e.name}: {param} is {POSE_SIZE} joint values, one per joint, not {size} "
                f"({MOTION_PAGE})",
            )

    def documented(self, e: N.Call, line: int) -> None:
        """Report a call the declared software's manual pages do not document."""
        if self.version is None or self.software is None:
            return
        rule = too_new(e.name, set(e.kwargs), self.version)
        if rule is not None:
            self.err(line, refusal(rule, self.software))

    def arguments(self, e: N.Call, line: int) -> None:
        """Constant arguments outside a documented range (encoder index, opt)."""
        params = BUILTINS[e.name].params
        args = dict(zip(params, e.args, strict=False)) | e.kwargs
        index = _constant(args["encoder_index"]) if "encoder_index" in args else None
        if index is not None and index not in ENCODER_INDICES:
            self.err(line, f"{e.name}: encoder_index must be 0 or 1, not {index!r}")
        opt = args.get("opt") if e.name == "encoder_get_tick_count" else None
        if isinstance(opt, N.Str) and opt.text not in TICK_COUNT_OPTS:
            self.err(line, f'{e.name}: opt is "" or "raw", not "{opt.text}"')


def _kinds(items: list[N.Expr]) -> list[str]:
    """Return the types of the literal elements of a list (:func:`_kind`), sorted."""
    return sorted({k for k in map(_kind, items) if k is not None})


def _kind(e: N.Expr) -> str | None:
    """Return the type of a literal list element ("numbers", …); None if not a literal."""
    kinds = {N.Num: "numbers", N.Str: "strings", N.Bool: "booleans", N.Pose: "poses"}
    if isinstance(e, N.Neg):
        return _kind(e.expr)
    return "lists" if isinstance(e, N.ListLit) else kinds.get(type(e))


def _constant(e: N.Expr) -> int | float | None:
    """Return the value of an expression of number literals only (exact ints), else None."""
    if isinstance(e, N.Num):
        return e.value
    if isinstance(e, N.Neg):
        v = _constant(e.expr)
        return None if v is None else -v
    if isinstance(e, N.BinOp) and e.op in "+-*":
        a, b = _constant(e.left), _constant(e.right)
        if a is None or b is None:
            return None
        return {"+": a + b, "-": a - b, "*": a * b}[e.op]
    return None


def _literal_lengths(assigns: list[N.Assign], params: set[str]) -> dict[str, int]:
    """Variables (not parameters) whose every assignment is a list or pose literal of one length."""
    lengths: dict[str, set[int | None]] = {}
    for s in assigns:
        if not s.target.indices:
            v = s.value
            size = len(v.items) if isinstance(v, (N.ListLit, N.Pose)) else None
            lengths.setdefault(s.target.name, set()).add(size)
    sizes = {k: next(iter(v)) for k, v in lengths.items() if len(v) == 1 and k not in params}
    return {k: size for k, size in sizes.items() if size is not None}


def operands(e: N.Expr) -> list[N.Expr]:
    """Return the expressions directly inside ``e``."""
    if isinstance(e, (N.ListLit, N.Pose)):
        return list(e.items)
    if isinstance(e, N.Index):
        return [e.base, e.index]
    if isinstance(e, N.Field):
        return [e.base]
    if isinstance(e, N.Call):
        return [*e.args, *e.kwargs.values()]
    if isinstance(e, N.RpcCall):
        return [e.base, *e.args, *e.kwargs.values()]
    if isinstance(e, (N.Neg, N.Not)):
        return [e.expr]
    if isinstance(e, (N.BinOp, N.Compare, N.Logic)):
        return [e.left, e.right]
    return []
