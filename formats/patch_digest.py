"""A patch's integrity: one digest per entry, so an edited patch is refused naming the edit.

:func:`seal` appends a ``[digest]`` table to a patch's text: for each entry, the first 16
hex digits of the sha256 of its parsed value (each top-level key; each sub-table of a table
of tables, e.g. ``parameters.a1``; any other table whole). It is computed from the values,
not the bytes, so it is generic over every table a patch holds and blind to comments and
layout. :func:`edits` compares a patch read back with its digests: an entry deleted
(``plausibility``, ``unchecked``), added, or changed (an offset moved together with its
value) is named. It guards against hand edits, not against forgery.
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from typing import Any

DIGEST_TABLE = "digest"
_HEADER = f"\n[{DIGEST_TABLE}]\n"


def _entries(data: dict[str, Any]) -> dict[str, Any]:
    """Return the patch's entries by name, in file order, without the digest table."""
    out: dict[str, Any] = {}
    for key, value in data.items():
        if key == DIGEST_TABLE:
            continue
        if isinstance(value, dict) and value and all(isinstance(v, dict) for v in value.values()):
            out.update({f"{key}.{sub}": v for sub, v in value.items()})
        else:
            out[key] = value
    return out


def _digest(value: Any) -> str:
    text = json.dumps(value, sort_keys=True, ensure_ascii=False, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


def seal(text: str) -> str:
    """Return the patch ``text`` with its ``[digest]`` table (replaced if it has one)."""
    body = text.split(_HEADER, 1)[0].rstrip("\n") + "\n"
    lines = [
        "",
        f"[{DIGEST_TABLE}]",
        "# sha256 (16 hex digits) of each entry: wirecal refuses a patch edited by hand",
    ]
    lines += [
        f"{json.dumps(k, ensure_ascii=False)} = {json.dumps(_digest(v))}"
        for k, v in _entries(tomllib.loads(body)).items()
    ]
    return body + "\n".join(lines) + "\n"


def edits(data: dict[str, Any]) -> list[tuple[str, str]]:
    """Return (entry, what happened to it) for each edit since :func:`seal`; [] if none."""
    recorded = data.get(DIGEST_TABLE)
    if not isinstance(recorded, dict):
        return [(DIGEST_TABLE, "missing: written before patches carried one, or edited")]
    entries = _entries(data)
    out = [(key, "deleted") for key in recorded if key not in entries]
    out += [(key, "added") for key in entries if key not in recorded]
    out += [
        (key, "changed")
        for key, value in entries.items()
        if key in recorded and recorded[key] != _digest(value)
    ]
    return out
