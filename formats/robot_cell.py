"""The robot file's optional ``[cell]`` table: floor, margin, keep-out volumes, encoder housing.

The model these tables describe is :mod:`wirecal.solver.cell.model`; the format is in
:mod:`wirecal.formats.robot_file`.
"""

from __future__ import annotations

import numpy as np

from wirecal.formats.robot_values import (
    MAX_CELL_MARGIN_MM,
    MAX_JOINT_DEG,
    MAX_LENGTH_MM,
    not_metres,
    point_mm,
    unit_vector,
)
from wirecal.formats.toml_fields import Table
from wirecal.solver.angle_units import within_a_turn
from wirecal.solver.cell.model import DEFAULT_MARGIN_MM, Box, CellModel, HalfSpace, Housing

CELL_KEYS = (
    "floor_z_mm",
    "margin_mm",
    "body_min_deg",
    "body_max_deg",
    "box",
    "half_space",
    "encoder_housing",
)
"""The keys of ``[cell]``."""
BOX_KEYS = ("name", "min_mm", "max_mm")
HALF_SPACE_KEYS = ("name", "point_mm", "normal")
HOUSING_KEYS = ("direction", "length_mm", "radius_mm")


def read_cell(table: Table, n: int | None) -> CellModel | None:
    """Read the optional ``[cell]`` table (a floor at z = 0 of frame 0 when absent).

    ``n`` is the number of joints (None when the DH table has problems).
    """
    floor = table.number("floor_z_mm", 0.0, lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM, unit="mm")
    margin = table.number("margin_mm", DEFAULT_MARGIN_MM, lo=0, hi=MAX_CELL_MARGIN_MM, unit="mm")
    body = [
        table.vector(
            key, None, length=n, labels="(one per joint)", lo=-MAX_JOINT_DEG, hi=MAX_JOINT_DEG
        )
        for key in ("body_min_deg", "body_max_deg")
    ]
    lo, hi = body
    if lo is not None and hi is not None and lo.shape == hi.shape:
        for j in np.flatnonzero(lo >= hi):
            table.add("body_max_deg", f"joint {j + 1}: {hi[j]:g} is not above body_min_deg")
        if within_a_turn(np.r_[lo, hi]):
            table.add(
                "body_max_deg",
                "every body limit is within ±2π: they look like radians (joint 2's would be "
                f"[{np.degrees(lo[1]):.4g}, {np.degrees(hi[1]):.4g}] deg); give degrees",
            )
    boxes = [_box(t) for t in table.tables("box", BOX_KEYS, required=False)]
    spaces = [_half_space(t) for t in table.tables("half_space", HALF_SPACE_KEYS, required=False)]
    housing = _housing(table.table("encoder_housing", HOUSING_KEYS, required=False))
    if floor is None or margin is None or None in boxes or None in spaces or housing is False:
        return None
    return CellModel(
        floor,
        margin,
        None if body[0] is None else tuple(body[0]),
        None if body[1] is None else tuple(body[1]),
        tuple(b for b in boxes if b is not None),
        tuple(h for h in spaces if h is not None),
        housing if isinstance(housing, Housing) else None,
    )


def _box(table: Table) -> Box | None:
    """Read one ``[[cell.box]]``: its name and opposite corners (frame 0, mm)."""
    name, lo, hi = table.string("name"), point_mm(table, "min_mm"), point_mm(table, "max_mm")
    if name is None or lo is None or hi is None:
        return None
    if not all(a < b for a, b in zip(lo, hi, strict=True)):
        table.add("max_mm", f"{list(hi)} is not above min_mm {list(lo)} in every coordinate")
        return None
    if not_metres(table, "", np.r_[lo, hi]) is None:  # a box of under 1 mm: no obstacle
        return None
    return Box(name, lo, hi)


def _half_space(table: Table) -> HalfSpace | None:
    """Read one ``[[cell.half_space]]``: a point on its plane and the free side's normal."""
    name = table.string("name")
    point, normal = point_mm(table, "point_mm"), unit_vector(table, "normal")
    if point is not None and not_metres(table, "point_mm", np.array(point)) is None:
        point = None
    if name is None or point is None or normal is None:
        return None
    return HalfSpace(name, point, normal)


def _housing(table: Table) -> Housing | bool | None:
    """Read ``[cell.encoder_housing]``: None when absent, False when it has problems."""
    if not table.present:
        return None
    direction = unit_vector(table, "direction")
    length = table.number("length_mm", above=0, hi=MAX_LENGTH_MM, unit="mm")
    radius = table.number("radius_mm", above=0, hi=MAX_LENGTH_MM, unit="mm")
    if direction is None or length is None or radius is None:
        return False
    if not_metres(table, "", np.array([length, radius])) is None:
        return False
    return Housing(direction, length, radius)
