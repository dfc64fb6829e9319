"""Fetch the corpus's public programs into the corpus cache (run it when the network allows).

    python tests/corpus_fetch.py      # into $WIRECAL_CORPUS or ~/.cache/wirecal-corpus

Each entry of tests/corpus/<language>/SOURCES.toml is fetched at its commit from
raw.githubusercontent.com into ``<cache>/<owner>__<repo>/<commit>/<path>``; what is there
already is kept. tests/test_corpus_urvp.py lints what the cache holds.
"""

from __future__ import annotations

import os
import sys
import tomllib
import urllib.request
from pathlib import Path

CORPUS = Path(__file__).resolve().parent / "corpus"


def cache_dir() -> Path:
    """Return the corpus cache: $WIRECAL_CORPUS, else ~/.cache/wirecal-corpus."""
    return Path(os.environ.get("WIRECAL_CORPUS") or Path.home() / ".cache" / "wirecal-corpus")


def entries(language: str) -> list[dict]:
    """Return the entries of a language's SOURCES.toml."""
    return tomllib.loads((CORPUS / language / "SOURCES.toml").read_text())["entry"]


def cached(entry: dict) -> Path:
    """Return where an entry's file is (or would be) in the cache."""
    owner_repo = entry["repo"].replace("/", "__")
    return cache_dir() / owner_repo / entry["commit"] / entry["path"]


def main() -> int:
    failed = 0
    for language in sorted(p.name for p in CORPUS.iterdir() if (p / "SOURCES.toml").is_file()):
        for entry in entries(language):
            target = cached(entry)
            if target.is_file():
                continue
            url = f"https://raw.githubusercontent.com/{entry['repo']}/{entry['commit']}/"
            url += urllib.request.quote(entry["path"])
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
