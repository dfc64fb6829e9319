"""The typed syntax tree of URScript programs: one dataclass per construct.

Built by the lark transformer of :mod:`wirecal.lang.urscript.parser` (classes deriving
from ``lark.ast_utils.Ast`` are matched to the grammar rule of the same name, as for V+);
the checker and the interpreter dispatch on the node type. URScript names are
case-sensitive and kept as written. Statements carry their line number in the source.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from lark import ast_utils


class _Node(ast_utils.Ast):
    """Base of every node (the leading underscore keeps it out of the transformer)."""


# ---------- expressions ----------
class Expr(_Node):
    """Base of expression nodes."""


@dataclass(slots=True)
class Num(Expr):
    """A number literal: an int (``12``) or a float (``1.5``, ``2e-3``)."""

    value: float | int
    is_int: bool


@dataclass(slots=True)
class Bool(Expr):
    """True or False."""

    value: bool


@dataclass(slots=True)
class Str(Expr):
    """A string literal."""

    text: str


@dataclass(slots=True)
class Var(Expr):
    """A variable read."""

    name: str


@dataclass(slots=True)
class ListLit(Expr):
    """A list literal ``[a, b, …]``."""

    items: list[Expr]


@dataclass(slots=True)
class Pose(Expr):
    """A pose literal ``p[x, y, z, rx, ry, rz]`` (m and rad, axis-angle)."""

    items: list[Expr]


@dataclass(slots=True)
class RunThread(Expr):
    """``run name()``: starts a thread and gives its handle."""

    name: str


@dataclass(slots=True)
class Index(Expr):
    """``base[index]``: an element of a list (0-based)."""

    base: Expr
    index: Expr


@dataclass(slots=True)
class Field(Expr):
    """``base.name``: a member of a struct (e.g. ``time(0).sec``)."""

    base: Expr
    name: str


@dataclass(slots=True)
class Call(Expr):
    """A function call with positional and keyword arguments."""

    name: str
    args: list[Expr]
    kwargs: dict[str, Expr]


@dataclass(slots=True)
class RpcCall(Expr):
    """``handle.method(args)``: a remote procedure call through an ``rpc_factory`` handle.

    The method is the XML-RPC server's, not the controller's: any name, any arguments
    (Script Manual SW5.20, "Remote Procedure Call (RPC)").
    """

    base: Expr
    method: str
    args: list[Expr]
    kwargs: dict[str, Expr]


@dataclass(slots=True)
class Neg(Expr):
    """Unary minus."""

    expr: Expr


@dataclass(slots=True)
class Not(Expr):
    """``not``: the logical negation."""

    expr: Expr


@dataclass(slots=True)
class BinOp(Expr):
    """An arithmetic operation: +, -, *, / or %."""

    op: str
    left: Expr
    right: Expr


@dataclass(slots=True)
class Compare(Expr):
    """A comparison: ==, !=, <, >, <= or >=."""

    op: str
    left: Expr
    right: Expr


@dataclass(slots=True)
class Logic(Expr):
    """``and``, ``or`` or ``xor`` of two truth values."""

    op: str
    left: Expr
    right: Expr


# ---------- statements (one line) ----------
@dataclass(slots=True)
class Stmt(_Node):
    """Base of statement nodes."""

    line: int = field(default=0, kw_only=True)


@dataclass(slots=True)
class Target(_Node):
    """The left side of an assignment: a name and the indices of an element, if any."""

    name: str
    indices: list[Expr]


@dataclass(slots=True)
class Assign(Stmt):
    """``[local|global] target = value``."""

    scope: str  # "", "local" or "global"
    target: Target
    value: Expr


@dataclass(slots=True)
class CallStmt(Stmt):
    """A function called for its effect."""

    call: Call | RpcCall


@dataclass(slots=True)
class Return(Stmt):
    """``return [value]``."""

    value: Expr | None


@dataclass(slots=True)
class HaltStmt(Stmt):
    """``halt``: the program stops."""


@dataclass(slots=True)
class Jump(Stmt):
    """``break`` or ``continue`` inside a ``while`` loop."""

    word: str


@dataclass(slots=True)
class Critical(Stmt):
    """``enter_critical`` or ``exit_critical``: a section no other thread interrupts."""

    word: str


@dataclass(slots=True)
class ThreadOp(Stmt):
    """``join handle`` or ``kill handle``: wait for or stop a thread started by ``run``."""

    word: str
    handle: str


# block openers and closers (one line each); assembled into the block nodes below
@dataclass(slots=True)
class DefStart(Stmt):
    """The ``def name(params):`` line (``thread name():`` and ``sec name():`` too)."""

    name: str
    params: list[str]
    defaults: dict[str, Expr] = field(default_factory=dict)
    kind: str = "def"  # "def", "thread" or "sec"


@dataclass(slots=True)
class WhileStart(Stmt):
    """The ``while cond:`` line."""

    cond: Expr


@dataclass(slots=True)
class IfStart(Stmt):
    """The ``if cond:`` line."""

    cond: Expr


@dataclass(slots=True)
class ElifLine(Stmt):
    """The ``elif cond:`` line."""

    cond: Expr


@dataclass(slots=True)
class ElseLine(Stmt):
    """The ``else:`` line."""


@dataclass(slots=True)
class EndLine(Stmt):
    """The ``end`` line."""


# ---------- blocks ----------
@dataclass(slots=True)
class Def(Stmt):
    """A function ``def name(params):`` … ``end``, a ``thread`` or a ``sec`` program.

    ``defaults`` holds the default values of the trailing parameters that have one.
    """

    name: str
    params: list[str]
    body: list[Stmt]
    defaults: dict[str, Expr] = field(default_factory=dict)
    kind: str = "def"


@dataclass(slots=True)
class While(Stmt):
    """``while cond:`` … ``end``."""

    cond: Expr
    body: list[Stmt]


@dataclass(slots=True)
class If(Stmt):
    """``if``/``elif`` branches (condition, body) and the ``else`` body."""

    branches: list[tuple[Expr, list[Stmt]]]
    orelse: list[Stmt]
