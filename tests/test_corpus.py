"""Public controller programs lint as their corpus entry says: kept files, every language.

tests/corpus/<language>/SOURCES.toml lists them; the kept ones (redistributable) are here and
are linted a task at a time (files of one task together); the rest are fetched and linted by
tests/corpus/check_remote.py when the network allows.
"""

from __future__ import annotations

import pytest

from tests.corpus.check_remote import Unit, entries, kept_path, languages, lint, units

KEPT = [u for key in languages() for u in units(key) if all(e["kept"] for e in u.entries)]


@pytest.mark.parametrize("unit", KEPT, ids=[u.name for u in KEPT])
def test_kept_programs_lint_as_listed(unit: Unit) -> None:
    def read(e: dict) -> str:
        return kept_path(unit.language, e).read_bytes().decode("latin-1")

    problems = lint(unit, read)
    if unit.refused:
        assert problems, f"{unit.name}: listed as refused, but lints clean"
    else:
        assert problems == []


@pytest.mark.parametrize("key", languages())
def test_every_entry_is_complete_and_kept_ones_carry_their_licence(key: str) -> None:
    for e in entries(key):
        assert {"repo", "commit", "path", "licence", "kept"} <= set(e), e
        assert len(e["commit"]) == 40, e
        if e["kept"]:
            path = kept_path(key, e)
            assert path.is_file(), path
            owner = path.parents[len(e["path"].split("/")) - 1]
            assert any(owner.glob("LICENSE*")), f"no licence beside {owner}"
            assert e["licence"] != "none stated", e


def test_the_rapid_corpus_holds_a_task_of_several_modules() -> None:
    """abb_driver's ROS_motion.mod is checked with its task's .sys modules."""
    motion = [u for u in units("rapid") if u.name.endswith(" ROS_motion")]
    assert [len(u.entries) for u in motion] == [4]
