"""No import circle among wirecal's modules (issue 25 item 3).

A circle (a imports b, b imports a, directly or round several modules) makes the import
order decide what exists, and pure geometry end up depending on plan-level code. Every
import counts, as in tests/test_layers.py: at the top of a module, inside a function (a
lazy import still closes a circle) and for type checking only. ``from package import
name`` counts as an import of ``package.name`` when that is a module, else of ``package``.
"""

from __future__ import annotations

import ast
from graphlib import CycleError, TopologicalSorter
from pathlib import Path

import pytest

from .conftest import ROOT
from .source_walk import walked
from .test_layers import FOLDERS, module_name


def _targets(node: ast.Import | ast.ImportFrom, importer: str, is_package: bool) -> list[str]:
    """Return the dotted names an import statement may load, relative imports resolved."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = node.module or ""
    if node.level:
        package = importer.split(".") if is_package else importer.split(".")[:-1]
        package = package[: len(package) - node.level + 1]
        base = ".".join([*package, *([node.module] if node.module else [])])
    return [base, *(f"{base}.{a.name}" for a in node.names)]


def import_graph(root: Path) -> dict[str, set[str]]:
    """Return each wirecal module of ``root``'s sources → the wirecal modules it imports."""
    paths = {
        module_name(root, path): path
        for folder in FOLDERS
        for path in sorted((root / folder).rglob("*.py"))
    }
    graph: dict[str, set[str]] = {}
    for importer, path in paths.items():
        graph[importer] = set()
        for node in walked(path).imports:
            names = _targets(node, importer, path.name == "__init__.py")
            base, members = (names[0], names[1:]) if isinstance(node, ast.ImportFrom) else ("", [])
            found = [n for n in (members or names) if n in paths]
            if isinstance(node, ast.ImportFrom) and len(found) < len(members) and base in paths:
                found.append(base)  # a name defined in the package's __init__
            graph[importer].update(n for n in found if n != importer)
    return graph


def first_cycle(root: Path) -> list[str] | None:
    """Return one import circle among ``root``'s modules (first module repeated), or None."""
    try:
        TopologicalSorter(import_graph(root)).prepare()
    except CycleError as exc:
        return list(exc.args[1])
    return None


def test_no_import_cycle():
    cycle = first_cycle(ROOT)
    assert cycle is None, "import circle: " + " → ".join(reversed(cycle or []))


def _plant(tmp_path: Path, files: dict[str, str]) -> Path:
    for name in FOLDERS:
        (tmp_path / name).mkdir()
    for rel, source in files.items():
        (tmp_path / rel).write_text(source, encoding="utf-8")
    return tmp_path


@pytest.mark.parametrize(
    ("files", "circle"),
    [
        (  # two modules, at the top
            {
                "solver/a.py": "from wirecal.solver.b import f\n",
                "solver/b.py": "from wirecal.solver import a\n",
            },
            {"wirecal.solver.a", "wirecal.solver.b"},
        ),
        (  # three modules, closed by a lazy import and one for type checking only
            {
                "solver/a.py": "import wirecal.solver.b\n",
                "solver/b.py": "if TYPE_CHECKING:\n    from wirecal.solver.c import C\n",
                "solver/c.py": "def f():\n    from wirecal.solver.a import g\n",
            },
            {"wirecal.solver.a", "wirecal.solver.b", "wirecal.solver.c"},
        ),
        (  # a relative import and a name from a package's __init__
            {
                "gen/__init__.py": "from .a import x\n",
                "gen/a.py": "from wirecal.gen import y\n",
            },
            {"wirecal.gen", "wirecal.gen.a"},
        ),
        (  # a chain is no circle
            {
                "solver/a.py": "from wirecal.solver.b import f\nimport numpy\n",
                "solver/b.py": "from wirecal.solver import c\n",
                "solver/c.py": "from wirecal import __version__\n",
            },
            set(),
        ),
    ],
)
def test_the_check_finds_planted_circles(tmp_path, files, circle):
    found = first_cycle(_plant(tmp_path, files))
    assert set(found or []) == circle
    if found:
        assert found[0] == found[-1]
