"""Which controller software documents a URScript call: the rule behind ``[controller] software``.

A call is accepted for a declared software version of a product line (the major version: 3
CB3, 5 e-Series, 10 PolyScope X) no older than the oldest page of that line on which it was
read (:data:`SINCE`); an older version, or a line on whose pages it was not read, is
refused. No page read gives a function's *first* version, so "documented from" is the
version of the page read, and an older controller may or may not have the call: it is not
confirmed there, and a program that stops at an unknown call mid-run leaves the robot and
the wire where they were.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from wirecal.solver.robot import SOFTWARE_PATTERN

_UR = "https://www.universal-robots.com/manuals/EN/HTML"


@dataclass(frozen=True)
class Since:
    """A URScript call and, per product line, the oldest software whose page documents it.

    The call counts when ``function`` is called (with ``keyword`` given, if set);
    ``versions`` maps a major version to the oldest (major, minor) read for it.
    """

    function: str
    keyword: str | None
    versions: Mapping[int, tuple[int, int]]
    what: str
    source: str

    def documented(self) -> str:
        """Say where the call is documented from: "3.8 (CB3), 5.2 (e-Series)"."""
        return ", ".join(f"{v[0]}.{v[1]} ({LINES[m]})" for m, v in sorted(self.versions.items()))


LINES = {3: "CB3", 5: "e-Series", 10: "PolyScope X"}
"""The product lines by major version (UR's software numbering)."""

CONVEYOR_GUIDE = (
    "https://www.universal-robots.com/articles/ur/programming/"
    "new-conveyor-tracking-guide-cb3-38-and-e-series-52 (software at least 3.8 on CB3 or 5.2 "
    "on e-Series; the controllers decode up to 40 kHz)"
)
"""UR's conveyor tracking guide: the encoder calls on CB3 from 3.8 and on e-Series from 5.2."""

PAYLOAD_ARTICLE = (
    "https://www.universal-robots.com/articles/ur/programming/"
    "how-to-change-payload-and-center-of-gravity-settings-using-urscript (set_payload(mass, "
    "CoG): mass in kg, CoG [Cx, Cy, Cz] in m; valid for CB3 3.3 onwards and every e-Series "
    "version)"
)
"""UR's article on setting the active payload from URScript during a program."""

PAYLOAD_READ = (
    "Universal Robots e-Series Script Directory (PolyScope 5), text copy, §15.20 "
    "get_target_payload() (the active payload's mass, kg) and §15.21 get_target_payload_cog() "
    "(its CoG [CoGx, CoGy, CoGz], m, from the tool flange), p. 57; the copy does not state "
    "its software version (it deprecates set_payload 'since SW 5.10.0', so 5.10 or later): "
    "taken as from 5.20, the oldest the e-Series programs need; read on no CB3 page"
)
"""Where reading the active payload is documented (e-Series only)."""

SINCE: tuple[Since, ...] = (
    Since(
        "time",
        None,
        {5: (5, 19)},
        "time() returning struct(sec, nanosec)",
        f"{_UR}/SW5_19/Content/prod-scriptmanual/G5/time2.htm",
    ),
    Since(
        "encoder_get_tick_count",
        "opt",
        {5: (5, 20)},
        'encoder_get_tick_count(i, opt="raw")',
        f"{_UR}/SW5_20/Content/prod-scriptmanual/G5/encoder_get_tick_count_encoder_index.htm "
        "(the 2021 G5 Script Manual lists encoder_get_tick_count(encoder_index) without opt)",
    ),
    Since(
        "encoder_get_tick_count",
        None,
        {3: (3, 8), 5: (5, 2)},
        "encoder_get_tick_count(encoder_index), the filtered count",
        CONVEYOR_GUIDE,
    ),
    Since(
        "encoder_enable_pulse_decode",
        None,
        {3: (3, 8), 5: (5, 2)},
        "encoder_enable_pulse_decode(i, type, A, B) on digital inputs 8-11",
        CONVEYOR_GUIDE,
    ),
    Since("set_payload", None, {3: (3, 3), 5: (5, 0)}, "set_payload(mass, CoG)", PAYLOAD_ARTICLE),
    Since("get_target_payload", None, {5: (5, 20)}, "get_target_payload()", PAYLOAD_READ),
    Since("get_target_payload_cog", None, {5: (5, 20)}, "get_target_payload_cog()", PAYLOAD_READ),
)


def needed(major: int) -> tuple[int, int]:
    """Return the oldest software of a line on which every call of :data:`SINCE` for it is read."""
    return max(s.versions[major] for s in SINCE if major in s.versions)


NEEDED = needed(5)
"""The oldest e-Series software all of :data:`SINCE` is documented on: 5.20."""


def version_of(software: str) -> tuple[int, ...]:
    """Return "5.20" as (5, 20); ``ValueError`` if it is not a version as numbers."""
    if not SOFTWARE_PATTERN.fullmatch(software):
        raise ValueError(f'{software!r} is not a software version as numbers, e.g. "5.20"')
    return tuple(int(x) for x in software.split("."))


def too_new(function: str, keywords: set[str], version: tuple[int, ...]) -> Since | None:
    """Return the rule a call breaks on software ``version``, or None."""
    for s in SINCE:
        wanted = s.keyword is None or s.keyword in keywords
        oldest = s.versions.get(version[0])
        if s.function == function and wanted and (oldest is None or version[:2] < oldest):
            return s
    return None


_REFUSAL = " is documented from software "


def refusal(s: Since, software: str) -> str:
    """Say why a call is refused on ``software``, naming the call, the version and the page."""
    return f"{s.what}{_REFUSAL}{s.documented()} on ({s.source}); not confirmed on {software}"


def is_refusal(problem: str) -> bool:
    """Tell whether a checker's problem is a :func:`refusal` (not a language error)."""
    return _REFUSAL in problem
