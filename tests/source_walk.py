"""Each source file parsed and walked once a session for the checks that read the sources.

The layer rule (test_layers.py), the import circles (test_import_cycles.py), the length of
functions (test_style.py) and the language keys in shared code (test_conformance.py) each
walked every file's syntax tree: four parses of the same texts. They read what
:func:`walked` keeps of a file instead — its import statements, its functions' extents and
its constants — taken in one walk and kept by the file's text, so a file written anew (the
checks' planted examples) is walked anew. The trees themselves are not kept (a session's
worth of them would be tens of megabytes the garbage collector walks again).
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from functools import cache
from pathlib import Path


@dataclass(frozen=True)
class Walked:
    """What the source checks read of one file, in the order of ``ast.walk``."""

    imports: tuple[ast.Import | ast.ImportFrom, ...]
    functions: tuple[tuple[str, int, int], ...]  # (name, first line, last line) of every def
    constants: frozenset[object]  # the value of every constant


def walked(path: Path) -> Walked:
    """Return what the source checks read of the file ``path`` (module docstring)."""
    return _walk(path.read_text(encoding="utf-8"), str(path))


@cache
def _walk(text: str, filename: str) -> Walked:
    imports: list[ast.Import | ast.ImportFrom] = []
    functions: list[tuple[str, int, int]] = []
    constants: set[object] = set()
    for node in ast.walk(ast.parse(text, filename)):
        if isinstance(node, ast.Import | ast.ImportFrom):
            imports.append(node)
        elif isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            functions.append((node.name, node.lineno, node.end_lineno or node.lineno))
        elif isinstance(node, ast.Constant):
            constants.add(node.value)
    return Walked(tuple(imports), tuple(functions), frozenset(constants))
