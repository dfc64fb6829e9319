r"""The RAPID checker: a module's problems, each ``SOURCE:LINE: what`` ([] = clean).

It reads a module with :mod:`.parser` and checks what the controller would refuse when the
module is loaded, for the subset of :mod:`.tables`: names declared before use (data,
routines, predefined data; a group-input argument may name an I/O signal of the
controller's configuration), reserved words and over-long names, types of every assignment,
argument, operand and condition (num, dnum and string do not mix: a numeric literal takes
the type it is used as), CONST data never assigned, instruction arguments (required ones in
order, optional ones ``\Name`` known), a FUNC that returns a value, string literals of at
most 80 characters and integer literals a num holds exactly.

It reads RAPID beyond what the twin runs (:class:`Dialect`): robtarget, tooldata and the
other records and their literals, RECORD and ALIAS declarations, MoveL/MoveJ/MoveC, I/O
signals, sockets, raw bytes, string functions, TRAP routines and CONNECT, ERROR handlers
with RAISE, RETRY and TRYNEXT (in a handler only), GOTO to a label of the routine, named
required arguments and ``%name%`` late binding. The twin's interpreter checks with
``subset=True``: then each of those is "not in wirecal's RAPID subset", named, before a
run. The interpreter reuses :class:`Typer` to know whether an expression is a num or a dnum.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from wirecal.lang.rapid import nodes as N
from wirecal.lang.rapid import tables as T
from wirecal.lang.rapid.eio import CONFIG_SUFFIX, config_signals
from wirecal.lang.rapid.parser import SyntaxProblem, parse_module
from wirecal.lang.syntax import node_method

SUBSET = "not in wirecal's RAPID subset"


@dataclass(frozen=True)
class Type:
    """A data type and its array sizes (``None``: a ``{*}`` parameter's open size)."""

    name: str
    dims: tuple[int | None, ...] = ()

    def element(self) -> Type:
        """Return the type of one element of this array."""
        return Type(self.name)

    def __str__(self) -> str:
        """Write the type as RAPID does: ``num{3,6}``."""
        if not self.dims:
            return self.name
        return self.name + "{" + ",".join("*" if d is None else str(d) for d in self.dims) + "}"


NUM, DNUM, BOOL, STRING = Type("num"), Type("dnum"), Type("bool"), Type("string")
UNKNOWN = Type("?")
"""The type of data declared outside the subset (reported once, where it is declared)."""
LITERAL = Type("numeric literal")
"""A numeric literal (or an expression of literals only): a num or a dnum, as it is used."""


@dataclass
class Symbol:
    """A data name in scope: its type and kind (VAR, PERS, CONST, INOUT, IN, FOR, PREDEF)."""

    name: str
    type: Type
    kind: str


@dataclass
class Problems:
    """The problems found, (line, message), in the order found."""

    items: list[tuple[int, str]] = field(default_factory=list)

    def add(self, line: int, message: str) -> None:
        """Record one problem."""
        self.items.append((line, message))


@dataclass(frozen=True)
class Dialect:
    """The RAPID a check accepts: the twin's subset, or RAPID as far as the tables go."""

    subset: bool
    records: Mapping[str, tuple[tuple[str, str], ...]]
    aliases: Mapping[str, str]
    opaque: frozenset[str]
    instructions: Mapping[str, T.Routine]
    functions: Mapping[str, T.Routine]

    def resolve(self, type_name: str) -> str | None:
        """Return the type ``type_name`` means (an alias followed), None if unknown."""
        key = type_name.lower()
        for _ in range(8):  # an ALIAS of an ALIAS: RAPID refuses it (unconfirmed); 8 is ample
            if key not in self.aliases:
                break
            key = self.aliases[key]
        known = key in T.ATOMIC or key in self.opaque or key in self.records
        return key if known else None

    def components(self, type_name: str) -> dict[str, str]:
        """Return a record's components, name → type (lower case)."""
        return {k.lower(): v.lower() for k, v in self.records.get(type_name, ())}


SUBSET_DIALECT = Dialect(True, T.RECORDS, {}, T.OPAQUE, T.INSTRUCTIONS, T.FUNCTIONS)
"""What the twin runs (the interpreter's check)."""


def dialect(subset: bool, modules: tuple[N.Module, ...]) -> Dialect:
    """Return the dialect of a check: with ``subset`` False, RAPID with the modules' types."""
    if subset:
        return SUBSET_DIALECT
    records = {**T.RECORDS, **T.WIDE_RECORDS}
    aliases = dict(T.ALIASES)
    for m in modules:
        records.update({k.lower(): v for k, v in m.records.items()})
        aliases.update({k.lower(): v.lower() for k, v in m.aliases.items()})
    return Dialect(
        False,
        records,
        aliases,
        T.OPAQUE | T.WIDE_OPAQUE,
        {**T.INSTRUCTIONS, **T.WIDE_INSTRUCTIONS},
        {**T.FUNCTIONS, **T.WIDE_FUNCTIONS},
    )


class Typer:
    """Types of expressions in one routine's scope (problems go to ``problems``)."""

    def __init__(
        self,
        scope: dict[str, Symbol],
        problems: Problems,
        routines: dict[str, T.Routine],
        line: int = 0,
        lang: Dialect = SUBSET_DIALECT,
    ):
        self.scope, self.problems, self.routines, self.line = scope, problems, routines, line
        self.lang = lang
        self.signals: set[str] = set()
        self.software: tuple[int, ...] | None = None
        self.external = False  # calls to routines not in the module are allowed

    def symbol(self, name: str) -> Symbol | None:
        """Return the data ``name`` refers to, or None (the problem reported)."""
        sym = self.scope.get(name.lower())
        wide = None if self.lang.subset else T.wide_data(name)
        if sym is None and wide is not None:
            return Symbol(name, Type(self.lang.resolve(wide) or wide), "PREDEF")
        if sym is None and T.other_data(name):
            self.problems.add(self.line, f"{name}: RAPID's predefined data {SUBSET}")
        elif sym is None:
            what = (
                "a routine, not data"
                if name.lower() in self.routines
                else "not declared in this module, nor data RAPID predefines"
            )
            self.problems.add(self.line, f"unknown data name {name} ({what})")
        return sym

    def root(self, e: N.Expr) -> N.Name | None:
        """Return the data name at the root of ``e`` (a.b{1}.c → a), None if not data."""
        while isinstance(e, N.Component | N.Index):
            e = e.base
        return e if isinstance(e, N.Name) else None

    @node_method
    def type(self, e: N.Expr, want: Type | None = None) -> Type | None:
        """Return the type of ``e`` (``want``: the type the context needs, for aggregates).

        A function call when no case is its own.
        """
        assert isinstance(e, N.FuncCall), e
        return self.call(e.name, e.args, function=True)

    @type.register
    def _(self, e: N.Num, want: Type | None = None) -> Type | None:
        return LITERAL

    @type.register
    def _(self, e: N.Str, want: Type | None = None) -> Type | None:
        if len(e.value) > T.STRING_MAX:
            self.problems.add(
                self.line,
                f"a string of {len(e.value)} characters: a RAPID string holds at most "
                f"{T.STRING_MAX} (RAPID kernel, built-in data types: string)",
            )
        return STRING

    @type.register
    def _(self, e: N.Bool, want: Type | None = None) -> Type | None:
        return BOOL

    @type.register
    def _(self, e: N.Name, want: Type | None = None) -> Type | None:
        sym = self.symbol(e.name)
        if sym is not None and sym.type.name in T.SIGNAL_TYPES and not sym.type.dims:
            return NUM  # a signal in an expression is its value (unconfirmed)
        return sym.type if sym else None

    @type.register
    def _(self, e: N.Component, want: Type | None = None) -> Type | None:
        return self._component(e)

    @type.register
    def _(self, e: N.Index, want: Type | None = None) -> Type | None:
        return self._index(e)

    @type.register
    def _(self, e: N.Aggregate, want: Type | None = None) -> Type | None:
        return self._aggregate(e, want)

    @type.register
    def _(self, e: N.Neg, want: Type | None = None) -> Type | None:
        got = self.type(e.a)
        if got is not None and got not in (NUM, DNUM, LITERAL, UNKNOWN, Type("pos")):
            self.problems.add(self.line, f"- of a {got}: a number is needed")
        return got

    @type.register
    def _(self, e: N.Not, want: Type | None = None) -> Type | None:
        self.expect(e.a, BOOL, "NOT's operand")
        return BOOL

    @type.register
    def _(self, e: N.BinOp, want: Type | None = None) -> Type | None:
        return self._binop(e)

    def _component(self, e: N.Component) -> Type | None:
        base = self.type(e.base)
        if base is None or base == UNKNOWN:
            return None
        parts = self.lang.components(base.name) if not base.dims else {}
        if e.field.lower() not in parts:
            self.problems.add(self.line, f"{base} has no component {e.field}")
            return None
        return self.named_type(parts[e.field.lower()])

    def _index(self, e: N.Index) -> Type | None:
        base = self.type(e.base)
        for i in e.indices:
            self.expect(i, NUM, "an array index")
        if base is None or base == UNKNOWN:
            return None
        if len(e.indices) != len(base.dims):
            self.problems.add(
                self.line,
                f"{len(e.indices)} index(es) to an array of {len(base.dims)} dimension(s)",
            )
            return None
        for i, size in zip(e.indices, base.dims, strict=True):
            if isinstance(i, N.Num) and size is not None and not 1 <= i.value <= size:
                self.problems.add(self.line, f"index {i.value:g} outside 1..{size}")
        return base.element()

    def _aggregate(self, e: N.Aggregate, want: Type | None) -> Type | None:
        if want == UNKNOWN:
            return None
        if want is None:
            self.problems.add(self.line, "an aggregate [...] where its type is not known")
            return None
        if want.dims:
            if want.dims[0] is not None and len(e.items) != want.dims[0]:
                self.problems.add(
                    self.line, f"{len(e.items)} values for an array of {want.dims[0]}"
                )
            inner = Type(want.name, want.dims[1:])
            for item in e.items:
                self.expect(item, inner, "an array element")
            return want
        parts = self.lang.records.get(want.name)
        if parts is None:
            self.problems.add(self.line, f"an aggregate [...] for a {want}")
            return None
        if len(parts) != len(e.items):
            self.problems.add(
                self.line, f"{len(e.items)} values for a {want}, which has {len(parts)} components"
            )
            return want
        for item, (name, type_name) in zip(e.items, parts, strict=True):
            self.expect(item, self.named_type(type_name), f"component {name} of {want}")
        return want

    def operands(self, e: N.BinOp) -> tuple[Type | None, Type | None]:
        """Return the types of a binary operation's operands.

        An aggregate takes the other operand's type (``[10,10,30] + p.trans``).
        """
        if isinstance(e.a, N.Aggregate) and not isinstance(e.b, N.Aggregate):
            b = self.type(e.b)
            return self.type(e.a, b if b != LITERAL else None), b
        a = self.type(e.a)
        return a, self.type(e.b, a if isinstance(e.b, N.Aggregate) and a != LITERAL else None)

    def _binop(self, e: N.BinOp) -> Type | None:
        a, b = self.operands(e)
        if a is None or b is None:
            return None
        if UNKNOWN in (a, b):
            return UNKNOWN
        op = e.op
        if op in ("AND", "OR", "XOR"):
            for _side, got in ((e.a, a), (e.b, b)):
                if got != BOOL:
                    self.problems.add(self.line, f"{op} of a {got}: bool is needed")
            return BOOL
        if op == "+" and a == b == STRING:
            return STRING
        vector = self._vector(a, op, b)
        if vector is not None:
            return vector
        if op in ("=", "<>") and a == b and a not in (LITERAL,) and not a.dims:
            return BOOL
        both = self.numeric(a, b, op, e)
        if both is None:
            return None
        return BOOL if op in ("=", "<>", "<", ">", "<=", ">=") else both

    def _vector(self, a: Type, op: str, b: Type) -> Type | None:
        """Return the type of an operation on pos or orient (None: not one).

        The subset has them as data (a loaddata's parts), not arithmetic: refused there.
        """
        vector = _VECTOR_OPS.get((a.name if not a.dims else "", op, b.name if not b.dims else ""))
        if vector is not None and self.lang.subset:
            self.problems.add(self.line, f"{a.name} {op} {b.name}: {SUBSET}")
        return None if vector is None else Type(vector)

    def numeric(self, a: Type, b: Type, op: str, e: N.BinOp) -> Type | None:
        """Return the type two numeric operands combine to (num, dnum or a literal)."""
        for got in (a, b):
            if got not in (NUM, DNUM, LITERAL):
                self.problems.add(self.line, f"{a} {op} {b}: {op} needs two numbers of one type")
                return None
        if LITERAL in (a, b):
            typed = b if a == LITERAL else a
            if typed == NUM:
                self.literal_fits(e.a if a == LITERAL else e.b, NUM)
            return typed
        if a != b:
            self.problems.add(
                self.line,
                f"num and dnum mixed ({a} {op} {b}): convert one with NumToDnum or DnumToNum",
            )
            return None
        return a

    def literal_fits(self, e: N.Expr, want: Type) -> None:
        """Report the integer literals of ``e`` a num does not hold exactly."""
        if want != NUM:
            for lit in _literals(e):
                if math.isinf(lit.value):
                    self.problems.add(self.line, f"a literal beyond a {want}'s range")
            return
        for lit in _literals(e):
            if lit.integer and not T.NUM_EXACT[0] <= lit.value <= T.NUM_EXACT[1]:
                self.problems.add(
                    self.line,
                    f"the integer {int(lit.value)} is beyond what a num holds exactly "
                    f"({T.NUM_EXACT[0]}..{T.NUM_EXACT[1]}, RAPID kernel, built-in data types: "
                    "num); declare the data dnum",
                )
            elif abs(lit.value) > 3.4028234663852886e38:
                self.problems.add(self.line, "a literal beyond a num's range (±3.4E38)")

    def expect(self, e: N.Expr, want: Type, what: str) -> None:
        """Report ``e`` unless it is of type ``want`` (a literal fits a num or a dnum)."""
        got = self.type(e, want)
        if got is None or UNKNOWN in (got, want):
            return
        if got == LITERAL and want in (NUM, DNUM):
            self.literal_fits(e, want)
            return
        if got == want or (
            got.name == want.name
            and len(got.dims) == len(want.dims)
            and all(w is None or g == w for g, w in zip(got.dims, want.dims, strict=True))
        ):
            return
        hint = ": convert with NumToDnum or DnumToNum" if {got, want} == {NUM, DNUM} else ""
        if got == LITERAL:
            got = Type("number")
        self.problems.add(self.line, f"{what} is a {want}, not a {got}{hint}")

    def call(self, name: str, args: list[N.Arg], function: bool) -> Type | None:
        """Check a call of ``name`` (a function when ``function``); return its result type."""
        key = name.lower()
        table = self.lang.functions if function else self.lang.instructions
        routine = self.routines.get(key) or table.get(key)
        unlisted = not self.lang.subset and key in T.OTHER_ROUTINES  # RAPID's, no signature
        if routine is None and (unlisted or (self.external and key not in T.OTHER_ROUTINES)):
            for a in args:  # a routine of another module: its arguments are still read
                if a.value is not None and self.root(a.value) is None:
                    self.untyped(a.value)
            return UNKNOWN
        if routine is None or (routine.returns is None) == function:
            self._unknown(name, function, routine)
            return None
        self.arguments(name, routine, args)
        if self.software is not None and _version(routine.since) > self.software:
            self.problems.add(
                self.line,
                f"{name} needs RobotWare {routine.since} (the controller has "
                f"{'.'.join(map(str, self.software))})",
            )
        return self.named_type(routine.returns) if routine.returns else None

    def untyped(self, e: N.Expr) -> None:
        """Read an expression whose type no signature gives (an aggregate item by item)."""
        if isinstance(e, N.Aggregate):
            for item in e.items:
                self.untyped(item)
        else:
            self.type(e)

    def named_type(self, type_name: str) -> Type:
        """Return the type a table or declaration names (an alias followed)."""
        return Type(self.lang.resolve(type_name) or type_name.lower())

    def _unknown(self, name: str, function: bool, routine: T.Routine | None) -> None:
        key, kind = name.lower(), "function" if function else "instruction"
        if routine is not None:
            other = "a FUNC: call it in an expression" if routine.returns else "a PROC"
            self.problems.add(
                self.line,
                f"{name} is {other}, not an {kind}"
                if kind == "instruction"
                else f"{name} is {other}, not a {kind}",
            )
        elif (
            key in T.OTHER_ROUTINES
            or key in T.WIDE_FUNCTIONS
            or key in T.WIDE_INSTRUCTIONS
            or key in (self.lang.functions if not function else self.lang.instructions)
        ):
            self.problems.add(self.line, f"{name}: a RAPID {kind} {SUBSET}")
        else:
            self.problems.add(
                self.line,
                f"unknown {kind} {name} (neither RAPID's, in wirecal's table, nor a "
                f"{'FUNC' if function else 'PROC'} of this module)",
            )

    def arguments(self, name: str, routine: T.Routine, args: list[N.Arg]) -> None:
        """Match ``args`` to ``routine``'s parameters: required in order, optional by name."""
        required = [p for p in routine.params if not p.optional]
        optional = {p.name.lower(): p for p in routine.params if p.optional}
        positional = [a for a in args if a.name is None or a.named]
        self._named(name, required, positional)
        if len(positional) != len(required):
            self.problems.add(
                self.line,
                f"{name} takes {len(required)} argument(s) "
                f"({', '.join(p.name for p in required) or 'none'}), "
                f"given {len(positional)}",
            )
        for p, a in zip(required, positional, strict=False):
            self.argument(name, p, a)
        seen: set[str] = set()
        for a in args:
            if a.name is None or a.named:
                continue
            opt = optional.get(a.name.lower())
            if opt is None or a.name.lower() in seen:
                why = "given twice" if opt else "no such optional argument"
                self.problems.add(self.line, f"{name} \\{a.name}: {why}")
                continue
            seen.add(a.name.lower())
            if a.condition is not None:
                self.conditional(name, opt, a.condition)
            elif (opt.type == "switch") != (a.value is None):
                need = "takes no value" if opt.type == "switch" else f"needs := a {opt.type}"
                self.problems.add(self.line, f"{name} \\{a.name} {need}")
            elif a.value is not None:
                self.argument(name, opt, a)

    def conditional(self, name: str, p: T.P, condition: str) -> None:
        r"""Check ``\P ? Param``: ``Param`` an optional parameter of the calling routine.

        A conditional argument passes the caller's optional parameter on when it is given
        (RAPID kernel, conditional arguments: unconfirmed, no page read; controller-loaded:
        compas-rrc/compas_rrc_start@4b831ac, RRC_Base_Feedback_Rob.sys, ``\FlyBy?FlyBy``).
        """
        if self.lang.subset:
            self.problems.add(
                self.line, f"{name} \\{p.name}?{condition}: a conditional argument: {SUBSET}"
            )
            return
        sym = self.scope.get(condition.lower())
        if sym is None or sym.kind != "OPT":
            self.problems.add(
                self.line,
                f"{name} \\{p.name}?{condition}: {condition} is not an optional parameter of "
                "this routine",
            )
        elif (
            UNKNOWN not in (sym.type,)
            and p.type != "switch"
            and sym.type != self.named_type(p.type)
        ):
            self.problems.add(
                self.line,
                f"{name} \\{p.name}?{condition}: {condition} is a {sym.type}, not a {p.type}",
            )

    def _named(self, name: str, required: list[T.P], positional: list[N.Arg]) -> None:
        """Check required arguments given by name (``Speed:=v100``): each in its place."""
        for p, a in zip(required, positional, strict=False):
            if a.named and self.lang.subset:
                self.problems.add(self.line, f"{a.name} := …: a named required argument: {SUBSET}")
            elif a.named and (a.name or "").lower() != p.name.lower():
                self.problems.add(self.line, f"{name}: {a.name} := where {p.name} is due")

    def argument(self, name: str, p: T.P, a: N.Arg) -> None:
        """Check one argument against its parameter."""
        assert a.value is not None
        if p.type in T.SIGNAL_TYPES:
            self._signal(name, p, a.value)
            return
        if p.type == T.SIGNAL_NAME:
            self._any_signal(name, p, a.value)
            return
        if p.type in ("anytype", "anynum"):
            if p.var:
                self.writable(a.value, f"{name}'s {p.name}")
            got = self.type(a.value)
            if p.type == "anynum" and got not in (None, NUM, DNUM, LITERAL, UNKNOWN):
                self.problems.add(self.line, f"{name}'s {p.name} is a num or a dnum, not a {got}")
            return
        if p.type == "optional parameter":
            sym = self.scope.get(a.value.name.lower()) if isinstance(a.value, N.Name) else None
            if sym is None or sym.kind != "OPT":
                self.problems.add(self.line, f"{name} takes an optional parameter's name")
            return
        if p.type == "tooldata" or (p.type in ("zonedata", "wobjdata") and self.lang.subset):
            (self._tool if p.type == "tooldata" else self._predefined)(name, p, a.value)
            return
        if p.var:
            self.writable(a.value, f"{name}'s {p.name}")
        want = Type(self.named_type(p.type).name, (None,) * p.dims)
        self.expect(a.value, want, f"{name}'s {p.name}")

    def _signal(self, name: str, p: T.P, e: N.Expr) -> None:
        """Check a signal: a name of the configuration, or (beyond the subset) its data."""
        if isinstance(e, N.Name) and e.name.lower() not in self.scope:
            self.signals.add(e.name)
            return
        sym = self.scope.get(e.name.lower()) if isinstance(e, N.Name) else None
        if sym is not None and sym.type in (Type(p.type), UNKNOWN):
            return  # a signal variable (the subset's: a signalgi bound by AliasIO)
        self.problems.add(
            self.line,
            f"{name}'s {p.name} is the name of {T.SIGNAL_TYPES[p.type]} signal ({p.type})",
        )

    def _any_signal(self, name: str, p: T.P, e: N.Expr) -> None:
        """Check a signal of any type: a configured name, a string naming one, or a variable."""
        if isinstance(e, N.Name) and e.name.lower() not in self.scope and not p.var:
            self.signals.add(e.name)
            return
        if p.var and not self.writable(e, f"{name}'s {p.name}"):
            return
        got = self.type(e) if not isinstance(e, N.Name) else self.symbol(e.name)
        got = got.type if isinstance(got, Symbol) else got
        if got is None or got == UNKNOWN or (got.name in T.SIGNAL_TYPES and not got.dims):
            return
        if got == STRING and not p.var:
            return
        self.problems.add(self.line, f"{name}'s {p.name} is an I/O signal, not a {got}")

    def _tool(self, name: str, p: T.P, e: N.Expr) -> None:
        """Check a Tool: a tooldata persistent, entire (:data:`~T.TOOLDATA_PAGE`).

        The page: "Arguments of the type tool data in any motion instruction should only be
        an entire persistent (not array element or record component)"; tool0 is one, and so
        is a PERS parameter (an optional one is not judged).
        """
        sym = self.scope.get(e.name.lower()) if isinstance(e, N.Name) else None
        if isinstance(e, N.Name) and (sym is None or sym.kind in ("PERS", "PREDEF", "OPT")):
            self.expect(e, Type("tooldata"), f"{name}'s {p.name}")
            return
        if sym is not None and sym.type == UNKNOWN:
            return
        self.problems.add(
            self.line,
            f"{name}'s {p.name}: a tooldata PERS, whole (not a VAR, a CONST, an array "
            "element or a component: RAPID Reference Manual, tooldata)",
        )

    def _predefined(self, name: str, p: T.P, e: N.Expr) -> None:
        known = [k for k, v in T.PREDEFINED.items() if v == p.type]
        sym = self.scope.get(e.name.lower()) if isinstance(e, N.Name) else None
        if sym is not None and sym.type == UNKNOWN:
            return
        if not isinstance(e, N.Name) or e.name.lower() not in known:
            self.problems.add(
                self.line,
                f"{name}'s {p.name}: wirecal's subset takes a predefined {p.type} "
                f"({', '.join(known[:4])}…), {SUBSET} otherwise",
            )

    def writable(self, e: N.Expr, what: str) -> bool:
        """Report ``e`` unless it is a variable the program may write."""
        root = self.root(e)
        if root is None:
            self.problems.add(self.line, f"{what} must be a variable, not an expression")
            return False
        sym = self.scope.get(root.name.lower())
        if sym is None:
            return True  # type() reports it
        if sym.kind in ("CONST", "PREDEF", "FOR"):
            self.problems.add(
                self.line,
                f"{root.name} is {_KIND_WORDS[sym.kind]}: it cannot be assigned",
            )
            return False
        return True


_VECTOR_OPS = {
    ("pos", "+", "pos"): "pos",
    ("pos", "-", "pos"): "pos",
    ("pos", "*", "pos"): "pos",  # the cross product
    ("num", "*", "pos"): "pos",
    ("numeric literal", "*", "pos"): "pos",
    ("pos", "*", "num"): "pos",
    ("pos", "*", "numeric literal"): "pos",
    ("pos", "/", "num"): "pos",
    ("pos", "/", "numeric literal"): "pos",
    ("orient", "*", "orient"): "orient",
}
"""Operators on pos and orient and their result (RAPID kernel, expressions: unconfirmed;
controller-loaded: SDEBEUL/Kraker1@5a5835c mSettings_Gripper.sys adds two pos)."""

_KIND_WORDS = {"CONST": "a CONST", "PREDEF": "predefined data", "FOR": "a FOR loop variable"}


def _literals(e: N.Expr) -> list[N.Num]:
    """Return the numeric literals of an expression."""
    if isinstance(e, N.Num):
        return [e]
    if isinstance(e, N.Neg):
        return _literals(e.a)
    if isinstance(e, N.BinOp):
        return _literals(e.a) + _literals(e.b)
    return []


class Checker:
    """Check one module (see the module docstring)."""

    def __init__(
        self,
        module: N.Module,
        software: str | None = None,
        task: tuple[N.Module, ...] = (),
        external_calls: bool = False,
        subset: bool = False,
        config: Mapping[str, str] | None = None,
    ):
        self.module, self.problems, self.task = module, Problems(), task
        self.external_calls = external_calls
        self.software = _version(software) if software else None
        self.lang = dialect(subset, (module, *task))
        predefined = T.PREDEFINED if subset else {**T.PREDEFINED, **T.WIDE_PREDEFINED}
        self.globals: dict[str, Symbol] = {
            k: Symbol(k, Type(self.lang.resolve(v) or v), "PREDEF")
            for k, v in {**(config or {}), **predefined}.items()
        }
        self.user: dict[str, T.Routine] = {}
        self.traps: set[str] = set()
        self.signals: set[str] = set()
        self.own_types = {u.name.lower() for m in (module, *task) for u in m.unsupported if u.name}
        self.sizes: dict[str, int] = {}
        self.task_data: set[str] = set()  # global data the task's other modules declare
        self.in_handler = False
        self.labels: set[str] = set()

    def typer(self, scope: dict[str, Symbol], line: int = 0) -> Typer:
        """Return a :class:`Typer` of this check's dialect over ``scope``."""
        return Typer(scope, self.problems, self.user, line, self.lang)

    def run(self) -> list[tuple[int, str]]:
        """Check the module; return its problems sorted by line."""
        m = self.module
        self.name(m.name, 1, "module")
        for attr in m.attrs:
            if attr.upper() not in T.MODULE_ATTRIBUTES:
                self.problems.add(1, f"unknown module attribute {attr}")
        for u in m.unsupported:
            if self.lang.subset:
                self.problems.add(u.line, f"{u.what}: {SUBSET}")
            else:
                self.own_type(u, m)
        self.declare_task()
        self.task_data = {k for k, sym in self.globals.items() if sym.kind != "PREDEF"}
        self.constant_sizes(m.data)
        for r in m.routines:
            self.signature(r)
        typer = self.typer(self.globals)
        for d in m.data:
            self.declare(d, self.globals, typer)
        for r in m.routines:
            self.routine(r)
        return sorted(set(self.problems.items))

    def declare_task(self) -> None:
        """Declare the global data and routines of the task's other modules (not checked)."""
        checked, self.problems = self.problems, Problems()
        typer = self.typer(self.globals)
        for other in self.task:
            for r in other.routines:
                if not r.local:
                    self.signature(r)
            for d in other.data:
                if not d.local:
                    self.declare(d, self.globals, typer)
        self.problems = checked

    def constant_sizes(self, data: list[N.Data]) -> None:
        """Record the module's CONST nums of an integer value: array sizes, declared anywhere.

        An array size may name a CONST declared further down (controller-loaded:
        compas-rrc/compas_rrc_start@4b831ac, RRC_DataTask_Ctrl.sys; RAPID kernel: unconfirmed).
        """
        for d in data:
            if d.storage == "CONST" and d.type.lower() == "num" and isinstance(d.init, N.Num):
                if d.init.integer:
                    self.sizes[d.name.lower()] = int(d.init.value)

    def own_type(self, u: N.Unsupported, m: N.Module) -> None:
        """Check a RECORD's component types or an ALIAS's type (declared types only)."""
        self.name(u.name, u.line, "data type")
        if u.name in m.records:
            for _, type_name in m.records[u.name]:
                self.data_type(type_name, [], u.line)
        elif self.lang.resolve(u.name) is None:
            self.problems.add(u.line, f"ALIAS {u.name} names an unknown data type")

    def name(self, name: str, line: int, what: str) -> None:
        """Report a reserved word or an over-long identifier used as a name."""
        if name.upper() in T.RESERVED:
            self.problems.add(line, f"{name} is a RAPID reserved word: it cannot name a {what}")
        if len(name) > T.NAME_MAX:
            self.problems.add(
                line, f"the name {name} has {len(name)} characters: RAPID takes {T.NAME_MAX}"
            )

    def data_type(self, type_name: str, dims: list[int | None], line: int) -> Type | None:
        """Return the declared type, or None (reported) outside the subset."""
        key = self.lang.resolve(type_name)
        if key is not None:
            return Type(key, tuple(dims))
        key = type_name.lower()
        if not self.lang.subset:
            self.problems.add(
                line,
                f"unknown data type {type_name} (neither RAPID's in wirecal's table, nor a "
                "RECORD or ALIAS of the task)",
            )
        elif key in T.OTHER_TYPES or key in T.WIDE_OPAQUE or key in T.WIDE_RECORDS:
            self.problems.add(line, f"the data type {type_name}: {SUBSET}")
        elif key in self.own_types:
            self.problems.add(line, f"data of the type {type_name} (this module's): {SUBSET}")
        else:
            self.problems.add(
                line, f"unknown data type {type_name} (neither RAPID's nor a RECORD of this module)"
            )
        return None

    def declare(self, d: N.Data, scope: dict[str, Symbol], typer: Typer) -> None:
        """Check one declaration and add it to ``scope``."""
        typer.line = d.line
        self.name(d.name, d.line, "data")
        sizes = [self.size(x, d.line) for x in d.dims]
        dtype = self.data_type(d.type, sizes, d.line)
        key = d.name.lower()
        if key in scope and self.clashes(d, scope):
            self.problems.add(d.line, f"{d.name} is declared twice")
        if dtype is None:
            scope[d.name.lower()] = Symbol(d.name, UNKNOWN, d.storage)
            return
        if d.init is not None:
            if dtype.name in self.lang.opaque:
                self.problems.add(d.line, f"a {dtype.name} takes no initial value")
            else:
                typer.expect(d.init, dtype, f"the initial value of {d.name}")
        elif d.storage == "CONST":
            self.problems.add(d.line, f"the CONST {d.name} needs a value (:= …)")
        if d.storage == "CONST" and dtype == NUM and isinstance(d.init, N.Num) and d.init.integer:
            self.sizes[d.name.lower()] = int(d.init.value)
        if d.storage == "CONST" and dtype.name in self.lang.opaque:
            self.problems.add(d.line, f"a {dtype.name} cannot be a CONST")
        scope[d.name.lower()] = Symbol(d.name, dtype, d.storage)

    def clashes(self, d: N.Data, scope: dict[str, Symbol]) -> bool:
        """Whether ``d`` clashes with the data of its name already in ``scope``.

        Routine data hides module data and a module's LOCAL data hides the task's global
        data (RAPID kernel, scope rules: unconfirmed; controller-loaded: the COMPAS RRC and
        Kraker1 modules do both); predefined data may be declared again.
        """
        key = d.name.lower()
        known = scope[key]
        if known.kind == "PREDEF":
            return False
        if scope is not self.globals:
            return known is not self.globals.get(key)
        return not (d.local and key in self.task_data)

    def size(self, e: N.Expr, line: int) -> int | None:
        """Return an array size: a positive integer literal, or a CONST num of one."""
        if isinstance(e, N.Name) and e.name.lower() in self.sizes:
            return self.sizes[e.name.lower()]
        if isinstance(e, N.Num) and e.integer and e.value >= 1:
            return int(e.value)
        self.problems.add(
            line, "an array size must be a positive integer, or a CONST num declared as one"
        )
        return None

    def signature(self, r: N.Routine) -> None:
        """Check a routine's name and parameters; record its signature."""
        self.name(r.name, r.line, "routine")
        key = r.name.lower()
        if key in self.user:
            self.problems.add(r.line, f"the routine {r.name} is defined twice")
        if key in self.lang.instructions or key in self.lang.functions:
            self.problems.add(r.line, f"{r.name} is a RAPID routine's name: rename it")
        if r.kind == "TRAP":
            self.traps.add(key)
            if self.lang.subset:
                self.problems.add(r.line, f"TRAP routines (interrupts): {SUBSET}")
        params = [q for p in r.params for q in self.parameter(p)]
        rtype = None
        if r.kind == "FUNC":
            assert r.type is not None
            rtype = self.lang.resolve(r.type) or r.type.lower()
            self.data_type(r.type, [], r.line)
        self.user[key] = T.Routine(tuple(params), rtype, "this module")

    def parameter(self, p: N.Param) -> list[T.P]:
        """Check one parameter (and its ``|`` alternatives); return their table rows."""
        self.name(p.name, p.line, "parameter")
        subset = self.lang.subset
        if subset and (p.mode == "PERS" or (p.mode == "VAR" and not p.optional)):
            self.problems.add(p.line, f"a {p.mode} parameter: {SUBSET} (use INOUT)")
        if subset and p.alternatives:
            self.problems.add(p.line, f"\\{p.name} | …: exclusive parameters: {SUBSET}")
        out = []
        for type_name, name in [(p.type, p.name), *p.alternatives]:
            ptype = type_name.lower()
            if not (ptype == "switch" and p.optional):
                resolved = self.data_type(type_name, [], p.line)
                ptype = resolved.name if resolved else ptype
            out.append(T.P(name, ptype, p.optional, p.mode in ("INOUT", "VAR", "PERS"), p.dims))
        return out

    def routine(self, r: N.Routine) -> None:
        """Check a routine's body in its scope."""
        scope = dict(self.globals)
        for p in r.params:
            kind = "OPT" if p.optional else p.mode if p.mode in ("INOUT", "PERS") else "IN"
            for type_name, name in [(p.type, p.name), *p.alternatives]:
                known = self.lang.resolve(type_name)
                ptype = Type(known, (None,) * p.dims) if known else UNKNOWN
                scope[name.lower()] = Symbol(name, ptype, kind)
        typer = self.typer(scope, r.line)
        typer.software, typer.external = self.software, self.external_calls
        handlers = {"ERROR": r.handler} if r.handler is not None else {}
        handlers.update(r.other_handlers)
        everything = r.body + [s for h in handlers.values() for s in h]
        self.labels = {s.name.lower() for s in _walk(everything) if isinstance(s, N.Label)}
        self.in_handler = False
        self.body(r.body, typer, r)
        for which, handler in handlers.items():
            if self.lang.subset and which != "ERROR":
                self.problems.add(r.line, f"an {which} handler: {SUBSET}")
                continue
            self.in_handler = which == "ERROR"
            self.body(handler, typer, r)
        self.signals |= typer.signals
        if r.kind == "FUNC" and not any(isinstance(s, N.Return) for s in _walk(everything)):
            self.problems.add(r.line, f"the FUNC {r.name} has no RETURN: it must return a {r.type}")

    def body(self, stmts: list[N.Stmt], typer: Typer, r: N.Routine) -> None:
        """Check statements in order."""
        for s in stmts:
            typer.line = s.line
            self.stmt(s, typer, r)

    @node_method
    def stmt(self, s: N.Stmt, typer: Typer, r: N.Routine) -> None:
        """Check one statement (RAPID beyond the subset, or EXIT, when no case is its own)."""
        if self.lang.subset and not isinstance(s, N.Exit) and not self.passes_on(s):
            self.problems.add(s.line, f"{_WHAT[type(s)]}: {SUBSET}")
        else:
            self.beyond(s, typer)

    @stmt.register
    def _(self, s: N.Data, typer: Typer, r: N.Routine) -> None:
        if s.storage == "PERS":
            self.problems.add(s.line, "PERS data cannot be declared in a routine")
        self.declare(s, typer.scope, typer)

    @stmt.register
    def _(self, s: N.Assign, typer: Typer, r: N.Routine) -> None:
        if typer.writable(s.target, "the left of :="):
            want = typer.type(s.target)
            if want is not None:
                typer.expect(s.value, want, f"{_text(s.target)}")

    @stmt.register
    def _(self, s: N.Call, typer: Typer, r: N.Routine) -> None:
        if s.name.lower() in self.traps:
            self.problems.add(s.line, f"{s.name} is a TRAP: an interrupt runs it, a call cannot")
        else:
            typer.call(s.name, s.args, function=False)

    @stmt.register
    def _(self, s: N.If, typer: Typer, r: N.Routine) -> None:
        for cond, body in s.branches:
            typer.line = s.line
            typer.expect(cond, BOOL, "an IF condition")
            self.body(body, typer, r)
        self.body(s.orelse, typer, r)

    @stmt.register
    def _(self, s: N.While, typer: Typer, r: N.Routine) -> None:
        typer.expect(s.cond, BOOL, "a WHILE condition")
        self.body(s.body, typer, r)

    @stmt.register
    def _(self, s: N.For, typer: Typer, r: N.Routine) -> None:
        self.loop(s, typer, r)

    @stmt.register
    def _(self, s: N.Test, typer: Typer, r: N.Routine) -> None:
        self.test(s, typer, r)

    @stmt.register
    def _(self, s: N.Return, typer: Typer, r: N.Routine) -> None:
        self.ret(s, typer, r)

    def passes_on(self, s: N.Stmt) -> bool:
        """Whether ``s`` is ``RAISE;`` in an ERROR handler: the subset runs it."""
        return isinstance(s, N.Raise) and s.value is None and self.in_handler

    def beyond(self, s: N.Stmt, typer: Typer) -> None:
        """Check a statement of RAPID beyond the subset (GOTO, RAISE, CONNECT …)."""
        if isinstance(s, N.Goto) and s.label.lower() not in self.labels:
            self.problems.add(s.line, f"GOTO {s.label}: no label {s.label}: in this routine")
        elif isinstance(s, N.Raise) and s.value is not None:
            typer.expect(s.value, NUM, "RAISE's error number (an errnum)")
        elif isinstance(s, N.Raise) and not self.in_handler:
            self.problems.add(
                s.line, f"RAISE without an error number outside an ERROR handler ({T.RM_RAISE})"
            )
        elif isinstance(s, N.Resume) and not self.in_handler:
            self.problems.add(s.line, f"{s.kind} outside an ERROR handler (unconfirmed)")
        elif isinstance(s, N.Connect):
            self.connect(s, typer)
        elif isinstance(s, N.LateCall):
            typer.expect(s.name, STRING, "a late-bound procedure's name")
            for a in s.args:
                if a.value is not None:
                    typer.type(a.value)

    def connect(self, s: N.Connect, typer: Typer) -> None:
        """CONNECT intno WITH trap: an intnum variable and a TRAP of the task (RM p. 112)."""
        if typer.writable(s.target, "CONNECT's interrupt"):
            typer.expect(s.target, NUM, "CONNECT's interrupt (an intnum)")
        if s.trap.lower() not in self.traps:
            self.problems.add(s.line, f"CONNECT … WITH {s.trap}: no TRAP {s.trap} in the task")

    def loop(self, s: N.For, typer: Typer, r: N.Routine) -> None:
        """Check a FOR loop: its variable is its own num, read-only in the body."""
        for e in (s.start, s.stop, *([s.step] if s.step else [])):
            typer.expect(e, NUM, "a FOR bound")
        self.name(s.var, s.line, "loop variable")
        saved = typer.scope.get(s.var.lower())
        typer.scope[s.var.lower()] = Symbol(s.var, NUM, "FOR")
        self.body(s.body, typer, r)
        if saved is None:
            del typer.scope[s.var.lower()]
        else:
            typer.scope[s.var.lower()] = saved

    def test(self, s: N.Test, typer: Typer, r: N.Routine) -> None:
        """TEST: each CASE value of the tested expression's type."""
        got = typer.type(s.expr)
        for values, body in s.cases:
            typer.line = s.line
            for v in values:
                if got is not None:
                    typer.expect(v, NUM if got == LITERAL else got, "a CASE value")
            self.body(body, typer, r)
        self.body(s.default, typer, r)

    def ret(self, s: N.Return, typer: Typer, r: N.Routine) -> None:
        """RETURN: a value in a FUNC (of its type), none in a PROC."""
        if r.kind == "FUNC" and s.value is None:
            self.problems.add(s.line, f"RETURN in the FUNC {r.name} needs a {r.type} value")
        elif r.kind != "FUNC" and s.value is not None:
            self.problems.add(s.line, f"RETURN with a value in the {r.kind} {r.name}")
        elif s.value is not None and r.type is not None:
            typer.expect(s.value, typer.named_type(r.type), f"the value {r.name} returns")


_WHAT: dict[type, str] = {
    N.Goto: "GOTO",
    N.Label: "a label (GOTO)",
    N.Raise: "RAISE",
    N.Resume: "RETRY and TRYNEXT",
    N.Connect: "CONNECT (interrupts)",
    N.LateCall: "late binding (%name%)",
    N.Placeholder: "a placeholder <SMT> (a statement not yet written)",
}


def _text(e: N.Expr) -> str:
    if isinstance(e, N.Name):
        return e.name
    if isinstance(e, N.Component):
        return f"{_text(e.base)}.{e.field}"
    if isinstance(e, N.Index):
        return f"{_text(e.base)}{{…}}"
    return "the value"


def _walk(stmts: list[N.Stmt]) -> Any:
    for s in stmts:
        yield s
        if isinstance(s, N.If):
            for _, body in s.branches:
                yield from _walk(body)
            yield from _walk(s.orelse)
        elif isinstance(s, N.For | N.While):
            yield from _walk(s.body)
        elif isinstance(s, N.Test):
            for _, body in s.cases:
                yield from _walk(body)
            yield from _walk(s.default)


def check(
    text: str, source: str, software: str | None = None, *, external_calls: bool = False
) -> list[str]:
    """Return the problems of a module's text, each ``SOURCE:LINE: what`` ([] = clean).

    ``external_calls``: calls of routines the module does not define (nor RAPID) are taken
    as routines of another module of the task, their arguments unchecked.
    """
    return check_task({source: text}, software, external_calls=external_calls)


def check_task(
    texts: Mapping[str, str], software: str | None = None, *, external_calls: bool = False
) -> list[str]:
    """Check the modules of one task (file name → text) together.

    Each module sees the global data and routines of the others (RAPID's task scope); the
    problems are each module's own, ``SOURCE:LINE: what``. A ``.cfg`` file among them is the
    controller's I/O configuration: the signals it lists are data the modules may read
    (:mod:`.eio`).
    """
    version = _software(software) if software is not None else []
    modules: dict[str, N.Module] = {}
    out = [f"{source}:{line}: {m}" for source in list(texts)[:1] for line, m in version]
    config: dict[str, str] = {}
    for source, text in texts.items():
        if source.lower().endswith(CONFIG_SUFFIX):
            config.update(config_signals(text))
    for source, text in texts.items():
        if source.lower().endswith(CONFIG_SUFFIX):
            continue
        try:
            modules[source] = parse_module(text)
        except SyntaxProblem as e:
            out.append(f"{source}:{e.line}: {e.message}")
    first: dict[str, str] = {}
    for source, module in list(modules.items()):
        other = first.setdefault(module.name.lower(), source)
        if other != source:
            out.append(
                f"{source}:1: a second module {module.name} in the task (the first: {other}); "
                "a task holds one module of a name: check them as separate tasks"
            )
            del modules[source]
    for source, module in modules.items():
        task = tuple(m for s, m in modules.items() if s != source)
        checker = Checker(
            module, None if version else software, task, external_calls, config=config
        )
        out += [f"{source}:{line}: {m}" for line, m in checker.run()]
    return out


def _version(text: str) -> tuple[int, ...]:
    """Return a RobotWare version as numbers ("6.13.02" → (6, 13, 2)); junk parts read 0."""
    return tuple(int(p) if p.isdigit() else 0 for p in text.strip().split("."))


def _software(software: str) -> list[tuple[int, str]]:
    """RobotWare 6 (IRC5) and 7 (OmniCore) run the subset; refuse anything else by name."""
    major = software.strip().split(".")[0]
    if major in ("6", "7"):
        return []
    return [
        (
            1,
            f'software = "{software}": wirecal\'s RAPID is written for RobotWare 6 (IRC5) '
            "and 7 (OmniCore)",
        )
    ]
