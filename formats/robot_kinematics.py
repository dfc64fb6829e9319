"""The robot file's ``[kinematics]`` table: the DH table and the joint limits.

Craig's modified DH convention; the format is in :mod:`wirecal.formats.robot_file`.
"""

from __future__ import annotations

import numpy as np

from wirecal.formats.robot_values import (
    MAX_DH_ANGLE_DEG,
    MAX_JOINT_DEG,
    MAX_JOINTS,
    MAX_LENGTH_MM,
)
from wirecal.formats.toml_fields import Table

KINEMATICS_KEYS = (
    "convention",
    "dh",
    "joint_min_deg",
    "joint_max_deg",
    "joint_speed_deg_s",
    "joint_speed_confirmed",
)
"""The keys of ``[kinematics]``."""
_DH_COLUMNS = "[alpha_deg, a_mm, theta_offset_deg, d_mm]"
_DH_BOUND = (MAX_DH_ANGLE_DEG, MAX_LENGTH_MM, MAX_DH_ANGLE_DEG, MAX_LENGTH_MM)


def read_dh(kin: Table) -> np.ndarray | None:
    """Read ``convention`` and ``dh``: rows (α_{i-1}, a_{i-1}, θ_i offset, d_i), deg and mm."""
    kin.string("convention", choices={"craig": "modified DH, the one supported"})
    dh = kin.matrix(
        "dh",
        cols=4,
        labels=_DH_COLUMNS,
        lo=[-b for b in _DH_BOUND],
        hi=_DH_BOUND,
        unit=("deg", "mm", "deg", "mm"),
        max_rows=MAX_JOINTS,
    )
    if dh is not None and dh.shape[0] < 2:
        kin.add("dh", f"has {dh.shape[0]} row(s); a serial arm needs at least 2")
        return None
    return dh


def dh_radians(dh: np.ndarray | None) -> np.ndarray | None:
    """Return the DH table with its angles (α, θ offset) in radians (None stays None)."""
    if dh is None:
        return None
    dh_rad = np.array(dh, dtype=float)
    dh_rad[:, [0, 2]] = np.radians(dh_rad[:, [0, 2]])
    return dh_rad


def read_limits(kin: Table, n: int | None) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Read ``joint_min_deg`` and ``joint_max_deg`` (``n`` joints; each min below its max)."""
    lo, hi = (
        kin.vector(
            key,
            length=n,
            labels="(one per joint)",
            lo=-MAX_JOINT_DEG,
            hi=MAX_JOINT_DEG,
            unit="deg",
        )
        for key in ("joint_min_deg", "joint_max_deg")
    )
    if lo is None or hi is None or lo.shape != hi.shape:
        return lo, hi
    for j in np.flatnonzero(lo >= hi):
        kin.add("joint_min_deg", f"joint {j + 1}: min {lo[j]:g} is not below max {hi[j]:g}")
    return lo, hi
