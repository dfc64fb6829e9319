"""The corpus of public controller programs: read SOURCES.toml, group files into tasks, lint.

``tests/corpus/<language>/SOURCES.toml`` lists public programs ([[program]]: repo, commit,
path, licence, kept; optional tasks, external_calls, refused). Kept files are here, under
``<owner>__<repo>/<path>`` (tests/test_corpus.py lints them); run this file to fetch the
others with git and lint them too::

    python tests/corpus/check_remote.py [LANGUAGE ...]

It prints one line per task and exits 0 when every file lints as its entry says (clean, or
refused for the reason given), 1 otherwise; a repository that cannot be fetched (no
network) is skipped with a line saying so.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from wirecal.lang.registry import language

CORPUS = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Unit:
    """Files checked together: one task's, or one file alone; ``refused``: expect problems."""

    language: str
    name: str
    entries: tuple[dict, ...]
    external_calls: bool
    refused: bool


def entries(key: str) -> list[dict]:
    """Return the [[program]] entries of a language's SOURCES.toml."""
    with open(CORPUS / key / "SOURCES.toml", "rb") as f:
        return list(tomllib.load(f)["program"])


def languages() -> list[str]:
    """Return the languages with a SOURCES.toml."""
    return sorted(p.parent.name for p in CORPUS.glob("*/SOURCES.toml"))


def units(key: str) -> list[Unit]:
    """Group a language's entries into the units that are checked together."""
    tasks: dict[tuple[str, str, str], list[dict]] = {}
    alone: list[Unit] = []
    for e in entries(key):
        if e.get("refused") or not e.get("tasks"):
            name = f"{e['repo']}@{e['commit'][:7]}/{e['path']}"
            alone.append(Unit(key, name, (e,), bool(e.get("external_calls")), "refused" in e))
            continue
        for task in e["tasks"]:
            tasks.setdefault((e["repo"], e["commit"], task), []).append(e)
    together = [
        Unit(
            key,
            f"{repo}@{commit[:7]} {task}",
            tuple(group),
            any(e.get("external_calls") for e in group),
            False,
        )
        for (repo, commit, task), group in tasks.items()
    ]
    return together + alone


def kept_path(key: str, e: dict) -> Path:
    """Return where a kept entry's file is."""
    return CORPUS / key / e["repo"].replace("/", "__") / e["path"]


def lint(unit: Unit, read: Callable[[dict], str]) -> list[str]:
    """Lint a unit's files together; return the problems."""
    texts = {f"{e['repo']}@{e['commit'][:7]}/{e['path']}": read(e) for e in unit.entries}
    return language(unit.language).lint_files(texts, external_calls=unit.external_calls)


def _fetch(repo: str, commit: str, into: Path) -> bool:
    """Fetch one commit of a GitHub repository into ``into``; False when that fails."""
    git = ["git", "-C", str(into)]
    try:
        subprocess.run(["git", "init", "-q", str(into)], check=True, capture_output=True)
        subprocess.run(
            [*git, "fetch", "-q", "--depth", "1", f"https://github.com/{repo}", commit],
            check=True,
            capture_output=True,
            timeout=300,
        )
    except (subprocess.CalledProcessError, subprocess.TimeoutExpired, OSError):
        return False
    return True


def _reader(root: Path) -> Callable[[dict], str]:
    def read(e: dict) -> str:
        where = root / e["repo"].replace("/", "__")
        shown = subprocess.run(
            ["git", "-C", str(where), "show", f"{e['commit']}:{e['path']}"],
            check=True,
            capture_output=True,
        )
        return shown.stdout.decode("latin-1")

    return read


def main(keys: list[str]) -> int:
    """Fetch and lint every unit with a file not kept; return the exit status."""
    failed = 0
    with tempfile.TemporaryDirectory() as tmp:
        root, fetched = Path(tmp), {}
        for key in keys or languages():
            for unit in units(key):
                if all(e["kept"] for e in unit.entries):
                    continue
                repos = {(e["repo"], e["commit"]) for e in unit.entries}
                for repo, commit in repos - set(fetched):
                    fetched[repo, commit] = _fetch(repo, commit, root / repo.replace("/", "__"))
                if not all(fetched[r] for r in repos):
                    print(f"skipped (cannot fetch): {unit.name}")
                    continue
                problems = lint(unit, _reader(root))
                ok = bool(problems) == unit.refused
                failed += not ok
                state = "refused as listed" if unit.refused else "clean"
                print(f"{'ok' if ok else 'FAILED'} {state if ok else ''}: {unit.name}")
                if not ok:
                    print("\n".join(f"    {p}" for p in problems) or "    (no problems)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
