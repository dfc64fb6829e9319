"""The URDF reader against hostile files (issue 22): joint loops, two parents, undeclared
links, deep nesting, huge files and entity expansion end in a clear error, quickly and in
bounded memory; any joint graph either reads as a tree or is refused."""

from __future__ import annotations

import itertools
import re
import signal
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats import urdf as U
from wirecal.solver.errors import WirecalError

SECONDS = 10  # each refusal must come well within this (the loop once never ended)


@contextmanager
def deadline(seconds: int = SECONDS):
    """Fail, rather than hang, when the body takes longer than ``seconds``."""

    def expired(*_):
        raise AssertionError(f"still running after {seconds} s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _joint(name: str, parent: str, child: str, kind: str = "revolute") -> str:
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
    )


def _urdf(links: list[str], joints: list[tuple[str, str, str]]) -> str:
    body = "".join(f'<link name="{x}"/>' for x in links)
    body += "".join(_joint(*j) for j in joints)
    return f'<?xml version="1.0"?><robot name="r">{body}</robot>'


def _import(tmp_path: Path, text: str | bytes, tip: str = "c"):
    path = tmp_path / "arm.urdf"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    with deadline():
        r = CliRunner().invoke(
            main, ["import-urdf", str(path), "--tip", tip, "-o", str(tmp_path / "r.toml")]
        )
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    assert r.exit_code == 2, r.output
    assert not (tmp_path / "r.toml").exists()
    return r.output


def test_a_joint_loop_is_an_error_naming_its_joints(tmp_path):
    # base → a, and a loop b → c → d → b hanging off nothing: the tip's walk never met the base
    text = _urdf(
        ["base", "a", "b", "c", "d"],
        [("j0", "base", "a"), ("j1", "b", "c"), ("j2", "c", "d"), ("j3", "d", "b")],
    )
    out = _import(tmp_path, text)
    loop = re.search(r"the joints (.*) form a loop", out)
    assert loop is not None, out
    assert sorted(loop.group(1).split(" → ")) == ["j1", "j2", "j3"]


def test_a_self_loop_is_an_error(tmp_path):
    text = _urdf(["base", "c"], [("j0", "base", "c"), ("j1", "base", "base")])
    assert "form a loop" in _import(tmp_path, text)


def test_two_parents_is_an_error(tmp_path):
    text = _urdf(["base", "b", "c"], [("j0", "base", "c"), ("j1", "b", "c"), ("j2", "base", "b")])
    out = _import(tmp_path, text)
    assert "link 'c' is the child of joints 'j0' and 'j1'" in out


def test_an_undeclared_link_is_an_error(tmp_path):
    text = _urdf(["base", "c"], [("j0", "base", "c"), ("j1", "c", "ghost")])
    out = _import(tmp_path, text)
    assert "joint 'j1': its child link 'ghost' is not a <link> of this URDF" in out
    text = _urdf(["c"], [("j0", "base", "c")])
    assert "its parent link 'base' is not a <link>" in _import(tmp_path, text)


def test_a_link_defined_twice_is_an_error(tmp_path):
    text = _urdf(["base", "c", "c"], [("j0", "base", "c")])
    assert "link 'c' is defined 2 times" in _import(tmp_path, text)


def test_deep_nesting_is_refused_while_streaming(tmp_path):
    depth = 100_000
    text = '<robot name="r">' + "<a>" * depth + "</a>" * depth + "</robot>"
    t0 = time.perf_counter()
    out = _import(tmp_path, text)
    assert f"nested {U.MAX_DEPTH + 1} elements deep" in out
    assert "line 1" in out
    assert time.perf_counter() - t0 < 2.0


def test_too_many_elements_are_refused(tmp_path):
    text = '<robot name="r">' + "<x/>" * (U.MAX_ELEMENTS + 1) + "</robot>"
    assert f"more than {U.MAX_ELEMENTS} elements" in _import(tmp_path, text)


def test_a_huge_file_is_refused_without_reading_it_whole(tmp_path):
    path = tmp_path / "arm.urdf"
    with path.open("wb") as f:
        f.write(b'<robot name="r">')
        f.seek(U.MAX_URDF_BYTES + 10)
        f.write(b"</robot>")
    out = _import(tmp_path, path.read_bytes())
    assert f"more than {U.MAX_URDF_BYTES // 2**20} MiB: not a URDF" in out


def test_entity_expansion_is_refused(tmp_path):
    lol = "".join(f'<!ENTITY lol{i} "{("&lol" + str(i - 1) + ";") * 10}">' for i in range(1, 10))
    text = (
        f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY lol0 "lol">{lol}]>'
        '<robot name="&lol9;"><link name="c"/></robot>'
    )
    t0 = time.perf_counter()
    out = _import(tmp_path, text)
    assert "declares the entity 'lol0'" in out
    assert time.perf_counter() - t0 < 2.0


def test_an_external_entity_is_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("top secret", encoding="utf-8")
    text = (
        f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x SYSTEM "file://{secret}">]>'
        '<robot name="&x;"><link name="c"/></robot>'
    )
    out = _import(tmp_path, text)
    assert "declares the entity 'x'" in out
    assert "top secret" not in out


names = st.sampled_from(["l0", "l1", "l2", "l3", "l4", "l5"])


@settings(max_examples=150, deadline=None)
@given(st.lists(st.tuples(names, names), max_size=8))
def test_any_joint_graph_is_a_tree_or_refused(edges):
    """Random parent → child edges: either refused, or every link reaches a root."""
    links = ["l0", "l1", "l2", "l3", "l4", "l5"]
    text = _urdf(links, [(f"j{i}", p, c) for i, (p, c) in enumerate(edges)])
    with tempfile.TemporaryDirectory() as d, deadline():
        path = Path(d) / "g.urdf"
        path.write_text(text, encoding="utf-8")
        children = [c for _, c in edges]
        if len(set(children)) < len(children) or _has_cycle(edges):
            with pytest.raises(WirecalError, match=r"form a loop|child of joints"):
                U.read_urdf(path)
            return
        doc = U.read_urdf(path)
    parent = {j.child: j.parent for j in doc.joints.values()}
    for link in links:
        seen = 0
        while link in parent:
            link = parent[link]
            seen += 1
            assert seen <= len(links)
    for tip in links:
        try:
            path_ = U.chain(doc, None, tip)
        except WirecalError:
            continue
        assert all(a.child == b.parent for a, b in itertools.pairwise(path_))


def _has_cycle(edges) -> bool:
    parent = dict((c, p) for p, c in edges)
    for start in parent:
        link, steps = start, 0
        while link in parent and steps <= len(parent):
            link, steps = parent[link], steps + 1
        if steps > len(parent):
            return True
    return False


@pytest.mark.parametrize("bad", ["<robot", "<robot><link name='a'></robot>", "\x00"])
def test_broken_xml_is_an_error_not_a_traceback(tmp_path, bad):
    assert "not valid XML" in _import(tmp_path, bad)
