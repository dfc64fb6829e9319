"""The parsers, made faster, read what main's did: the same trees, problems and lines.

The reference (tests/data/parse_reference.json, :mod:`tests.parse_reference`) was written by
main's parsers before the change; every text of its corpus must give the same outcome. The
RAPID parser counts an expression's depth while it builds the nodes; a property test holds
that count to the walk down the whole lark tree that names where a too-deep one is.
"""

from __future__ import annotations

import json

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedInput

from wirecal.lang.rapid import parser as rapid
from wirecal.lang.rapid.parser import SyntaxProblem, parse_module

from .parse_reference import REFERENCE, _broken, _module, corpus, outcome

CORPUS = corpus()


@pytest.mark.slow  # about 5 s of CPU in a fresh process: the golden programs parsed anew
@pytest.mark.parametrize("name", list(CORPUS))
def test_the_parsers_read_the_corpus_as_main_did(name: str) -> None:
    reference = json.loads(REFERENCE.read_text(encoding="utf-8"))
    key, text = CORPUS[name]
    assert json.loads(json.dumps(outcome(key, text))) == reference[name]


def test_the_reference_holds_the_whole_corpus() -> None:
    reference = json.loads(REFERENCE.read_text(encoding="utf-8"))
    assert set(reference) == set(CORPUS)
    refused = [v["parse"] for v in reference.values() if not str(v["parse"]).startswith("tree")]
    assert len(reference) - len(refused) >= 100
    assert len(refused) >= 100
    assert sum("levels deep" in str(p) for p in refused) >= 60  # the depth bound, refused


WRAPS = (
    "1 + ( {} )",  # binop: one level each
    "( {} ) * 2",
    "- ( {} )",  # signed
    "NOT ( {} )",  # not_op
    "Abs( {} )",  # funcall, args, arg: three levels
    "f( 1, \\a:= ( {} ) )",  # funcall, args, opt_arg
    "f( b:= {} )",  # funcall, args, named_arg
    "[ {}, 1 ]",  # aggregate
    "a{{ {} }}",  # an index: the index's own level
    "( {} ).c",  # component
)


def _walked(text: str) -> tuple[int, str] | None:
    """What the walk down the whole lark tree refuses (main's check): (line, message)."""
    try:
        rapid._expression_depth(rapid._tree_parser().parse(rapid._without_header(text)))
    except SyntaxProblem as e:
        return e.line, e.message
    return None


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.sampled_from(WRAPS), min_size=30, max_size=90),
    st.integers(min_value=1, max_value=12),
)
def test_an_expression_is_refused_where_its_whole_tree_says(wraps: list[str], every: int) -> None:
    """Nested constructs around the depth bound, broken over lines: refused iff, and where."""
    expression = "1"
    for wrap in wraps:
        expression = wrap.format(expression)
    text = _module(_broken(f"x := {expression};", every))
    before = rapid._too_deep(rapid._without_header(text))  # brackets beyond 100: unparsed
    expected = (before.line, before.message) if before else _walked(text)
    try:
        parse_module(text)
        found = None
    except SyntaxProblem as e:
        found = e.line, e.message
    assert found == expected


def _written(tree: object) -> list[object]:
    """A lark tree written out: each node's rule and lines, each token's type, text and place."""
    out: list[object] = []
    stack = [tree]
    while stack:  # iterative: the corpus nests expressions beyond a few frames
        node = stack.pop()
        if isinstance(node, Tree):
            meta = node.meta
            out.append(
                ("tree", node.data, getattr(meta, "line", None), getattr(meta, "end_line", None))
            )
            stack.extend(reversed(node.children))
        elif isinstance(node, Token):
            out.append(("token", node.type, str(node), node.line, node.column, node.end_line))
        else:
            out.append(("value", repr(node)))
    return out


def _tree_or_error(parser: Lark, text: str) -> object:
    try:
        return _written(parser.parse(text))
    except UnexpectedInput as e:
        return type(e).__name__, e.line, e.column


@pytest.mark.slow  # about 1.2 s of CPU: the parser built anew costs what the copy saves
def test_the_tree_parser_copied_from_the_first_reads_as_one_built_anew() -> None:
    """The too-deep path's parser (the first's tables, copied) gives a parser built anew's trees.

    Every short RAPID text of the reference corpus (the examples, the windows of the golden
    module, the nested expressions): the same rules, lines, tokens and places, or the same
    error at the same place.
    """
    built = rapid._lark(None)
    texts = [t for key, t in CORPUS.values() if key == "rapid" and len(t) < 10_000]
    assert len(texts) > 200
    for text in texts:
        plain = rapid._without_header(text)
        assert _tree_or_error(rapid._tree_parser(), plain) == _tree_or_error(built, plain)
