"""Public controller programs of every language lint as their corpus entry says.

tests/corpus/<language>/SOURCES.toml lists them (the format: tests/corpus_fetch.py). A
task's files are linted together, a file alone in each form its sender sends it
(tests/corpus_senders.py) for each software version listed: clean, or refused when the
entry says so (0 false rejections). The files are read from the corpus cache that
tests/corpus_fetch.py fills; a unit with a file not there is skipped, saying which, so the
test runs offline. Nothing of the corpus is kept in this repository.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import pytest

from wirecal.lang.registry import language

from .corpus_fetch import CORPUS, cache_dir, cached, entries, languages
from .corpus_senders import sent


@dataclass(frozen=True)
class Unit:
    """Files linted together: one task's, or one file alone; ``refused``: expect problems."""

    language: str
    name: str
    entries: tuple[dict, ...]
    external_calls: bool
    refused: bool


def source_name(e: dict) -> str:
    """Return the name problems give a file: repository, short commit and path."""
    return f"{e['repo']}@{e['commit'][:7]}/{e['path']}"


def units(key: str) -> list[Unit]:
    """Group a language's entries into the units that are linted together."""
    tasks: dict[tuple[str, str, str], list[dict]] = {}
    alone: list[Unit] = []
    for e in entries(key):
        if e.get("refused") or not e.get("tasks"):
            external = bool(e.get("external_calls"))
            alone.append(Unit(key, source_name(e), (e,), external, "refused" in e))
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


def forms(unit: Unit, software: str | None) -> list[tuple[str, dict[str, str]]]:
    """Return (label, files) of each form the unit's files reach the controller in."""
    texts = {source_name(e): cached(e).read_bytes().decode("latin-1") for e in unit.entries}
    if len(texts) > 1:
        return [("as loaded", texts)]
    ((where, text),) = texts.items()
    out = []
    for label, program in sent(unit.entries[0].get("send", "as-is"), text, software):
        if isinstance(program, tuple):  # a program and the file included in it
            out.append((label, {"main.script": program[0], where: program[1]}))
        else:
            out.append((label, {where: program}))
    return out


CASES = [
    pytest.param(unit, software, id=f"{unit.name}-{software}")
    for key in languages()
    for unit in units(key)
    for software in unit.entries[0].get("software", [None])
]


@pytest.mark.slow  # with the cache full: 45 s on one core; the largest modules take 2-7 s
@pytest.mark.parametrize(("unit", "software"), CASES)
def test_public_programs_lint_as_listed(unit: Unit, software: str | None) -> None:
    missing = [cached(e) for e in unit.entries if not cached(e).is_file()]
    if missing:
        pytest.skip(
            f"{len(missing)} of {len(unit.entries)} files not in the corpus cache "
            f"{cache_dir()} (first: {missing[0]}): python tests/corpus_fetch.py fetches them"
        )
    short = ".".join(software.split(".")[:2]) if software else None
    for label, files in forms(unit, software):
        problems = language(unit.language).lint_files(
            files, short, external_calls=unit.external_calls
        )
        if unit.refused:
            reason = unit.entries[0]["refused"]
            assert problems, f"{unit.name} ({label}): listed as refused ({reason}), lints clean"
        else:
            assert problems == [], f"{unit.name} ({label})"


@pytest.mark.parametrize("key", languages())
def test_every_entry_is_complete_and_none_is_kept(key: str) -> None:
    for e in entries(key):
        assert {"repo", "commit", "path", "licence", "kept"} <= set(e), e
        assert re.fullmatch(r"[\w.-]+/[\w.-]+", e["repo"]), e
        assert re.fullmatch(r"[0-9a-f]{40}", e["commit"]), e
        assert e["licence"].strip(), e
        assert e["kept"] is False, f"{e}: program text by others is not committed"
        if e.get("tasks"):  # files of a task are read as loaded, for one software
            assert e.get("send", "as-is") == "as-is", e
            assert "software" not in e, e
    assert [p.name for p in (CORPUS / key).iterdir()] == ["SOURCES.toml"]


def test_the_rapid_corpus_holds_a_task_of_several_modules() -> None:
    """abb_driver's ROS_motion.mod is linted with its task's three .sys modules."""
    motion = [u for u in units("rapid") if u.name.endswith(" ROS_motion")]
    assert [len(u.entries) for u in motion] == [4]
