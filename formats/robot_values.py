"""The bounds a robot file's values are checked against, and the readers of its 3-vectors.

Each bound is wirecal's plausibility limit, not a controller's: a value beyond it is a typing
slip (a wrong unit, a missing decimal point) that would only fail later.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from wirecal.formats.toml_fields import Table

MAX_LENGTH_MM = 10_000.0
"""Largest |a|, |d|, tool coordinate or link radius (mm): no arm a draw wire spans is 10 m."""
MAX_DH_ANGLE_DEG = 360.0
"""Largest |α| or |θ offset| in the DH table (deg)."""
MAX_JOINT_DEG = 3600.0
"""Largest |joint limit| (deg): ten turns."""
MAX_JOINTS = 12
"""Most rows of ``dh``: serial arms have 6 or 7 joints; wirecal's bound, not a controller's."""
MAX_SPEED_DEG_S = 10_000.0
MAX_MM_PER_COUNT = 10.0
MAX_RANGE_MM = 100_000.0
MIN_RANGE_MM = 10.0
"""A ``range_mm`` under this is in metres (1.25 for a 1250 mm wire): a wire that short
spans no arm, and 10 m is still a draw wire's range."""
MAX_WIRE_SPEED_MM_S = 20_000.0
"""Largest wire speed limit (mm/s): catalogue draw-wire sensors allow 1–10 m/s."""
MAX_WIRE_ACCEL_MM_S2 = 1_000_000.0
"""Largest wire acceleration limit (mm/s²): about 100 g; catalogues give 5–20 g."""
MIN_WIRE_SPEED_MM_S = 20.0
"""A wire speed limit under this is in m/s (1 for 1000 mm/s): a sensor that slow would
take a minute per metre of wire."""
MIN_WIRE_ACCEL_MM_S2 = 1000.0
"""A wire acceleration limit under this (0.1 g) is in m/s² (49 for 5 g) or in g."""
MAX_CELL_MARGIN_MM = 500.0
"""Largest ``[cell] margin_mm``: a gap wider than half a metre leaves no arm room to move."""
MIN_JOINT_RANGE_DEG = 10.0
"""A joint's range (deg) must exceed this: plan points stay 5° (the planner's and the
generator's default margin) inside each limit."""
MAX_SCALE_PPM = 100_000.0
"""Largest scale tolerance (ppm): 10 %; a draw-wire sensor is far better than that."""
MAX_REFERENCE_U_MM = 1.0
"""Largest certified uncertainty of a reference gauge (mm)."""
MAX_TEMPCO_PPM_PER_K = 1000.0
"""Largest |temperature coefficient| (ppm/K): metals and plastics are below 200."""
MAX_GRAVITY_SAG_DEG_PER_M = 1.0
"""Largest gravity sag (deg per metre of lever): 1 deg/m bends a 0.6 m arm by 10 mm."""
MAX_REPEATABILITY_MM = 1.0
"""Largest pose repeatability (mm): industrial arms state 0.01–0.1 mm; 1 mm is a slip."""
METRES_RATIO = 0.01
"""Links adding up to less than this fraction of the encoder's range are in metres."""
MAX_EXIT_DEG = 90.0
"""Largest eyelet cone half-angle (deg): beyond 90° the wire would leave backwards."""
MAX_EXIT_RADIUS_MM = 100.0
"""Largest eyelet edge or guide pulley radius (mm): draw-wire sensors' are a few mm."""
AXIS_TOLERANCE = 0.01
"""A unit vector (an exit axis, a normal) must have length 1 to within this; it is then
normalised exactly."""


def in_metres(point_mm: Sequence[float] | np.ndarray) -> bool:
    """Whether a point meant in mm is in metres: every value under 1 mm, not all zero.

    A wire's attachment 0.06 mm from the flange is a slip for 60 mm (0.06 m).
    """
    return bool(0 < np.max(np.abs(point_mm), initial=0.0) < 1)


def not_metres(
    table: Table, key: str, point: np.ndarray | None, example: str = ""
) -> np.ndarray | None:
    """Return ``point``; None, with a problem naming ``key``, when it is in metres.

    ``example`` (" (e.g. …)") ends the problem.
    """
    if point is None or not in_metres(point):
        return point
    table.add(
        key,
        f"[{', '.join(f'{v:g}' for v in point)}]: every value under 1 mm: that looks like "
        f"metres; give it in mm{example}",
    )
    return None


def point_mm(table: Table, key: str) -> tuple[float, float, float] | None:
    """Read a point (x, y, z) in mm, each coordinate within :data:`MAX_LENGTH_MM`."""
    v = table.vector(key, length=3, labels="(x, y, z)", lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM)
    return None if v is None else (float(v[0]), float(v[1]), float(v[2]))


def unit_vector(
    table: Table, key: str, what: str = "a unit vector", example: str = ""
) -> tuple[float, float, float] | None:
    """Read a unit vector, normalised exactly; its length must be 1 within 1 %.

    A problem says to give ``what``, then ``example`` (", e.g. …") if any.
    """
    v = table.vector(key, length=3, labels="(x, y, z)", lo=-1, hi=1)
    if v is None:
        return None
    norm = float(np.linalg.norm(v))
    if abs(norm - 1) > AXIS_TOLERANCE:
        table.add(key, f"has length {norm:.4g}; give {what} (length 1 within 1 %){example}")
        return None
    x, y, z = (float(c) for c in v / norm)
    return (x, y, z)
