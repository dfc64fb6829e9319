"""The layer rule of docs/architecture.md: each layer imports only the layers below it.

    solver  ←  lang  ←  formats←  gen, twin  ←  app  ←  wirecal (the API)  ←  cli

``lang`` holds the controller languages' front ends and their registry; ``gen`` and ``twin``
both import it and are peers: neither imports the other. Every import counts, at the top
of a module or inside a function (a lazy import is still a dependency), and so do imports
for type checking only. ``from wirecal import __version__`` is allowed everywhere: the
package root is imported before any of its parts anyway.

There are no exceptions (the last, the simulation writing the log's text, went with
issue 33): the test fails on any violation.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable
from pathlib import Path

import pytest

from .conftest import ROOT
from .source_walk import walked

FOLDERS = {
    "solver": "wirecal.solver",
    "lang": "wirecal.lang",
    "formats": "wirecal.formats",
    "gen": "wirecal.gen",
    "twin": "wirecal.twin",
    "app": "wirecal.app",
    "cli": "wirecal.cli",
    "wirecal": "wirecal",
}
"""Source folder → the package it installs as (the links in wirecal/)."""

LAYERS = {
    "wirecal.solver": 0,
    "wirecal.lang": 1,
    "wirecal.formats": 2,
    "wirecal.gen": 3,
    "wirecal.twin": 3,
    "wirecal.app": 4,
    "wirecal": 5,
    "wirecal.cli": 6,
}
"""Each layer's package and its height: a module imports only strictly lower layers."""


def layer(module: str) -> str | None:
    """Return the layer package of ``module`` (its longest listed prefix), None if foreign."""
    parts = module.split(".")
    for n in range(len(parts), 0, -1):
        if ".".join(parts[:n]) in LAYERS:
            return ".".join(parts[:n])
    return None


def module_name(root: Path, path: Path) -> str:
    """Return the installed name of the source file ``path`` under ``root``."""
    rel = path.relative_to(root).with_suffix("")
    parts = [FOLDERS[rel.parts[0]], *rel.parts[1:]]
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported(statements: Iterable[ast.Import | ast.ImportFrom]) -> set[str]:
    """Return every ``wirecal`` module a file's import ``statements`` (all of them) import."""
    names: set[str] = set()
    for node in statements:
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "wirecal" and [a.name for a in node.names] == ["__version__"]:
                continue
            names.add(node.module)
    return {n for n in names if n == "wirecal" or n.startswith("wirecal.")}


def violations(root: Path) -> set[tuple[str, str]]:
    """Return every (importer, imported) pair of ``root``'s sources that breaks the rule."""
    found = set()
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            importer = module_name(root, path)
            own = layer(importer)
            assert own is not None, path
            for target in imported(walked(path).imports):
                other = layer(target)
                if other is not None and other != own and LAYERS[other] >= LAYERS[own]:
                    found.add((importer, target))
    return found


def test_layers_import_only_downwards():
    found = sorted(violations(ROOT))
    assert not found, f"imports against the layer order (docs/architecture.md): {found}"


def test_every_source_folder_is_checked():
    """Each top-level package folder is one layer: none escapes the rule, none hides in another."""
    packages = {
        p.parent.name
        for p in ROOT.glob("*/__init__.py")
        if p.parent.name not in ("tests", "templates", "examples")
    }
    assert packages == set(FOLDERS)
    assert set(LAYERS) == set(FOLDERS.values()), "each layer is one top-level folder"


@pytest.mark.parametrize(
    ("folder", "source", "expected"),
    [
        (
            "solver",
            "from wirecal.cli.main import main\n",
            {("wirecal.solver.x", "wirecal.cli.main")},
        ),
        (
            "solver",
            "def f():\n    import wirecal.app.demo\n",
            {("wirecal.solver.x", "wirecal.app.demo")},
        ),
        (
            "gen",
            "from wirecal.twin.machine import Cell\n",
            {("wirecal.gen.x", "wirecal.twin.machine")},
        ),
        (
            "twin",
            "from wirecal.gen.tables import build_tables\n",
            {("wirecal.twin.x", "wirecal.gen.tables")},
        ),
        ("app", "import wirecal\n", {("wirecal.app.x", "wirecal")}),
        ("gen", "from wirecal import __version__\n", set()),
        ("cli", "from wirecal.app.demo import run_demo\nimport numpy\n", set()),
        ("twin", "from wirecal.formats.log import parse_log\n", set()),
        (
            "solver",
            "from wirecal.formats.log import parse_log\n",
            {("wirecal.solver.x", "wirecal.formats.log")},
        ),
        ("gen", "from wirecal.lang.vplus.parser import parse_module\n", set()),
        (
            "lang",
            "from wirecal.formats.robot_file import load_robot\n",
            {("wirecal.lang.x", "wirecal.formats.robot_file")},
        ),
    ],
)
def test_the_rule_catches_upward_imports(tmp_path, folder, source, expected):
    """The checker on a planted file: upward, sideways (gen ↔ twin) and lazy imports."""
    for name in FOLDERS:
        (tmp_path / name).mkdir()
    (tmp_path / folder / "x.py").write_text(source, encoding="utf-8")
    assert violations(tmp_path) == expected
