"""The V+ keyword table (``keywords.csv``).

Every keyword the V+ manuals name, with its kind and the page it was read on.

A keyword cannot be used as a program, variable or parameter name (V+ Language User's
Guide v17 p. 99). The kinds are those of the manuals: instruction, function, operator,
system constant, switch, system parameter, monitor command, and "word" for the words
that only appear inside other statements (THEN, TO, ALWAYS, ...). One name may have
several kinds (HERE is an instruction and a function). Each row cites the manual page
(or, marked so, the third-party program or "unconfirmed") it rests on.

Monitor commands (typed at the terminal, not program steps) are listed but not treated
as reserved names: whether p. 99's rule covers them is unconfirmed, and rejecting a valid
name is as wrong as accepting an invalid one. Nor are the names of string functions
reserved for string variables: Adept's own ROS driver (ros.v2, 2012, ACE 3.1.3.10;
ros-industrial-attic/swri-ros-pkg adept/adept_common/V+/ros.v2 line 153) declares
``AUTO … $chr`` and uses it beside ``$CHR(…)``.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import cache
from importlib import resources


@dataclass(frozen=True)
class Keyword:
    """A V+ keyword: its name, kinds and the pages they were read on."""

    name: str  # lower case, with its $ or # prefix
    kinds: tuple[str, ...]
    sources: tuple[str, ...]

    def describe(self) -> str:
        """``instruction; User's Guide p. 99`` — kinds and the first source."""
        return f"{', '.join(self.kinds)}; {self.sources[0].split(' | ')[0]}"


@cache
def keywords() -> dict[str, Keyword]:
    """Return the table, keyed by lower-case name."""
    text = resources.files(__package__).joinpath("keywords.csv").read_text(encoding="utf-8")
    kinds: dict[str, list[str]] = {}
    sources: dict[str, list[str]] = {}
    for row in csv.DictReader(text.splitlines()):
        name = row["name"].strip().lower()
        for store, value in ((kinds, row["kind"].strip()), (sources, row["source"].strip())):
            seen = store.setdefault(name, [])
            if value not in seen:
                seen.append(value)
    return {n: Keyword(n, tuple(kinds[n]), tuple(sources[n])) for n in kinds}


#: kinds of keyword that are not reserved as names
NOT_RESERVED = ("monitor command",)

#: keywords a public controller-loaded program uses as a name, and where: the rule of p. 99
#: is not applied to them (rejecting a name a controller loads is as wrong as accepting one
#: it refuses)
USED_AS_NAMES = {
    "stop": "BenjaminSchellenbeck/adept_experimental@bdd7478 adept_driver/V+/adept_ros.v2 "
    "line 344, 'stop = STATE(4) BAND 4' (created in ACE 3.6.3.2)",
}


def keyword(name: str) -> Keyword | None:
    """Return the keyword a name collides with, if it is reserved."""
    k = keywords().get(name.lower())
    if k is None or all(kind in NOT_RESERVED for kind in k.kinds) or k.name in USED_AS_NAMES:
        return None
    if name.startswith("$") and k.kinds == ("function",):
        return None  # $chr is a string variable in Adept's ros.v2
    return k


def is_kind(name: str, *kinds: str) -> bool:
    """Tell whether ``name`` is a keyword of one of ``kinds``."""
    k = keywords().get(name.lower())
    return k is not None and any(kind in k.kinds for kind in kinds)


#: kinds of keyword that may be read as a value where a variable could stand
#: (``x = PI``, ``IF TRUE THEN``, ``SET t = HERE``, ``x = TIMER(1)``)
VALUE_KINDS = ("function", "system constant", "system parameter", "switch")
