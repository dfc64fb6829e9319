"""The syntax tree of a RAPID module: dataclasses the parser builds from the lark tree.

Names keep the spelling of the source; RAPID compares them without case (the checker and
the interpreter key their tables by ``name.lower()``).
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Num:
    """A numeric literal: its value and whether it was written as an integer."""

    value: float
    integer: bool


@dataclass
class Str:
    r"""A string literal, its escapes ("" and \hh) resolved."""

    value: str


@dataclass
class Bool:
    """TRUE or FALSE."""

    value: bool


@dataclass
class Name:
    """A data name (a variable, a constant, a parameter, predefined data such as v100)."""

    name: str


@dataclass
class Component:
    """A record component: ``base.field`` (jt.robax.rax_1)."""

    base: Expr
    field: str


@dataclass
class Index:
    """An array element: ``base{i}`` or ``base{i, j}`` (indices from 1)."""

    base: Expr
    indices: list[Expr]


@dataclass
class Aggregate:
    """An aggregate ``[a, b, …]``: an array's or a record's value."""

    items: list[Expr]


@dataclass
class BinOp:
    """``a op b``; ``op`` in upper case for the word operators (DIV, MOD, AND, OR, XOR)."""

    op: str
    a: Expr
    b: Expr


@dataclass
class Neg:
    """``-a``."""

    a: Expr


@dataclass
class Not:
    """``NOT a``."""

    a: Expr


@dataclass
class Arg:
    r"""One argument of a call: ``\Name:=value`` (optional, ``name`` set), or a value."""

    value: Expr | None
    name: str | None = None
    named: bool = False
    """A required argument given by its parameter's name (``Name := value``)."""
    condition: str | None = None
    r"""A conditional argument ``\Name ? Param``: given when the caller's optional
    parameter ``Param`` is."""


@dataclass
class FuncCall:
    """A function call in an expression: ``Name(args)``."""

    name: str
    args: list[Arg]


Expr = Num | Str | Bool | Name | Component | Index | Aggregate | BinOp | Neg | Not | FuncCall


@dataclass
class Data:
    """A data declaration: ``[LOCAL] VAR|PERS|CONST type name [{dims}] [:= init];``."""

    storage: str
    type: str
    name: str
    dims: list[Expr]
    init: Expr | None
    line: int
    local: bool = False


@dataclass
class Assign:
    """``target := value;``; the target is a Name, a Component or an Index."""

    target: Expr
    value: Expr
    line: int


@dataclass
class Call:
    """A procedure call (an instruction): ``Name args;``."""

    name: str
    args: list[Arg]
    line: int


@dataclass
class If:
    """IF/ELSEIF/ELSE/ENDIF (a compact IF is one branch of one statement)."""

    branches: list[tuple[Expr, list[Stmt]]]
    orelse: list[Stmt]
    line: int


@dataclass
class For:
    """``FOR var FROM start TO stop [STEP step] DO … ENDFOR`` (var is the loop's own)."""

    var: str
    start: Expr
    stop: Expr
    step: Expr | None
    body: list[Stmt]
    line: int


@dataclass
class While:
    """``WHILE cond DO … ENDWHILE``."""

    cond: Expr
    body: list[Stmt]
    line: int


@dataclass
class Test:
    """``TEST expr CASE v, …: … DEFAULT: … ENDTEST``."""

    expr: Expr
    cases: list[tuple[list[Expr], list[Stmt]]]
    default: list[Stmt]
    line: int


@dataclass
class Return:
    """``RETURN [value];``."""

    value: Expr | None
    line: int


@dataclass
class Exit:
    """``EXIT;``: the program ends."""

    line: int


@dataclass
class Unsupported:
    """A type declaration (RECORD or ALIAS) as the twin's subset refuses it, by line.

    ``name``: the type it declares (its components are in :attr:`Module.records` or
    :attr:`Module.aliases`).
    """

    what: str
    line: int
    name: str = ""


@dataclass
class Goto:
    """``GOTO label;``."""

    label: str
    line: int


@dataclass
class Label:
    """``label:``, a GOTO's target in its routine."""

    name: str
    line: int


@dataclass
class Raise:
    """``RAISE [errno];``: enter the routine's ERROR handler (or the caller's)."""

    value: Expr | None
    line: int


@dataclass
class Resume:
    """``RETRY;`` or ``TRYNEXT;`` (``kind``), allowed in an ERROR handler only."""

    kind: str
    line: int


@dataclass
class Connect:
    """``CONNECT intno WITH trap;``."""

    target: Expr
    trap: str
    line: int


@dataclass
class LateCall:
    """``%expr% args;``: a procedure called by a name computed at run time."""

    name: Expr
    args: list[Arg]
    line: int


@dataclass
class Placeholder:
    """``<SMT>``: a statement not yet written; a module with one loads, running it fails.

    RAPID kernel, placeholders: unconfirmed, no page read; a controller's backup holds one
    (EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e, RAPID/TASK1/PROGMOD/MainModule.mod).
    """

    text: str
    line: int


Stmt = (
    Data
    | Assign
    | Call
    | If
    | For
    | While
    | Test
    | Return
    | Exit
    | Goto
    | Label
    | Raise
    | Resume
    | Connect
    | LateCall
    | Placeholder
)


@dataclass
class Param:
    r"""A routine parameter; ``optional`` for ``\name``; ``mode`` "", INOUT, VAR or PERS."""

    name: str
    type: str
    mode: str
    optional: bool
    dims: int
    line: int
    alternatives: list[tuple[str, str]] = field(default_factory=list)
    """Mutually exclusive optional parameters after ``|``: (type, name) each."""


@dataclass
class Routine:
    """A PROC, FUNC or TRAP with its parameters and body (``handler``: its ERROR handler)."""

    kind: str
    name: str
    type: str | None
    params: list[Param]
    body: list[Stmt]
    handler: list[Stmt] | None
    line: int
    local: bool = False
    other_handlers: dict[str, list[Stmt]] = field(default_factory=dict)
    """BACKWARD and UNDO handlers by keyword."""


@dataclass
class Module:
    """A module: its name, attributes, module data and routines, in source order."""

    name: str
    attrs: list[str]
    data: list[Data]
    routines: list[Routine]
    unsupported: list[Unsupported] = field(default_factory=list)
    records: dict[str, tuple[tuple[str, str], ...]] = field(default_factory=dict)
    """RECORD types declared here: name → (component, type) in order."""
    aliases: dict[str, str] = field(default_factory=dict)
    """ALIAS types declared here: name → the type it names."""
