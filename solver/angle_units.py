"""Angles meant in degrees that were written in radians."""

from __future__ import annotations

import numpy as np

TURN_RAD = 2 * np.pi
"""Angles meant in degrees that all stay within ± this (6.28°) were written in radians."""


def within_a_turn(angles_deg: np.ndarray) -> bool:
    """Whether angles meant in degrees all lie within ±2π: they were written in radians.

    Joint limits, body limits, a plan's or a table's joints that all fit within ±6.3° leave
    an arm no room to move; in radians the same numbers span up to ±360°.
    """
    return bool(np.all(np.abs(angles_deg) <= TURN_RAD + 1e-9))
