"""Craig's modified DH model rewritten in the standard (distal) DH convention, exactly.

Modified DH (DESIGN.md): T = Π_{i=1..n} RotX(α_{i-1})·TransX(a_{i-1})·RotZ(θ_i)·TransZ(d_i).
Standard DH:            T = B · Π_{i=1..n} RotZ(θ_i)·TransZ(d_i)·TransX(a_i)·RotX(α_i).

The conversion is a regrouping of the same product, not a fit. RotX(α) and TransX(a)
commute (both act along x), so

    T = [RotX(α_0)·TransX(a_0)] · Π_{i=1..n-1} [RotZ(θ_i)·TransZ(d_i)·TransX(a_i)·RotX(α_i)]
        · [RotZ(θ_n)·TransZ(d_n)]

and the standard row i takes θ_i, d_i from modified row i and a_i, α_i from modified row
i+1 (wirecal's names ``a<i>``, ``al<i>`` already index them so: ``a2`` is a_2 in both);
the last row has a_n = α_n = 0; the modified model's first link RotX(α_0)·TransX(a_0) is a
constant base transform B (identity for the UR5, whose base frame is joint 1's).

Standard DH needs each link frame's z on the *next* joint's axis and its x on the common
normal of consecutive axes. When two axes are parallel (the UR's joints 2, 3, 4) the common
normal is not unique. The choice here is the modified model's own: frame i of the
standard table *is* modified frame i+1 before its θ rotation, so the common normal is the
one the modified table already fixed (its x_i and d values), and the flange frame n is
the same frame in both conventions — the tool point needs no change. Any other choice
would move a d_i between rows and change which parameters are errors; this one maps every
modified error parameter to exactly one standard parameter of the same name.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.kinematics import Model
from wirecal.solver.robot import Robot


@dataclass(frozen=True)
class StandardDH:
    """A standard-DH model.

    A standard-DH model: ``table`` rows (θ offset [rad], d [mm], a [mm], α [rad]) per
    joint, the base transform RotX(``base_alpha``)·TransX(``base_a_mm``), and the tool
    point in the flange frame (mm).
    """

    table: np.ndarray  # (n, 4)
    base_alpha: float
    base_a_mm: float
    tool_point: np.ndarray  # (3,)


def from_modified(model: Robot | Model) -> StandardDH:
    """Return the exact standard-DH form of a (single, unbatched) modified-DH model."""
    dh = np.asarray(model.dh, dtype=float)
    if dh.ndim != 2:
        raise ValueError("from_modified takes one model, not a batch")
    n = dh.shape[0]
    table = np.zeros((n, 4))
    table[:, 0] = dh[:, 2]  # θ_i offset
    table[:, 1] = dh[:, 3]  # d_i
    table[: n - 1, 2] = dh[1:, 1]  # a_i = modified a of row i+1
    table[: n - 1, 3] = dh[1:, 0]  # α_i = modified α of row i+1
    return StandardDH(table, float(dh[0, 0]), float(dh[0, 1]), np.array(model.tool_point, float))


def to_modified(std: StandardDH) -> Model:
    """Return the inverse regrouping; refuses a last row with a or α (no modified row holds it)."""
    t = std.table
    if t[-1, 2] != 0.0 or t[-1, 3] != 0.0:
        raise ValueError("the last standard row has a or alpha: a modified table cannot hold it")
    n = t.shape[0]
    dh = np.zeros((n, 4))
    dh[:, 2], dh[:, 3] = t[:, 0], t[:, 1]
    dh[1:, 1], dh[1:, 0] = t[: n - 1, 2], t[: n - 1, 3]
    dh[0, 0], dh[0, 1] = std.base_alpha, std.base_a_mm
    return Model(dh=dh, tool_point=np.array(std.tool_point, float))


def _rot_x(alpha: float) -> np.ndarray:
    c, s = np.cos(alpha), np.sin(alpha)
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, c, -s, 0.0], [0.0, s, c, 0.0], [0, 0, 0, 1.0]])


def flange_pose(std: StandardDH, q: np.ndarray) -> np.ndarray:
    """Return the homogeneous flange poses (N, 4, 4) for joint angles ``q``.

    Homogeneous flange poses (N, 4, 4) for joint angles ``q`` (N, n) in radians,
    composed in the standard convention (vectorised over N).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    N, n = q.shape
    if n != std.table.shape[0]:
        raise ValueError(f"configurations have {n} joints; the model has {std.table.shape[0]}")
    base = _rot_x(std.base_alpha)
    base[0, 3] = std.base_a_mm
    T = np.broadcast_to(base, (N, 4, 4)).copy()
    for i in range(n):
        th_off, d, a, alpha = std.table[i]
        th = q[:, i] + th_off
        c, s = np.cos(th), np.sin(th)
        ca, sa = np.cos(alpha), np.sin(alpha)
        A = np.zeros((N, 4, 4))  # RotZ(θ)·TransZ(d)·TransX(a)·RotX(α)
        A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = c, -s * ca, s * sa, a * c
        A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = s, c * ca, -c * sa, a * s
        A[:, 2, 1], A[:, 2, 2], A[:, 2, 3] = sa, ca, d
        A[:, 3, 3] = 1.0
        T = T @ A
    return T


def tool_position(std: StandardDH, q: np.ndarray) -> np.ndarray:
    """Tool point in the base frame (N, 3), mm."""
    T = flange_pose(std, q)
    return T[:, :3, 3] + T[:, :3, :3] @ std.tool_point
