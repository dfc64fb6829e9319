"""The public URScript and V+ programs of tests/corpus/: 0 false rejections.

Each entry is linted as its sender sends it (tests/corpus_senders.py) for every software
version it lists; a file not in the corpus cache (tests/corpus_fetch.py fetches them) is
skipped, so the test runs offline.
"""

from __future__ import annotations

import re

import pytest

from wirecal.lang.registry import language

from .corpus_fetch import CORPUS, cached, entries
from .corpus_senders import sent

LANGUAGES = ("urscript", "vplus")
FIELDS = {"repo", "commit", "path", "licence", "kept"}


def _cases():
    for key in LANGUAGES:
        for entry in entries(key):
            for software in entry.get("software", [None]):
                yield pytest.param(key, entry, software, id=f"{entry['path']}-{software}")


@pytest.mark.parametrize("key", LANGUAGES)
def test_every_entry_names_its_repository_commit_path_and_licence(key):
    for entry in entries(key):
        assert FIELDS <= set(entry), entry
        assert re.fullmatch(r"[\w.-]+/[\w.-]+", entry["repo"])
        assert re.fullmatch(r"[0-9a-f]{40}", entry["commit"])
        assert entry["licence"].strip()
        assert isinstance(entry["kept"], bool)
        if entry["kept"]:  # a kept file sits in the corpus with its licence beside it
            folder = CORPUS / key / entry["repo"].replace("/", "__")
            assert (folder / entry["path"]).is_file()
            assert any(p.name.upper().startswith(("LICENSE", "LICENCE")) for p in folder.iterdir())


@pytest.mark.parametrize(("key", "entry", "software"), list(_cases()))
def test_public_programs_lint_clean(key, entry, software):
    path = (
        cached(entry)
        if not entry["kept"]
        else CORPUS / key / entry["repo"].replace("/", "__") / entry["path"]
    )
    if not path.is_file():
        pytest.skip(f"{path}: not in the corpus cache (python tests/corpus_fetch.py)")
    text = path.read_bytes().decode("latin-1")
    lang = language(key)
    short = ".".join(software.split(".")[:2]) if software else None
    for label, program in sent(entry.get("send", "as-is"), text, software):
        where = f"{entry['path']} ({label})"
        if isinstance(program, tuple):  # a program and a file included in it
            files = {"main.script": program[0], where: program[1]}
            assert lang.lint_files(files, short) == [], label
        else:
            assert lang.lint(program, where, short) == [], label
