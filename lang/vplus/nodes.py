"""The typed syntax tree of V+ programs: one dataclass per construct.

The lark transformer of :mod:`wirecal.lang.vplus.parser` builds these nodes (classes
that derive from ``lark.ast_utils.Ast`` are matched to the grammar rule of the same name
in snake case, as in lark's ``create_ast`` example); the checker and the interpreter
dispatch on the node type. Names are kept in lower case with their type prefix
(``$`` string, ``#`` precision point, ``%`` belt; User's Guide p. 99); instruction and
function names in lower case too (V+ keywords are case-insensitive, p. 99).

Statements carry the number of their line in the source file; an expression belongs to
the line of its statement.
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
    """A number literal."""

    value: float
    double: bool  # a ^D literal is DOUBLE (User's Guide p. 102)


@dataclass(slots=True)
class Str(Expr):
    """A string literal."""

    text: str


@dataclass(slots=True)
class Var(Expr):
    """A variable, with its index expressions when it is an array element.

    When its name is a V+ constant such as TRUE, PI or NULL, that constant.
    """

    name: str
    index: list[Expr] | None = None

    @property
    def kind(self) -> str:
        """Return the kind: n (real or transformation), s ($), l (#), b (%)."""
        return _PREFIX_KIND.get(self.name[:1], "n")


@dataclass(slots=True)
class Func(Expr):
    """A function call, e.g. SQRT(x)."""

    name: str
    args: list[Expr | None]


@dataclass(slots=True)
class Shift(Expr):
    """SHIFT(t BY dx, dy, dz) (User's Guide p. 168)."""

    base: Expr
    dx: Expr
    dy: Expr
    dz: Expr


@dataclass(slots=True)
class Compound(Expr):
    """``a:b``: the transformation b relative to a (User's Guide p. 314)."""

    left: Expr
    right: Expr


@dataclass(slots=True)
class Paren(Expr):
    """``(e)``: kept, because ``(x)`` passes x by value in a CALL (p. 42–45)."""

    expr: Expr


@dataclass(slots=True)
class Neg(Expr):
    """Unary minus."""

    expr: Expr


@dataclass(slots=True)
class Not(Expr):
    """NOT: the logical negation."""

    expr: Expr


@dataclass(slots=True)
class Com(Expr):
    """COM: the bitwise complement of one number (User's Guide p. 114)."""

    expr: Expr


@dataclass(slots=True)
class BinOp(Expr):
    """An arithmetic operation: +, -, *, / or MOD."""

    op: str  # + - * / MOD
    left: Expr
    right: Expr


@dataclass(slots=True)
class Compare(Expr):
    """A comparison: ==, <>, <, >, <= or >=."""

    op: str  # == <> < > <= >=
    left: Expr
    right: Expr


@dataclass(slots=True)
class Logic(Expr):
    """A logical or bitwise operation: AND, OR, XOR, BAND, BOR or BXOR."""

    op: str  # AND OR XOR BAND BOR BXOR
    left: Expr
    right: Expr


@dataclass(slots=True)
class Format(Expr):
    """A format specifier such as /S, /D or /F10.3 in TYPE, WRITE or $ENCODE."""

    spec: str


@dataclass(slots=True)
class Group(Expr):
    """A parenthesised list of instruction operands, e.g. ``(lun, 4)`` in ATTACH.

    ``None`` marks an omitted operand.
    """

    items: list[Expr | None]


@dataclass(slots=True)
class ArrayArg(Expr):
    """``a[]``: a whole array passed to a CALL (by reference)."""

    name: str

    @property
    def kind(self) -> str:
        """Return the kind of its elements: n, s ($), l (#) or b (%)."""
        return _PREFIX_KIND.get(self.name[:1], "n")


_PREFIX_KIND = {"$": "s", "#": "l", "%": "b"}


# ---------- statements (one line) ----------
@dataclass(slots=True)
class Stmt(_Node):
    """Base of statement nodes."""

    line: int = field(default=0, kw_only=True)


@dataclass(slots=True)
class DeclItem(_Node):
    """One name of an AUTO, LOCAL or GLOBAL declaration, with its dimensions."""

    name: str
    dims: list[int] | None = None


@dataclass(slots=True)
class Decl(Stmt):
    """An AUTO, LOCAL or GLOBAL declaration."""

    scope: str  # AUTO, LOCAL, GLOBAL
    dtype: str  # REAL, DOUBLE, LOC (or "" when not given)
    items: list[DeclItem]


@dataclass(slots=True)
class Assign(Stmt):
    """An assignment: ``var = value``."""

    target: Var
    value: Expr


@dataclass(slots=True)
class Call(Stmt):
    """CALL program(arguments)."""

    program: str
    args: list[Expr | None]  # None: an omitted argument


@dataclass(slots=True)
class Clause(_Node):
    """One comma-separated operand of a generic instruction.

    Leading format specifiers, the operands written next to each other, and ``= value``.
    """

    formats: list[str]
    items: list[Expr]
    value: Expr | None = None


@dataclass(slots=True)
class Instruction(Stmt):
    """Any V+ instruction without a structure of its own (MOVE, TYPE, SIGNAL, ...).

    Its name and its operands; ``None`` marks an empty operand (``WAIT.EVENT , 3``).
    """

    name: str
    clauses: list[Clause | None]


@dataclass(slots=True)
class Goto(Stmt):
    """GOTO label."""

    label: int


@dataclass(slots=True)
class IfGoto(Stmt):
    """IF cond GOTO label."""

    cond: Expr
    label: int


@dataclass(slots=True)
class Label(Stmt):
    """A step label."""

    number: int


# block openers and closers (one line each); assembled into the block nodes below
@dataclass(slots=True)
class IfStart(Stmt):
    """The IF ... THEN line."""

    cond: Expr


@dataclass(slots=True)
class ElseLine(Stmt):
    """The ELSE line."""


@dataclass(slots=True)
class EndLine(Stmt):
    """The END line."""


@dataclass(slots=True)
class ForStart(Stmt):
    """The FOR ... TO ... STEP line."""

    var: Var
    start: Expr
    stop: Expr
    step: Expr | None = None


@dataclass(slots=True)
class WhileStart(Stmt):
    """The WHILE ... DO line."""

    cond: Expr


@dataclass(slots=True)
class DoStart(Stmt):
    """The DO line."""


@dataclass(slots=True)
class UntilLine(Stmt):
    """The UNTIL line."""

    cond: Expr


@dataclass(slots=True)
class CaseStart(Stmt):
    """The CASE ... OF line."""

    selector: Expr


@dataclass(slots=True)
class ValueLine(Stmt):
    """The VALUE line of a CASE."""

    values: list[Expr]


@dataclass(slots=True)
class AnyLine(Stmt):
    """The ANY line of a CASE."""


# ---------- blocks ----------
@dataclass(slots=True)
class If(Stmt):
    """The IF ... ELSE ... END block."""

    cond: Expr
    then: list[Stmt]
    orelse: list[Stmt]


@dataclass(slots=True)
class For(Stmt):
    """The FOR ... END block."""

    var: Var
    start: Expr
    stop: Expr
    step: Expr | None
    body: list[Stmt]


@dataclass(slots=True)
class While(Stmt):
    """The WHILE ... END block."""

    cond: Expr
    body: list[Stmt]


@dataclass(slots=True)
class DoUntil(Stmt):
    """The DO ... UNTIL block."""

    body: list[Stmt]
    cond: Expr | None


@dataclass(slots=True)
class Branch(_Node):
    """A VALUE or ANY branch of a CASE block."""

    values: list[Expr] | None  # None: ANY
    body: list[Stmt]


@dataclass(slots=True)
class Case(Stmt):
    """The CASE ... END block."""

    selector: Expr
    branches: list[Branch]
