"""The rules a robot file's values obey beyond their types: degrees, millimetres, sizes.

Each rule reports what looks like a wrong unit (radians, metres) or a value no plan can use,
and what to give instead (:mod:`wirecal.formats.robot_file`'s docstring lists them).
"""

from __future__ import annotations

import math

import numpy as np

from wirecal.formats.robot_values import METRES_RATIO, MIN_JOINT_RANGE_DEG
from wirecal.formats.toml_fields import Table
from wirecal.solver.angle_units import within_a_turn
from wirecal.solver.robot import Encoder


def check_units(
    doc: Table,
    dh: np.ndarray | None,
    lo: np.ndarray | None,
    hi: np.ndarray | None,
    encoder: Encoder | None,
    radii: np.ndarray | None,
) -> None:
    """Report the values, each past its type check, that break a unit or size rule."""
    if dh is not None:
        _check_not_radians(dh[:, 0], "α (column 1)", doc)
        _check_not_radians(dh[:, 2], "θ offsets (column 3)", doc)
    if lo is not None and hi is not None and lo.shape == hi.shape:
        _check_joint_ranges(lo, hi, doc)
    if encoder is not None:
        _check_counter(encoder, doc)
    if dh is not None and encoder is not None and radii is not None:
        _check_not_metres(dh, encoder.range_mm, radii, doc)


def _check_not_radians(column_deg: np.ndarray, what: str, doc: Table) -> None:
    """Report a column of angles that holds radians.

    Twists and θ offsets of real arms are 0 or multiples of 90°: non-zero values all within
    ±π, one of them ±π/2 or ±π, are radians.
    """
    nz = np.abs(column_deg[np.abs(column_deg) > 1e-9])
    if (
        nz.size
        and np.all(nz <= math.pi + 1e-6)
        and np.any(np.minimum(np.abs(nz - math.pi / 2), np.abs(nz - math.pi)) < 1e-3)
    ):
        doc.add(
            "kinematics.dh",
            f"{what} holds values like {nz[0]:g}: that looks like radians; give degrees "
            f"({nz[0]:g} rad = {math.degrees(nz[0]):.4g}°)",
        )


def _check_joint_ranges(lo: np.ndarray, hi: np.ndarray, doc: Table) -> None:
    """Per joint: limits in radians, or a range too narrow to plan."""
    for j in np.flatnonzero(hi > lo):
        span = hi[j] - lo[j]
        if within_a_turn(np.array([lo[j], hi[j]])):
            doc.add(
                "kinematics.joint_max_deg",
                f"joint {j + 1}: limits [{lo[j]:g}, {hi[j]:g}] are within ±2π: they look like "
                f"radians (that would be [{math.degrees(lo[j]):.4g}, "
                f"{math.degrees(hi[j]):.4g}] deg); give degrees",
            )
        elif span <= MIN_JOINT_RANGE_DEG:
            doc.add(
                "kinematics.joint_max_deg",
                f"joint {j + 1}: range [{lo[j]:g}, {hi[j]:g}] spans {span:g} deg, no more than "
                f"{MIN_JOINT_RANGE_DEG:g} deg: no room for plan points "
                f"{MIN_JOINT_RANGE_DEG / 2:g} deg inside both limits; check the limits",
            )


def _check_counter(enc: Encoder, doc: Table) -> None:
    """Report a counter too narrow for the encoder's range.

    2^(bits−1)·|mm_per_count| must exceed the range: the signed counter then holds every
    wire length the encoder can give, so no reading is a counter turn away from another.
    """
    half, mpc = enc.counter.half, abs(enc.mm_per_count)
    if enc.range_mm / mpc >= 2**63:  # more counts than any counter holds: the resolution
        doc.add(
            "encoder.mm_per_count",
            f"is {enc.mm_per_count:g} mm: range_mm {enc.range_mm:g} would be "
            f"{enc.range_mm / mpc:.3g} counts, more than a 64-bit counter holds; give the "
            "encoder's resolution in mm per count (a Unimeasure EP-50: 0.025488)",
        )
    elif enc.range_mm / mpc >= half:
        doc.add(
            "encoder.counter_bits",
            f"a signed {enc.counter_bits}-bit counter tells lengths apart up to {half} counts "
            f"({half * mpc:g} mm at {mpc:g} mm/count); range_mm {enc.range_mm:g} is "
            f"{enc.range_mm / mpc:.0f} counts: wire lengths a counter turn apart would read "
            "the same; give the width of the controller's counter (24 for a V+ belt encoder) "
            "or a smaller range_mm, and check mm_per_count",
        )


def _check_not_metres(dh: np.ndarray, range_mm: float, radii: np.ndarray, doc: Table) -> None:
    """Report lengths in metres.

    Links adding up to under 1 % of the encoder range, or under the widest link radius,
    are metres.
    """
    reach = float(np.abs(dh[:, [1, 3]]).sum())
    widest = float(radii.max(initial=0.0))
    if reach < max(METRES_RATIO * range_mm, widest):
        against = (
            f"the widest link radius ({widest:g} mm)"
            if widest > METRES_RATIO * range_mm
            else f"1 % of the encoder's range_mm ({range_mm:g})"
        )
        doc.add(
            "kinematics.dh",
            f"the links add up to {reach:g} mm (Σ|a| + Σ|d|), less than {against}: the "
            "lengths look like metres; give a and d in mm (the tool point, range_mm and "
            "link_radius_mm too)",
        )
