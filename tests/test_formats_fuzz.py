"""Hostile TOML inputs: mutated robot files, plans, truth files, validation setups and
patches are either read or refused with a :class:`WirecalError` — never a traceback.

Each example starts from a real document (the shipped Viper files, a simulated truth, a
written patch) and applies a few mutations anywhere in its tree: a value replaced by one of
another type (booleans, huge, NaN, infinite, strings, dates, lists, tables), a key deleted or added.
A second family mutates the text itself (characters cut, doubled or replaced).
"""

from __future__ import annotations

import copy
import json
import tomllib
from datetime import UTC, datetime
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats import fileio, plan_file, robot_file, truth, validation_files
from wirecal.formats import patch as patch_format
from wirecal.solver.errors import WirecalError
from wirecal.solver.identify import Estimate

from .conftest import VIPER

ROBOTS = sorted((VIPER.parent).glob("*/robot.toml"))

SCALARS = st.one_of(
    st.booleans(),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, 1, -1, 8, 24, 1e300, -1e300, 1e-300, 0.5, 360.0, 1250.0]),
    st.text(max_size=8),
    st.dates(),
    st.times(),
    st.sampled_from(["craig", "belt", "device", "th2", "a1", "deg", "mm", ""]),
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: st.one_of(
        st.lists(inner, max_size=7), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=12,
)


def _paths(node: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path (keys and list indices) into a parsed TOML tree."""
    out = [prefix] if prefix else []
    if isinstance(node, dict):
        for k, v in node.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += _paths(v, (*prefix, i))
    return out


@st.composite
def mutated(draw, base: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(base)
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = data
        for k in path[:-1]:
            parent = parent[k]
        action = draw(st.sampled_from(["replace", "replace", "delete", "add"]))
        if action == "replace":
            parent[path[-1]] = draw(VALUES)
        elif action == "delete":
            del parent[path[-1]]
        elif isinstance(parent, dict):
            parent[draw(st.text(min_size=1, max_size=8))] = draw(VALUES)
        else:
            parent.append(draw(VALUES))
    return data


def _never_a_traceback(read, module, data: dict[str, Any]) -> None:
    def read_toml(path, what) -> dict[str, Any]:  # a function: a MagicMock costs 0.2 ms
        return data

    with mock.patch.object(module, "read_toml", read_toml):
        problems = _problems(read)
    assert problems is None or problems
    assert all(isinstance(p, str) and p for p in problems or ())


def _problems(read, *args) -> list[str] | None:
    """The problems ``read(*args)`` reports as a WirecalError, or None when it accepts."""
    try:
        read(*args)
    except WirecalError as exc:
        return exc.problems
    return None


FUZZ = settings(max_examples=100, deadline=None)
VIPER_ROBOT = tomllib.loads((VIPER / "robot.toml").read_text())
PLAN = tomllib.loads((VIPER / "paper_plan.toml").read_text())
SETUP = tomllib.loads((VIPER / "validation.toml").read_text())
TRUTH = {"robot": "Adept Viper s650", "seed": 3, "errors": {"th2": 0.5, "a2": -0.1, "d4": 0.2}}


def _patch_doc(viper, paper_plan) -> dict[str, Any]:
    estimate = Estimate(
        "joint", ("th2", "a2", "d4"), np.array([0.5, -0.1, 0.2]), 0.011, std=np.ones(3)
    )
    text = patch_format.patch_text(
        viper,
        estimate,
        plan_fingerprint=paper_plan.fingerprint(),
        log_path="run.csv",
        log_sha256="ab" * 32,
        version="0.0",
        date=datetime(2026, 1, 1, tzinfo=UTC),
    )
    return tomllib.loads(text)


@FUZZ
@given(data=st.data())
def test_mutated_robot_files(data):
    base = tomllib.loads(data.draw(st.sampled_from(ROBOTS)).read_text())
    doc = data.draw(mutated(base))
    _never_a_traceback(lambda: robot_file.load_robot("r.toml"), robot_file, doc)


@FUZZ
@given(doc=mutated(PLAN))
def test_mutated_plans(viper, doc):
    _never_a_traceback(lambda: plan_file.load_plan("p.toml", viper), plan_file, doc)


@FUZZ
@given(doc=mutated(TRUTH))
def test_mutated_truth_files(viper, doc):
    _never_a_traceback(lambda: truth.load_errors("t.toml", viper), truth, doc)


@FUZZ
@given(doc=mutated(SETUP))
def test_mutated_validation_setups(doc):
    _never_a_traceback(lambda: validation_files.load_setup("v.toml"), validation_files, doc)


@FUZZ
@given(data=st.data())
def test_mutated_patches(viper, paper_plan, data):
    doc = data.draw(mutated(_patch_doc(viper, paper_plan)))

    def read():
        patch_format.read_patch("patch.toml").offsets_for(viper, paper_plan)

    _never_a_traceback(read, patch_format, doc)


READERS = {
    "robot": (VIPER / "robot.toml", lambda p, r, pl: robot_file.load_robot(p)),
    "plan": (VIPER / "paper_plan.toml", lambda p, r, pl: plan_file.load_plan(p, r)),
    "setup": (VIPER / "validation.toml", lambda p, r, pl: validation_files.load_setup(p)),
}


@pytest.fixture(scope="module")
def fuzz_folder(tmp_path_factory) -> Path:
    """One folder for the mutated texts, each written over the last (not 100 folders a kind)."""
    return tmp_path_factory.mktemp("fuzz")


@pytest.mark.parametrize("kind", sorted(READERS))
@FUZZ
@given(data=st.data())
def test_mutated_text(kind, viper, paper_plan, fuzz_folder, data):
    source, read = READERS[kind]
    text = source.read_text()
    for _ in range(data.draw(st.integers(1, 4))):
        at = data.draw(st.integers(0, len(text) - 1))
        cut = data.draw(st.integers(0, 6))
        insert = data.draw(st.sampled_from(["", "=", "[", "]", '"', ",", "\n", "e9", "true", "-"]))
        text = text[:at] + insert + text[at + cut :]
    path = fuzz_folder / f"{kind}.toml"
    path.write_text(text, encoding="utf-8")
    problems = _problems(read, path, viper, paper_plan)
    assert problems is None or problems


TOML_TEXT = st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=12)


@settings(max_examples=60, deadline=None)
@given(
    depth=st.integers(1, 20),
    strings=st.lists(TOML_TEXT, min_size=1, max_size=4),
    comment=TOML_TEXT,
)
def test_toml_depth_counts_nesting_not_brackets_in_strings(depth, strings, comment):
    """Brackets inside basic, literal and multi-line strings and comments nest nothing."""
    items = ", ".join(json.dumps(s, ensure_ascii=False) for s in strings)  # TOML basic strings
    literal = "'[{'" if "'" not in comment else "'x'"
    text = (
        f"a = {'[' * depth}{items}, {literal}{']' * depth}  # {comment.replace(chr(10), ' ')}\n"
        f'b = """{"[" * 30}\n{"{" * 30}"""\n'
    )
    assert _count_depth(tomllib.loads(text)["a"]) == depth  # the text is valid TOML
    assert fileio.toml_depth(text) == depth


def _count_depth(x: Any) -> int:
    return 1 + max(map(_count_depth, x), default=0) if isinstance(x, list) else 0
