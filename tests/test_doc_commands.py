"""Every ```bash block of the README and of docs/ runs as written.

Convention (docs/development.md): a ``bash`` block runs verbatim in a fresh folder holding a
copy of the repository's tracked files (a fresh clone) with ``wirecal`` on ``PATH``; the
blocks of one page run in order in one folder, each by ``bash -euo pipefail``. Everything
else is ``text``.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from .conftest import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```[ \t]*$", re.M | re.S)


def bash_blocks(text: str) -> list[str]:
    """Return the bodies of a Markdown text's ```bash blocks, in order."""
    return [body for lang, body in FENCE.findall(text) if lang == "bash"]


def test_bash_blocks_are_found():
    text = "a\n```bash\necho 1\n```\n```text\nno\n```\n```bash\necho 2\necho 3\n```\n"
    assert bash_blocks(text) == ["echo 1\n", "echo 2\necho 3\n"]


def test_every_page_is_linked_from_the_index():
    index = (ROOT / "docs" / "README.md").read_text(encoding="utf-8")
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} - {"README.md"}
    linked = set(re.findall(r"\]\(([\w.-]+\.md)\)", index))
    assert pages <= linked, f"docs pages missing from docs/README.md: {sorted(pages - linked)}"


def anchors(text: str) -> set[str]:
    """Return the anchors GitHub gives a Markdown text's headings (outside code blocks)."""
    text = FENCE.sub("", text)
    titles = re.findall(r"^#{1,6} (.+)$", text, re.M)
    return {re.sub(r"[^\w\- ]", "", t.strip().lower()).replace(" ", "-") for t in titles}


def test_anchors_follow_githubs_rule():
    assert anchors("## `wirecal psi ROBOT PLAN [--json]`\n### Can I trust it? Yes\n") == {
        "wirecal-psi-robot-plan---json",
        "can-i-trust-it-yes",
    }


def test_relative_links_resolve():
    """Every relative link of the README and docs/ names a file, and a heading, that exist."""
    broken = []
    for page in PAGES:
        links = re.findall(r"\]\(([^)#:\s]*)(?:#([^)]*))?\)", page.read_text("utf-8"))
        for target, anchor in links:
            path = page.parent / target if target else page
            if not path.exists():
                broken.append(f"{page.relative_to(ROOT)}: {target}")
            elif anchor and anchor not in anchors(path.read_text("utf-8")):
                broken.append(f"{page.relative_to(ROOT)}: {target}#{anchor}")
    assert not broken


def test_readme_is_short():
    assert len((ROOT / "README.md").read_text(encoding="utf-8").splitlines()) <= 300


def fresh_clone(folder: Path) -> None:
    """Copy into ``folder`` what a fresh clone holds: the repository's tracked files.

    (``examples/``, ``tests/data/``: what a recipe may name.) Outside a git checkout, the
    examples only.
    """
    listed = subprocess.run(
        ["git", "-C", str(ROOT), "ls-files", "-z"], capture_output=True, text=True
    )
    if listed.returncode != 0:
        shutil.copytree(ROOT / "examples", folder / "examples")
        return
    for name in filter(None, listed.stdout.split("\0")):
        source = ROOT / name
        if source.is_file() and not source.is_symlink():
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, folder / name)


@pytest.mark.slow
@pytest.mark.parametrize(
    "page",
    [p for p in PAGES if bash_blocks(p.read_text("utf-8"))],
    ids=lambda p: str(p.relative_to(ROOT)),
)
def test_bash_blocks_run(page, tmp_path):
    fresh_clone(tmp_path)
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    for n, block in enumerate(bash_blocks(page.read_text("utf-8")), 1):
        r = subprocess.run(
            ["bash", "-euo", "pipefail", "-c", block],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
        )
        assert r.returncode == 0, f"{page.name} block {n}:\n{block}\n{r.stdout}\n{r.stderr}"


def test_api_page_example_is_the_tested_one():
    """docs/api.md's Python example is, line for line, what tests/test_api.py runs."""
    page = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    shown = [body for lang, body in FENCE.findall(page) if lang == "python"]
    source = (ROOT / "tests" / "test_api.py").read_text(encoding="utf-8")
    tested = source.split("keep in step with docs/api.md) ---\n")[1]
    tested = tested.split("    # --- end of the example ---")[0]
    assert shown == [textwrap.dedent(tested)]


def _collected() -> tuple[int, int]:
    """Return how many tests the quick loop runs and how many slow tests it leaves out.

    One collection, ``pytest --collect-only -m "not slow"``: it prints the quick loop's count
    and the whole suite's, the slow tests being the rest.
    """
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "pytest",
            "--collect-only",
            "-q",
            "-p",
            "no:cacheprovider",
            "-m",
            "not slow",
            str(ROOT / "tests"),
        ],
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    m = re.search(r"^(\d+)(?:/(\d+))? tests? collected", r.stdout, re.M)
    assert m is not None, r.stdout[-2000:]
    quick = int(m.group(1))
    return quick, int(m.group(2) or quick) - quick


@pytest.mark.slow
def test_the_quoted_test_counts_are_current():
    """docs/development.md's counts of the quick loop and the slow tests, read from the page,
    against what pytest collects: within 10 % (eight branches add tests at once)."""
    text = (ROOT / "docs" / "development.md").read_text(encoding="utf-8")
    quick = re.search(r"The quick loop has (\d+) tests and the\s+slow tests are (\d+) more", text)
    assert quick is not None, "docs/development.md no longer quotes the test counts"
    for quoted, marker, collected in zip(
        quick.groups(), ("not slow", "slow"), _collected(), strict=True
    ):
        assert abs(int(quoted) - collected) <= 0.1 * collected, (marker, quoted, collected)
