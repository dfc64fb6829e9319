"""Joint speeds that cannot be real: a URDF template's placeholders, or rad/s typed as deg/s.

``wirecal gen`` times every move from ``joint_speed_deg_s`` (the V+ SPEED that keeps the wire
within its speed limit, the URScript joint speed): speeds below the real ones would let the
real wire run faster than the encoder allows, so such speeds need the user's confirmation.
"""

from __future__ import annotations

import numpy as np

MIN_PLAUSIBLE_SPEED_DEG_S = 60.0
"""Slowest joint speed taken as real (deg/s): industrial arms a draw wire calibrates move every
joint at 100–600 °/s; a URDF template's 1 rad/s (57.3 °/s) is below it, and so is every
joint's speed in rad/s (a Viper s650's 5.2–10.5)."""


def placeholder_speeds(speed_deg_s: np.ndarray) -> str | None:
    """Return why joint speeds cannot be real, or None.

    Placeholders: every joint the same whole number of rad/s (templates write 1.0), or any
    joint slower than :data:`MIN_PLAUSIBLE_SPEED_DEG_S`.
    """
    rad_s = np.radians(speed_deg_s)
    if np.all(rad_s == rad_s[0]) and abs(rad_s[0] - round(rad_s[0])) < 1e-9:
        return f"every joint's speed is {rad_s[0]:g} rad/s, a template's placeholder"
    slow = np.flatnonzero(speed_deg_s < MIN_PLAUSIBLE_SPEED_DEG_S)
    if slow.size:
        joints = ", ".join(f"{j + 1} ({speed_deg_s[j]:.4g} °/s)" for j in slow)
        return (
            f"joint(s) {joints} are slower than {MIN_PLAUSIBLE_SPEED_DEG_S:g} °/s, "
            "implausible for an industrial arm"
        )
    return None
