"""A statement written out as one Python function: what the twins' hot paths share.

The twins compile a program node by node into closures: a call per operation, per read
of a variable and per statement. A statement of arithmetic, reads and stores can instead
be written out as the source of one function that does the same operations on the same
values in the same order, counts them where the closures count them and raises the same
errors. Each twin writes its own nodes (its language's semantics:
:mod:`wirecal.twin.urscript.fused`, :mod:`wirecal.twin.rapid.fused`,
:mod:`wirecal.twin.vplus.fused`); what they share is here: the function's text with its
temporaries and blocks, the names it binds (constants, helpers, the closures of the
nodes it leaves to the node-by-node compiler), the single-precision rounding written out
(:func:`~wirecal.twin.machine.rounding_source`) and the compiled code, kept by its text
(the same statements recur run after run, and their constants are bound, not written).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import lru_cache, partial
from types import CodeType, FunctionType
from typing import Any, Protocol

from wirecal.twin.machine import ROUNDING_NAMES, Kept, rounding_source

CODES_KEPT = 4096
"""Compiled functions kept by their text (a generated module has some hundreds)."""

RECIPES_KEPT = 16384
"""Statements whose written-out function is kept (a generated module has some hundreds)."""

Maker = Callable[[Any], Any]
"""What makes a name's value anew for each compiler (its argument): a node's closure."""


@dataclass(frozen=True)
class Recipe:
    """A statement written out: its code, the values it binds, the names made per compiler.

    ``note``: what its writer learnt of it (V+: whether its value is DOUBLE).
    """

    code: CodeType
    bound: dict[str, Any]
    made: tuple[tuple[str, Maker], ...]
    note: Any = None

    def function(self, compiler: Any, names: dict[str, Any]) -> Callable[[Any], Any]:
        """Return the function for ``compiler``, with ``names`` (its counter, interpreter …)."""
        made = {name: make(compiler) for name, make in self.made}
        return FunctionType(self.code, {**self.bound, **names, **made})


_RECIPES = Kept(RECIPES_KEPT)


def recipe_of(node: Any, place: object, write: Callable[[], Recipe | None]) -> Recipe | None:
    """Return ``write()`` for ``node`` at ``place``, kept for that very pair.

    What is written depends on the node and on its place in its program (a variable's
    scope, a datum's type). A parse is kept by its text, but a line parser's kept line
    shares its expressions with every copy of that line, in other programs and functions
    too: so a recipe is kept for the node together with the parsed object that fixes its
    scope (``place``: a URScript function's definition, a RAPID module), which is the same
    object whenever the node is in the same place; a tuple ``place`` is several objects that
    together fix it (a V+ program and its module). What depends on the run (the counter,
    the interpreter, the closures of the nodes not written out) is made for each compiler
    (:meth:`Recipe.function`).
    """
    places = place if isinstance(place, tuple) else (place,)
    recipe: Recipe | None = _RECIPES.get(write, node, *places)
    return recipe


def written(
    node: Any, write: Callable[[], Recipe | None], compiler: Any, names: dict[str, Any]
) -> Callable[[Any], Any] | None:
    """Return the function ``write`` writes for ``node`` (kept: :func:`recipe_of`), or None."""
    recipe = recipe_of(node, compiler.place, write)
    return None if recipe is None else recipe.function(compiler, names)


class Writer(Protocol):
    """A language's writer of statements (its nodes' semantics) into its :class:`Source`."""

    src: Source

    def assign(self, s: Any) -> None:
        """Emit the assignment ``s``, its line set first."""
        ...


def fused_runs(
    compiler: Any,
    steps: list[Any],
    writable: Callable[[Any], bool],
    writer: Callable[[], Writer],
    names: dict[str, Any],
    one: Callable[[Any], Callable[[Any], Any]],
) -> list[tuple[Any, Callable[[Any], Any]]]:
    """Compile ``steps`` in order, runs of ``writable`` ones written out together.

    Each run of consecutive ``writable`` statements is one function (a new ``writer``'s,
    kept for the run's first statement at the compiler's place: :func:`recipe_of`) doing
    their work in their order, a call per statement less; each other statement is compiled
    by ``one`` (the node-by-node compiler's). Each function comes with its first statement.
    """
    out: list[tuple[Any, Callable[[Any], Any]]] = []
    k = 0
    while k < len(steps):
        n = 0
        while k + n < len(steps) and writable(steps[k + n]):
            n += 1
        if n == 0:
            out.append((steps[k], one(steps[k])))
            k += 1
            continue
        run = steps[k : k + n]
        recipe = recipe_of(steps[k], compiler.place, partial(_run, writer, run))
        assert recipe is not None
        out.append((steps[k], recipe.function(compiler, names)))
        k += n
    return out


def _run(writer: Callable[[], Writer], run: list[Any]) -> Recipe:
    w = writer()
    for s in run:
        w.assign(s)
    return w.src.recipe()


class Source:
    """The source of one generated function ``fused(f)`` (``f``: the frame) and its names.

    The names every such function of a language has (its counter ``ops``, its
    interpreter …) are given when the function is made (:meth:`Recipe.function`).
    """

    def __init__(self, bound: dict[str, Any]):
        self.lines: list[str] = []
        self.bound: dict[str, Any] = {**ROUNDING_NAMES, **bound}
        self.made: list[tuple[str, Maker]] = []
        self.depth = 0
        self.kinds: list[str] = []  # the operations counted, in the order first counted
        self._names = 0

    def bind(self, value: Any) -> str:
        """Return a new global name of the function bound to ``value``."""
        name = f"k{self._names}"
        self._names += 1
        self.bound[name] = value
        return name

    def make(self, maker: Maker) -> str:
        """Return a new global name of the function whose value ``maker`` makes per compiler."""
        name = f"k{self._names}"
        self._names += 1
        self.made.append((name, maker))
        return name

    def temp(self) -> str:
        """Return a new local variable's name."""
        name = f"t{self._names}"
        self._names += 1
        return name

    def emit(self, *lines: str) -> None:
        """Append lines at the current block's indentation."""
        self.lines += ["    " * self.depth + line for line in lines]

    def let(self, value: str) -> str:
        """Emit ``value`` into a new local; return its name."""
        name = self.temp()
        self.emit(f"{name} = {value}")
        return name

    @contextmanager
    def block(self, head: str) -> Iterator[None]:
        """Emit ``head`` (``if …:``, ``else:``) and indent what is emitted inside."""
        self.emit(head)
        self.depth += 1
        try:
            yield
        finally:
            self.depth -= 1

    def count(self, kind: str) -> None:
        """Emit the count of one operation of ``kind`` (into the counter ``ops``).

        Counted in a local, added to ``ops`` when the function ends, however it ends, and
        before :meth:`flush`: ``ops`` holds the same counts, first counted in the same
        order, wherever anything else can see it.
        """
        if kind not in self.kinds:
            self.kinds.append(kind)
        self.emit(f"n_{kind} += 1")

    def flush(self) -> None:
        """Emit the addition of the counts so far to ``ops``.

        Before a call that may read the counts or count into them itself.
        """
        for kind in self.kinds:
            self.emit(f"if n_{kind}: ops[{kind!r}] += n_{kind}; n_{kind} = 0")

    def single(self, value: str, result: str | None = None) -> str:
        """Emit ``value`` (a local) rounded to single precision; return the result's local.

        :func:`~wirecal.twin.machine.rounded`'s numbers and errors.
        """
        result = result or self.temp()
        self.emit(*rounding_source(value, result))
        return result

    def recipe(self, note: Any = None) -> Recipe:
        """Return the function's recipe (with ``note``), its code compiled once per text."""
        lines = self.lines
        if self.kinds:
            counts = [f"if n_{k}: ops[{k!r}] += n_{k}" for k in self.kinds]
            start = " = ".join(f"n_{k}" for k in self.kinds) + " = 0"
            lines = [start, "try:", *("    " + x for x in lines), "finally:"]
            lines += ["    " + x for x in counts]
        body = "".join(f"    {line}\n" for line in lines)
        return Recipe(code(f"def fused(f):\n{body}"), self.bound, tuple(self.made), note)


@lru_cache(maxsize=CODES_KEPT)
def code(text: str) -> CodeType:
    """Return the code of the function ``fused`` that ``text`` defines (kept: docstring)."""
    namespace: dict[str, Any] = {}
    exec(compile(text, "<twin fused statement>", "exec"), namespace)
    return namespace["fused"].__code__
