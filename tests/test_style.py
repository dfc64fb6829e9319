"""Style rules of docs/development.md that a machine can check.

No function is over 60 lines (issue 33): from its ``def`` line to its last line, the
docstring included, in every module of the package folders and of ``bench/``. A longer one
is split into well-named steps with one purpose each.
"""

from __future__ import annotations

from functools import cache

from .conftest import ROOT
from .source_walk import walked
from .test_layers import FOLDERS

MAX_LINES = 60

STILL_LONG: set[str] = set()
"""Functions over MAX_LINES allowed for now, by name."""


@cache
def _long_functions() -> dict[str, list[str]]:
    """Return function name → where each over MAX_LINES is (``path:line: n lines``).

    Walked once per session: two tests read it, and nothing changes the sources meanwhile.
    """
    found: dict[str, list[str]] = {}
    for folder in [*FOLDERS, "bench"]:
        for path in sorted((ROOT / folder).rglob("*.py")):
            for name, first, last in walked(path).functions:
                n = last - first + 1
                if n > MAX_LINES:
                    where = f"{path.relative_to(ROOT)}:{first}: {name}, {n} lines"
                    found.setdefault(name, []).append(where)
    return found


def test_no_function_is_over_60_lines():
    found = _long_functions()
    new = [w for name, where in sorted(found.items()) if name not in STILL_LONG for w in where]
    assert not new, f"split these into steps of at most {MAX_LINES} lines: " + "; ".join(new)


def test_the_allowed_long_functions_are_still_long():
    """The allow-list only shrinks: a function split since is taken off it."""
    gone = sorted(STILL_LONG - set(_long_functions()))
    assert not gone, f"no longer over {MAX_LINES} lines: remove {gone} from STILL_LONG"


def test_the_walk_sees_the_package_and_the_benches():
    """The rule would pass vacuously if the walk missed the folders (links are not followed)."""
    seen = {
        p.relative_to(ROOT).parts[0] for f in [*FOLDERS, "bench"] for p in (ROOT / f).rglob("*.py")
    }
    assert seen == {*FOLDERS, "bench"}
    assert len(list((ROOT / "solver").rglob("*.py"))) > 50
