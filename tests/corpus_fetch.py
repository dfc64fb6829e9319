"""The corpus of public controller programs: its lists, its cache, and the script filling it.

    python tests/corpus_fetch.py      # into $WIRECAL_CORPUS or ~/.cache/wirecal-corpus

``tests/corpus/<language>/SOURCES.toml`` lists public programs by others, one format for
every language; each ``[[program]]``:

- ``repo``, ``commit``, ``path``: where the file is on GitHub (the commit: 40 hex digits);
- ``licence``: as the repository states it;
- ``kept``: always false. No program text by others is in this repository's commits,
  whatever its licence; this script fetches each file at its commit from
  raw.githubusercontent.com into ``<cache>/<owner>__<repo>/<commit>/<path>`` (what is there
  already is kept), and tests/test_corpus.py lints what the cache holds;
- ``send`` (default ``"as-is"``): how its sender fills the file in before the controller
  reads it (tests/corpus_senders.py); ``software``: the versions it is linted for;
- ``tasks``: the tasks the file is loaded into (RAPID); the files sharing one are linted
  together, as loaded (none: the file alone, in each form its sender sends);
- ``external_calls``: the task calls routines of a file wirecal cannot read (an encrypted
  module), so an unknown routine name is not a problem;
- ``refused``: the checker refuses the file, and why that is right.
"""

from __future__ import annotations

import os
import sys
import tomllib
import urllib.parse
import urllib.request
from pathlib import Path

CORPUS = Path(__file__).resolve().parent / "corpus"


def cache_dir() -> Path:
    """Return the corpus cache: $WIRECAL_CORPUS, else ~/.cache/wirecal-corpus."""
    return Path(os.environ.get("WIRECAL_CORPUS") or Path.home() / ".cache" / "wirecal-corpus")


def languages() -> list[str]:
    """Return the languages with a SOURCES.toml."""
    return sorted(p.parent.name for p in CORPUS.glob("*/SOURCES.toml"))


def entries(language: str) -> list[dict]:
    """Return the [[program]] entries of a language's SOURCES.toml."""
    with open(CORPUS / language / "SOURCES.toml", "rb") as f:
        return list(tomllib.load(f)["program"])


def cached(entry: dict) -> Path:
    """Return where an entry's file is (or would be) in the cache."""
    owner_repo = entry["repo"].replace("/", "__")
    return cache_dir() / owner_repo / entry["commit"] / entry["path"]


def main() -> int:
    """Fetch every entry not in the cache yet; return 1 when one could not be fetched."""
    failed = 0
    for language in languages():
        for entry in entries(language):
            target = cached(entry)
            if target.is_file():
                continue
            url = f"https://raw.githubusercontent.com/{entry['repo']}/{entry['commit']}/"
            url += urllib.parse.quote(entry["path"])
            try:
                with urllib.request.urlopen(url, timeout=30) as got:
                    data = got.read()
            except OSError as exc:
                print(f"{url}: {exc}", file=sys.stderr)
                failed += 1
                continue
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
            print(f"fetched {target}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
