"""What each controller language's programs read of the encoder, by robot-file language name.

The encoder interface is the first of :data:`wirecal.solver.robot.INTERFACES` (the robot
file's default too); the counter width is the one the backend's programs read.
"""

from __future__ import annotations

from wirecal.gen.urscript.program import RAW_COUNTER_BITS
from wirecal.gen.vplus.program import BELT_COUNTER_BITS
from wirecal.lang.rapid.module import GROUP_COUNTER_BITS
from wirecal.solver.robot import INTERFACES, LANGUAGES

COUNTER_BITS = {
    "vplus": BELT_COUNTER_BITS,
    "urscript": RAW_COUNTER_BITS,
    "rapid": GROUP_COUNTER_BITS,
}
"""The counter width (bits) each language's programs read."""


def encoder_defaults(language: str) -> tuple[str, int]:
    """Return the encoder ``interface`` and ``counter_bits`` a language's programs read."""
    if language not in LANGUAGES:
        raise ValueError(f"unknown controller language {language!r}")
    return INTERFACES[language][0], COUNTER_BITS[language]
