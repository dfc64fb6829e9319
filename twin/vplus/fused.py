"""Arithmetic on AUTO scalars fused into one Python function: the V+ twin's hot path.

The controller solver's programs are long runs of ``x = a*b + c*d - …`` on AUTO DOUBLE
scalars; compiled node by node (:mod:`wirecal.twin.vplus.interp`) each operation and each
read of a variable is a closure call. An expression of +, - and * on the double path (an
operand DOUBLE: no rounding to single, User's Guide p. 102) whose leaves are AUTO numeric
scalars or numbers is compiled here into one function instead. It reads the frame's slots;
when every one is defined it counts the operations as the nodes would (by kind, in the
order the nodes count them first) and evaluates the same operations on the same numbers in
the same order (the source keeps the tree's parentheses). A slot still undefined leaves the
evaluation to the node-by-node closure, whose error it is.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from types import CodeType, FunctionType

from wirecal.lang.vplus import nodes as N
from wirecal.twin.fused_code import code
from wirecal.twin.machine import f32

_COUNTER = {"+": "add", "-": "add", "*": "mul"}
"""The operations fused and the counter each adds to (the interpreter's ``ops``)."""

Leaf = Callable[[N.Var], "tuple[int, bool] | None"]
"""A variable's frame slot and whether it is DOUBLE, where it is an AUTO numeric scalar."""


@dataclass
class _Fusion:
    """An expression tree being fused: its slots, numbers and operation counts."""

    slots: list[int] = field(default_factory=list)  # read into x0, x1, …
    numbers: list[float] = field(default_factory=list)  # bound as c0, c1, …
    counts: dict[str, int] = field(default_factory=dict)  # in the order the nodes count

    def source(self, e: N.Expr, leaf: Leaf) -> tuple[str, bool] | None:
        """Return ``e`` as Python source and whether it is DOUBLE; None where it cannot fuse."""
        if isinstance(e, N.Paren):
            return self.source(e.expr, leaf)
        if isinstance(e, N.Num):
            self.numbers.append(e.value if e.double else f32(e.value))
            return f"c{len(self.numbers) - 1}", e.double
        if isinstance(e, N.Var):
            found = leaf(e)
            if found is None:
                return None
            if found[0] not in self.slots:
                self.slots.append(found[0])
            return f"x{self.slots.index(found[0])}", found[1]
        if not isinstance(e, N.BinOp) or e.op not in _COUNTER:
            return None
        kind = _COUNTER[e.op]
        self.counts[kind] = self.counts.get(kind, 0) + 1  # the node counts before its operands
        left = self.source(e.left, leaf)
        right = None if left is None else self.source(e.right, leaf)
        if left is None or right is None or not (left[1] or right[1]):
            return None  # an operand that is no leaf, or single precision (rounded)
        return f"({left[0]} {e.op} {right[0]})", True


def fused(e: N.BinOp, leaf: Leaf, ops: Counter, nodes: Callable) -> Callable | None:
    """Return ``e`` compiled into one function (module docstring), or None where it cannot be.

    ``leaf`` names the AUTO numeric scalars, ``ops`` is the interpreter's operation counter,
    ``nodes`` the node-by-node closure of ``e`` (evaluated while a slot is undefined). What
    is written depends on the program's AUTO slots, so it is written for each program (a
    kept line's expression is shared with its copies in other programs); its code is kept
    by its text (:func:`~wirecal.twin.fused_code.code`).
    """
    fusion = _Fusion()
    found = fusion.source(e, leaf)
    if found is None or not found[1]:
        return None
    counts = tuple(fusion.counts.items())
    names = {f"c{k}": v for k, v in enumerate(fusion.numbers)}
    return FunctionType(
        _code(tuple(fusion.slots), counts, found[0]),
        {"ops": ops, "nodes": nodes, **names},
    )


def _code(slots: tuple[int, ...], counts: tuple[tuple[str, int], ...], value: str) -> CodeType:
    """Return the fused function's code (kept by its text, as every fused statement's)."""
    reads = "".join(f"    x{k} = frame[{slot}]\n" for k, slot in enumerate(slots))
    undefined = " or ".join(f"x{k} is None" for k in range(len(slots))) or "False"
    count = "".join(f'    ops["{kind}"] += {n}\n' for kind, n in counts)
    text = (
        f"def fused(frame):\n{reads}    if {undefined}:\n        return nodes(frame)\n"
        f"{count}    return {value}\n"
    )
    return code(text)
