"""Which controller software documents a URScript call: the rule behind ``[controller] software``.

A call is accepted for a declared software version no older than the oldest manual page on
which it was read (:data:`SINCE`); an older version is refused. No page read gives a
function's *first* version, so "documented from" is the version of the page read, and an
older controller may or may not have the call: it is not confirmed there, and a program
that stops at an unknown call mid-run leaves the robot and the wire where they were.
"""

from __future__ import annotations

from dataclasses import dataclass

from wirecal.solver.robot import SOFTWARE_PATTERN

_UR = "https://www.universal-robots.com/manuals/EN/HTML"


@dataclass(frozen=True)
class Since:
    """A URScript call and the oldest software on whose manual page it was read.

    The call counts when ``function`` is called (with ``keyword`` given, if set).
    """

    function: str
    keyword: str | None
    version: tuple[int, int]
    what: str
    source: str


SINCE: tuple[Since, ...] = (
    Since(
        "time",
        None,
        (5, 19),
        "time() returning struct(sec, nanosec)",
        f"{_UR}/SW5_19/Content/prod-scriptmanual/G5/time2.htm",
    ),
    Since(
        "encoder_get_tick_count",
        "opt",
        (5, 20),
        'encoder_get_tick_count(i, opt="raw")',
        f"{_UR}/SW5_20/Content/prod-scriptmanual/G5/encoder_get_tick_count_encoder_index.htm "
        "(the 2021 G5 Script Manual lists encoder_get_tick_count(encoder_index) without opt)",
    ),
    Since(
        "encoder_enable_pulse_decode",
        None,
        (5, 0),
        "encoder_enable_pulse_decode(i, type, A, B) on digital inputs 8-11",
        "Universal Robots e-Series Script Directory (PolyScope 5), §14.2, p. 26 (text copy; "
        "its minor version is not stated)",
    ),
)

NEEDED = max(s.version for s in SINCE)
"""The oldest software all of :data:`SINCE` is documented on: 5.20."""


def version_of(software: str) -> tuple[int, ...]:
    """Return "5.20" as (5, 20); ``ValueError`` if it is not a version as numbers."""
    if not SOFTWARE_PATTERN.fullmatch(software):
        raise ValueError(f'{software!r} is not a software version as numbers, e.g. "5.20"')
    return tuple(int(x) for x in software.split("."))


def too_new(function: str, keywords: set[str], version: tuple[int, ...]) -> Since | None:
    """Return the rule a call breaks on software ``version``, or None."""
    for s in SINCE:
        wanted = s.keyword is None or s.keyword in keywords
        if s.function == function and wanted and version[:2] < s.version:
            return s
    return None


_REFUSAL = " is documented from software "


def refusal(s: Since, software: str) -> str:
    """Say why a call is refused on ``software``, naming the call, the version and the page."""
    return (
        f"{s.what}{_REFUSAL}{s.version[0]}.{s.version[1]} on ({s.source}); "
        f"not confirmed on {software}"
    )


def is_refusal(problem: str) -> bool:
    """Tell whether a checker's problem is a :func:`refusal` (not a language error)."""
    return _REFUSAL in problem
