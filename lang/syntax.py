"""What the parsers of every controller language share: the nesting bounds they read.

A program nested deeper than these bounds is refused up front (the checks and the
interpreters recurse per level), a helper walks a parsed program's block tree, the
line parsers keep each line's node by its text, and the checkers and interpreters dispatch
on a node's class (:class:`node_method`).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from functools import cache, lru_cache, singledispatchmethod, update_wrapper
from typing import Any, TypeVar

from wirecal.solver.errors import WirecalError

MAX_BLOCK_DEPTH = 64
"""Deepest nesting of blocks (IF, FOR, WHILE, DO, CASE; URScript def, if, while) the
parsers read. wirecal's bound, far beyond the programs it generates; the controllers' own
limits are unconfirmed. The checks and the interpreters recurse per
level, so a deeper program is refused up front."""

MAX_EXPRESSION_DEPTH = 100
"""Deepest parse tree of one line (nested parentheses, a chain of operators) the parsers
read; wirecal's bound (its generated V+ and URScript lines reach 12), not a controller's."""

MAX_BRACKET_DEPTH = 100
"""Deepest nesting of brackets (``()``, ``[]``, ``{}``) wirecal reads in RAPID, V+ and
URScript, counted on the text before parsing (:func:`check_operator_run`; RAPID's module
scan counts across lines, as its aggregates span them): one rule for the three, whatever a
parse tree keeps of the brackets (URScript's collapses them). wirecal's bound, not a
controller's."""

BRACKET_PROBLEM = (
    f"brackets nested more than {MAX_BRACKET_DEPTH} deep; wirecal reads at most "
    f"{MAX_BRACKET_DEPTH}: split the expression"
)


MAX_OPERATOR_RUN = 10_000
"""Most operators wirecal reads in one run of an expression (at one level of brackets,
between commas and statement ends, whatever the operands, bracketed or not): a longer
chain is refused before parsing, which would take minutes and gigabytes (a chain nests one
level per operator, and :data:`MAX_EXPRESSION_DEPTH` refuses a nesting beyond 100 only
after parsing). wirecal's bound."""

OPERATOR_WORDS = frozenset("AND OR XOR NOT DIV MOD BAND BOR BXOR".split())
"""The operators spelled as words (upper case) in RAPID, V+ and URScript."""

_OPERATORS = OPERATOR_WORDS | frozenset("+-*/^%<>=&|~")
RUN_TOKENS = _OPERATORS | frozenset("()[]{},;")
"""The tokens :class:`OperatorRun` counts (upper case); every other one leaves it as it is."""
_LINE_TOKEN = re.compile(r'"[^"\n]*"|[A-Za-z_][A-Za-z0-9_.]*|[()\[\]{},;]|[-+*/^%<>=!&|~]')


class OperatorRun:
    """The operators of the run seen so far, token by token (see :data:`MAX_OPERATOR_RUN`).

    A bracket opens a run of its own and, closed, continues the run around it (``(a)+(a)``
    is a run of one operator); a comma ends the run, a semicolon every run.
    """

    def __init__(self) -> None:
        self.run = 0
        self.outer: list[int] = []  # the runs around the open brackets

    def see(self, token: str) -> bool:
        """Count ``token`` (upper case): True once the run is longer than the bound."""
        if token in _OPERATORS:
            self.run += 1
        elif token in ("(", "[", "{"):
            self.outer.append(self.run)
            self.run = 0
        elif token in (")", "]", "}"):
            self.run = self.outer.pop() if self.outer else 0
        elif token == ",":
            self.run = 0
        elif token == ";":
            self.run, self.outer = 0, []
        return self.run > MAX_OPERATOR_RUN


OPERATOR_RUN_PROBLEM = (
    f"more than {MAX_OPERATOR_RUN} operators in a row: wirecal reads at most "
    f"{MAX_OPERATOR_RUN} (and nests at most {MAX_EXPRESSION_DEPTH}): split the expression"
)


def check_operator_run(line: str) -> None:
    """Raise :class:`NestingError` for a line nested too deep or too slow to parse, unparsed.

    A run of more than :data:`MAX_OPERATOR_RUN` operators, or brackets nested deeper than
    :data:`MAX_BRACKET_DEPTH` (outside strings). A line of at most
    :data:`MAX_OPERATOR_RUN` characters and at most that many opening brackets is not
    scanned: it parses fast and cannot nest them deeper.
    """
    if len(line) <= MAX_OPERATOR_RUN and sum(map(line.count, "([{")) <= MAX_BRACKET_DEPTH:
        return
    run = OperatorRun()
    for m in _LINE_TOKEN.finditer(line):
        word = m.group().upper()
        if word in RUN_TOKENS and run.see(word):
            raise NestingError(OPERATOR_RUN_PROBLEM)
        if len(run.outer) > MAX_BRACKET_DEPTH:
            raise NestingError(BRACKET_PROBLEM)


KEPT_LINES = 32768
"""How many distinct lines a line parser keeps (:func:`kept_by_text`)."""


class NestingError(Exception):
    """A program nested deeper than the parsers read (its message says where the bound is)."""


def tree_depth(tree: object) -> int:
    """Return the depth of a lark parse tree, without recursion.

    Any object with ``children`` is a node; the root alone has depth 0.
    """
    deepest, level = 0, [tree]
    while level:
        deepest += 1
        level = [c for node in level for c in getattr(node, "children", ()) if c is not None]
    return deepest - 1


def check_line_depth(tree: object) -> None:
    """Raise :class:`NestingError` for a line parsed deeper than :data:`MAX_EXPRESSION_DEPTH`."""
    depth = tree_depth(tree)
    if depth > MAX_EXPRESSION_DEPTH:
        raise NestingError(
            f"the line nests {depth} levels deep (parentheses or chained operators); "
            f"wirecal reads at most {MAX_EXPRESSION_DEPTH}: split the expression"
        )


def check_block_depth(open_blocks: int, where: str) -> None:
    """Raise :class:`WirecalError` at ``where`` when one more block would be too deep.

    Too deep: beyond :data:`MAX_BLOCK_DEPTH`; the whole file is refused, since every
    later line's block would be wrong.
    """
    if open_blocks >= MAX_BLOCK_DEPTH:
        raise WirecalError(
            [
                f"{where}: blocks nested more than {MAX_BLOCK_DEPTH} deep; wirecal reads at "
                f"most {MAX_BLOCK_DEPTH} (the controller's own limit is unconfirmed): move "
                "the inner blocks into a program of their own"
            ]
        )


S = TypeVar("S")


def walk_tree(steps: list[S], children: Callable[[S], list[list[S]]]) -> Iterator[S]:
    """Every statement of ``steps`` and of the blocks inside them (``children``), depth first."""
    for s in steps:
        yield s
        for body in children(s):
            yield from walk_tree(body, children)


def kept_by_text(parse_line: Callable[[str], S]) -> Callable[[str], S]:
    """Return ``parse_line`` keeping each line's node by its text, a new copy per call.

    The modules of one robot (generated with other options, before and after a patch)
    share most of their lines and a module repeats many, so a process parses each distinct
    line once. The copy is shallow: the caller sets its line number; the expressions in it
    are shared with the other copies, and nothing changes them. A line that does not parse
    raises each time.
    """
    kept = lru_cache(maxsize=KEPT_LINES)(parse_line)

    def parse(line: str) -> S:
        return shallow_copy(kept(line))

    parse.__doc__ = parse_line.__doc__
    return parse


def shallow_copy(node: S) -> S:
    """Return what ``copy.copy`` returns for a node (a dataclass, its slots and ``__dict__``).

    The same object, built directly: a new instance of the class with every slot and
    attribute set to the node's, without ``copy.copy``'s ``__reduce_ex__`` (a quarter of the
    CPU; a line parser copies each line's node each time a module holds it).
    """
    cls = type(node)
    new = cls.__new__(cls)
    for name in _slots(cls):  # type: ignore[arg-type]  # a class is hashable
        if hasattr(node, name):
            setattr(new, name, getattr(node, name))
    attributes = getattr(node, "__dict__", None)
    if attributes:
        new.__dict__.update(attributes)
    return new


@cache
def _slots(cls: type) -> tuple[str, ...]:
    """Return the slots of ``cls`` and its bases (``__weakref__`` and ``__dict__`` are none).

    Their names as declared: no node declares a private ``__name``, which Python mangles.
    """
    names = (getattr(k, "__slots__", ()) for k in cls.__mro__)
    slots = [n for group in names for n in ((group,) if isinstance(group, str) else group)]
    return tuple(n for n in dict.fromkeys(slots) if n not in ("__dict__", "__weakref__"))


class node_method(singledispatchmethod):
    """``functools.singledispatchmethod``, bound once per instance, its cases found once per class.

    Python 3.11 builds a new wrapper (``functools.update_wrapper``) at every attribute
    access of a ``singledispatchmethod`` and, at every call, asks the dispatcher (a weak
    dictionary) for the case and binds it again; a checker or compiler calls its per-node
    method once per node. So the wrapper is kept in the instance's ``__dict__`` at its
    first access (the instance finds it there before the class's descriptor) and keeps, by
    the class of the first argument, the case the dispatcher gives bound to the instance.
    The cases are registered in the class body (:meth:`register` refuses one once an
    instance has the method) and none for an abstract class, whose virtual subclasses could
    change later (the first instance's access refuses it), so a case kept is the one the
    dispatcher would give.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        """Remember the attribute's name, where an instance keeps its wrapper."""
        self.attribute = name
        self.bound = False

    def register(self, cls: Any, method: Any = None) -> Any:
        """Register a case (``singledispatchmethod.register``), in the class body only."""
        if getattr(self, "bound", False):
            raise TypeError(f"{self.attribute}: register the cases in the class body")
        return super().register(cls, method)

    def __get__(self, obj: Any, cls: type | None = None) -> Any:
        """Return the dispatching wrapper, kept in ``obj`` from its first access."""
        if obj is None:
            return super().__get__(obj, cls)
        if not self.bound and any(
            hasattr(k, "__abstractmethods__") for k in self.dispatcher.registry
        ):
            raise TypeError(f"{self.attribute}: a case for an abstract class would not be kept")
        self.bound = True
        dispatch = self.dispatcher.dispatch
        cases: dict[type, Callable[..., Any]] = {}

        def dispatched(node: Any, /, *args: Any, **kwargs: Any) -> Any:
            try:
                case = cases[node.__class__]
            except KeyError:
                case = cases[node.__class__] = dispatch(node.__class__).__get__(obj, cls)
            return case(node, *args, **kwargs)

        dispatched.register = self.register  # type: ignore[attr-defined]  # as the base's
        dispatched.__isabstractmethod__ = self.__isabstractmethod__  # type: ignore[attr-defined]
        update_wrapper(dispatched, self.func)
        obj.__dict__[self.attribute] = dispatched
        return dispatched
