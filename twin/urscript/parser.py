"""The URScript front end: a ``.script`` file's text → a checked, typed syntax tree.

Each line (its ``#`` comment removed) is parsed by the lark grammar ``urscript.lark``
into the dataclass nodes of :mod:`wirecal.twin.urscript.nodes`; ``def``/``while``/``if``
blocks are assembled from the lines. :func:`parse_program` rejects, as
``file:line: problem``:

* the layout of a script sent to the controller (Script Manual SW10.6, "Connecting to
  URControl", confirmed): the first line is ``def`` in the first column, every other line
  is indented, the last line is ``end`` in the first column — one program per file;
* syntax errors, unclosed blocks, ``elif``/``else``/``end`` without their block;
* calls to functions that are neither defined in the program nor URScript functions the
  twin knows (:data:`BUILTINS`), wrong argument counts and unknown keyword arguments;
* a function defined twice; a variable read but never assigned, nor a parameter.

What the checker cannot know about a real controller (a URScript function outside
:data:`BUILTINS`, ``thread``/``sec`` and the other constructs wirecal does not emit) is
reported as "not in the URScript subset the twin runs" — valid URScript, perhaps, but
nothing wirecal writes.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache, singledispatchmethod
from importlib import resources

from lark import Lark, Transformer, ast_utils
from lark.exceptions import LarkError

from wirecal.solver.errors import WirecalError
from wirecal.twin.machine import NestingError, check_block_depth, check_line_depth, walk_tree
from wirecal.twin.urscript import nodes as N


@dataclass(frozen=True)
class Builtin:
    """A URScript function the twin knows: its parameters and how many are required.

    Where each signature was read, and which are confirmed on a Universal Robots page, is
    :mod:`wirecal.gen.urscript.facts`' table.
    """

    params: tuple[str, ...]
    required: int


#: the URScript functions the twin runs
BUILTINS: dict[str, Builtin] = {
    "movej": Builtin(("q", "a", "v", "t", "r"), 1),
    "get_actual_joint_positions": Builtin((), 0),
    "encoder_enable_pulse_decode": Builtin(("encoder_index", "decoder_type", "A", "B"), 4),
    "encoder_get_tick_count": Builtin(("encoder_index", "opt"), 1),
    "encoder_unwind_delta_tick_count": Builtin(("encoder_index", "delta_tick_count"), 2),
    "socket_open": Builtin(("address", "port", "socket_name"), 2),
    "socket_send_line": Builtin(("str", "socket_name"), 1),
    "socket_close": Builtin(("socket_name",), 0),
    "textmsg": Builtin(("s1", "s2"), 1),
    "popup": Builtin(("s", "title", "warning", "error", "blocking"), 1),
    "sleep": Builtin(("t",), 1),
    "sync": Builtin((), 0),
    "time": Builtin(("mode",), 0),
    "str_cat": Builtin(("op1", "op2"), 2),
    "str_len": Builtin(("str",), 1),
    "floor": Builtin(("f",), 1),
    "round": Builtin(("f",), 1),
    "to_num": Builtin(("str",), 1),
    "norm": Builtin(("a",), 1),
    "sqrt": Builtin(("f",), 1),
    "fabs": Builtin(("f",), 1),
    "sin": Builtin(("f",), 1),
    "cos": Builtin(("f",), 1),
    "atan2": Builtin(("y", "x"), 2),
    "r2d": Builtin(("rad",), 1),
    "d2r": Builtin(("deg",), 1),
    "get_list_length": Builtin(("v",), 1),
}
#: URScript words for constructs wirecal never emits (the twin does not run them)
_UNMODELLED_WORDS = ("sec", "thread", "run", "join", "kill", "for", "break", "continue")

_LINES = re.compile(r"\r\n|\n|\r")


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
        return N.Index(c[0], c[1])

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

    def call_line(self, c):
        return N.CallStmt(c[0])

    def assign_target(self, c):
        return N.Target(c[0], list(c[1:]))

    def assignment(self, c):
        scope, target, value = c
        return N.Assign(str(scope) if scope else "", target, value)

    def def_line(self, c):
        return N.DefStart(c[0], [p for p in c[1:] if p is not None])

    def return_line(self, c):
        return N.Return(c[0])

    def halt_line(self, c):
        return N.HaltStmt()


class _LineError(Exception):
    """A line that parses but is not URScript (e.g. a keyword argument given twice)."""


_build = ast_utils.create_transformer(N, _Terminals())


def parse_line(line: str) -> N.Stmt:
    """One line (no comment) → its node; lark's exception when it is not URScript."""
    tree = _parser().parse(line)
    check_line_depth(tree)
    return _build.transform(tree)


def strip_comment(line: str) -> str:
    """Return ``line`` without its ``#`` comment (a ``#`` inside a string is kept)."""
    quote = ""
    for k, ch in enumerate(line):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            return line[:k]
    return line


def parse_program(text: str, source: str = "<script>") -> Program:
    """Parse and check one ``.script`` program; raise :class:`WirecalError` listing problems."""
    problems: list[str] = []
    steps: list[N.Stmt] = []
    lines = [(n, strip_comment(raw).rstrip()) for n, raw in enumerate(_LINES.split(text), 1)]
    lines = [(n, s) for n, s in lines if s.strip()]
    if not lines:
        raise WirecalError([f"{source}: no program in the file (a script starts with def)"])
    for k, (n, raw) in enumerate(lines):
        _layout(source, n, raw, k == 0, k == len(lines) - 1, problems)
        step = _step(source, n, raw.strip(), problems)
        if step is not None:
            step.line = n
            steps.append(step)
    program = _nest(steps, source, problems)
    if program is not None:
        _Checker(program, source, problems).check()
    if problems:
        raise WirecalError(problems)
    assert program is not None
    return program


def _layout(source: str, n: int, raw: str, first: bool, last: bool, problems: list[str]) -> None:
    """Check the column rules of a script (Script Manual SW10.6, confirmed)."""
    column1 = not raw[:1].isspace()
    if first and not (column1 and re.match(r"def\s", raw)):
        problems.append(f"{source}:{n}: a script starts with 'def' in the first column")
    elif last and not (column1 and raw.strip() == "end"):
        problems.append(f"{source}:{n}: a script ends with 'end' in the first column")
    elif not first and not last and column1:
        problems.append(f"{source}:{n}: every line but the first and the last is indented")


def _step(source: str, n: int, line: str, problems: list[str]) -> N.Stmt | None:
    word = re.match(r"[A-Za-z_]\w*", line)
    if word and word.group() in _UNMODELLED_WORDS:
        problems.append(
            f"{source}:{n}: '{word.group()}' is not in the URScript subset the twin runs"
        )
        return None
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


def _nest(steps: list[N.Stmt], source: str, problems: list[str]):
    """Assemble the line statements into blocks; the one top-level def is the program."""
    root: list[N.Stmt] = []
    stack: list[tuple[N.Stmt, list[N.Stmt]]] = []  # open block and the list it fills
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
            block = stack[-1][0] if stack else None
            if not isinstance(block, N.If) or id(block) in with_else:
                problems.append(f"{where}: '{_word(s)}' without an open 'if'")
                continue
            if isinstance(s, N.ElseLine):
                with_else.add(id(block))
                target = block.orelse
            else:
                target = []
                block.branches.append((s.cond, target))
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


def _open(s: N.Stmt) -> N.Stmt:
    if isinstance(s, N.DefStart):
        return N.Def(s.name, s.params, [], line=s.line)
    if isinstance(s, N.WhileStart):
        return N.While(s.cond, [], line=s.line)
    assert isinstance(s, N.IfStart)
    return N.If([(s.cond, [])], [], line=s.line)


def _first_body(block: N.Stmt) -> list[N.Stmt]:
    if isinstance(block, N.If):
        return block.branches[0][1]
    return block.body


def _word(s: N.Stmt) -> str:
    return {
        N.Def: "def",
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
    """Checks calls and variables of one program (module docstring)."""

    def __init__(self, program: Program, source: str, problems: list[str]):
        self.p, self.source, self.problems = program, source, problems
        self.assigned = {s.target.name for s in walk(program.body) if isinstance(s, N.Assign)} | {
            name for d in program.functions.values() for name in d.params
        }

    def check(self) -> None:
        for s in walk(self.p.body):
            self.stmt(s)

    def err(self, line: int, message: str) -> None:
        self.problems.append(f"{self.source}:{line}: {message}")

    @singledispatchmethod
    def stmt(self, s: N.Stmt) -> None:
        pass  # Def, HaltStmt: nothing to check on the line itself

    @stmt.register
    def _(self, s: N.Assign) -> None:
        for e in s.target.indices:
            self.expr(e, s.line)
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

    def expr(self, e: N.Expr, line: int) -> None:
        """Check an expression and everything inside it."""
        if isinstance(e, N.Var) and e.name not in self.assigned:
            self.err(line, f"variable {e.name} is read but never assigned")
        elif isinstance(e, N.Call):
            self.call(e, line)
        for sub in _operands(e):
            self.expr(sub, line)

    def call(self, e: N.Call, line: int) -> None:
        user = self.p.functions.get(e.name)
        if user is not None:
            if e.kwargs or len(e.args) != len(user.params):
                self.err(
                    line,
                    f"{e.name} takes {len(user.params)} argument(s), "
                    f"given {len(e.args) + len(e.kwargs)}",
                )
            return
        b = BUILTINS.get(e.name)
        if b is None:
            self.err(
                line,
                f"unknown function {e.name} (not defined in the program, and not a URScript "
                "function of the subset the twin runs)",
            )
            return
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


def _operands(e: N.Expr) -> list[N.Expr]:
    """Return the expressions directly inside ``e``."""
    if isinstance(e, N.ListLit):
        return list(e.items)
    if isinstance(e, N.Index):
        return [e.base, e.index]
    if isinstance(e, N.Field):
        return [e.base]
    if isinstance(e, N.Call):
        return [*e.args, *e.kwargs.values()]
    if isinstance(e, (N.Neg, N.Not)):
        return [e.expr]
    if isinstance(e, (N.BinOp, N.Compare, N.Logic)):
        return [e.left, e.right]
    return []
