"""The checkers' and compilers' per-node methods dispatch as ``singledispatchmethod`` does.

:class:`~wirecal.lang.syntax.node_method` keeps, per instance, the case found for each node
class: every call must still reach the case ``functools.singledispatchmethod`` reaches,
bound to the right instance, and a registration that would make a kept case wrong is
refused. URScript's bracket count without strings must equal the count character by
character.
"""

from __future__ import annotations

import abc
from functools import singledispatchmethod

import pytest
from hypothesis import given
from hypothesis import strategies as st

from wirecal.lang.syntax import node_method
from wirecal.lang.urscript.parser import _goes_on, _open_brackets


class Node:
    pass


class Leaf(Node):
    pass


class Twig(Leaf):
    pass


class Branch(Node):
    pass


class Other:
    pass


def _walker(method: type) -> type:
    """A class whose ``visit`` names the case reached and the instance it was bound to."""

    class Walker:
        def __init__(self, name: str) -> None:
            self.name = name

        @method
        def visit(self, node: object, extra: str = "") -> str:
            return f"{self.name}: default {type(node).__name__}{extra}"

        @visit.register
        def _(self, node: Leaf, extra: str = "") -> str:
            return f"{self.name}: leaf {type(node).__name__}{extra}"

        @visit.register(Branch)
        def _(self, node: Branch, extra: str = "") -> str:
            return f"{self.name}: branch{extra}"

    return Walker


KEPT = _walker(node_method)
FRESH = _walker(singledispatchmethod)
NODES = [Node, Leaf, Twig, Branch, Other, int, str]


@given(st.lists(st.tuples(st.sampled_from(NODES), st.sampled_from(["", "!"])), max_size=40))
def test_each_call_reaches_the_case_singledispatchmethod_reaches(
    calls: list[tuple[type, str]],
) -> None:
    kept, fresh = KEPT("a"), FRESH("a")
    for cls, extra in calls:
        node = cls()
        assert kept.visit(node, extra=extra) == fresh.visit(node, extra=extra)


def test_the_cases_are_the_expected_ones_bound_to_their_instance() -> None:
    a, b = KEPT("a"), KEPT("b")
    assert a.visit(Twig()) == "a: leaf Twig"
    assert b.visit(Twig()) == "b: leaf Twig"  # a case kept by one instance is not another's
    assert a.visit(Twig()) == "a: leaf Twig"
    assert a.visit(Branch(), "?") == "a: branch?"
    assert b.visit(3) == "b: default int"
    assert a.visit is a.visit  # the wrapper kept in the instance
    assert a.visit.__name__ == "visit"


def test_a_case_registered_after_an_instance_has_the_method_is_refused() -> None:
    walker = _walker(node_method)
    walker("a").visit(Leaf())
    with pytest.raises(TypeError, match="register the cases in the class body"):
        walker.visit.register(Other, lambda self, node: "late")


def test_a_case_for_an_abstract_class_is_refused() -> None:
    class Shape(abc.ABC):
        @abc.abstractmethod
        def area(self) -> float: ...

    class Walker:
        @node_method
        def visit(self, node: object) -> str:
            return "default"

        @visit.register(Shape)
        def _(self, node: Shape) -> str:
            return "shape"

    with pytest.raises(TypeError, match="abstract class"):
        Walker().visit(Other())


def _counted(text: str) -> int:
    """The open brackets outside strings, character by character (the count before)."""
    depth, quote = 0, ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "([":
            depth += 1
        elif ch in ")]":
            depth -= 1
    return depth


@given(st.text(alphabet="()[]{}\"'ab1 ,+#:", max_size=60))
def test_urscript_brackets_are_counted_as_character_by_character(text: str) -> None:
    assert _open_brackets(text) == _counted(text)


@pytest.mark.parametrize(
    ("text", "goes_on"),
    [
        ("  movej([1, 2,", True),
        ("  movej([1, 2])", False),
        ('  textmsg("(")', False),  # a bracket in a string does not count
        ('  textmsg("a", (', True),
        ("  x = a +", True),
        ("  if a:", False),
        ("  x = a)", False),
    ],
)
def test_a_statement_goes_on_while_a_bracket_is_open(text: str, goes_on: bool) -> None:
    assert _goes_on(text) is goes_on
