"""Craig's modified DH parameters of a serial chain of revolute axes given as lines in space.

Input: for each joint at q = 0, a point on its axis and the axis direction (the direction the
joint turns positively about), the pose of the tip, all in one base frame (mm). Output: the
DH table, the base-to-frame-0 transform, and per joint the constant transform from the DH
frame to the joint's own frame (for a URDF: the joint's child link), so that

    T_base,link_i(q) = F0 · A_1(q_1) ⋯ A_i(q_i) · D_i,   A_i = RotX(α_{i-1}) TransX(a_{i-1})
                                                               RotZ(q_i + θ_i) TransZ(d_i)

holds exactly for every q: z_i is the joint's axis with its direction (so q turns the same
way in both descriptions), and the θ offsets put the DH zero where the input's zero is.

Choices where Craig's construction leaves freedom (deterministic, documented here):

* x_i (i < n) lies on the common normal of axes i and i+1. Of its two directions the one
  nearer x_{i-1} is taken (|θ_i offset| ≤ 90°; a may then be negative, as in UR's tables).
  For intersecting axes the common normal is ±(z_i × z_{i+1}) through the intersection.
* Parallel axes i ∥ i+1 have no unique common normal: o_i is put where x_{i-1} meets axis i,
  so d_i = 0 (Craig's rule), and the offset along the parallel axes is carried by the d of
  the last axis of the parallel group. The d's of a parallel group change every wire length
  in the same way (∂p/∂d_i = z_i = z_{i+1}): only one of them is identifiable, and the rule
  puts the whole nominal length in that one, which :func:`propose_parameters` then keeps.
* Axes within ``parallel_tol`` (default ``PARALLEL_TOL``: a URDF's π/2 written with 9
  digits) of parallel are made exactly parallel; the caller measures and reports the
  forward-kinematics difference this makes.
* Frame 0 is the base frame itself when row 1 can express axis 1 in it (axis 1 ⊥ x_base and
  meeting the x_base axis: α0, a0 and d1 then place it); otherwise frame 0 has z along axis
  1 through the point of axis 1 nearest the base origin, x along the base x (or y) projected,
  and F0 is not the identity (the caller records it).
* The last frame: origin where the tip's origin projects onto axis n, x_n = x_{n-1} at q = 0
  (θ_n offset 0); the tip's origin in that frame is the tool point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.kinematics import Model, frames

PARALLEL_TOL = 1e-9
"""|sin| of the angle between two axes below which they are treated as parallel (rad)."""

NEAR_PARALLEL = 1e-3
"""Axes this close to parallel, but not within PARALLEL_TOL, put the common normal far away
(a d of more than a metre per mm of offset): refused as a rounded URDF angle."""


class ChainError(ValueError):
    """The chain cannot be written in modified DH; the message names the joints."""


@dataclass(frozen=True)
class DhChain:
    """A modified-DH description of a chain of axes, with the frames it maps to."""

    dh: np.ndarray  # (n, 4): α_{i-1} [rad], a_{i-1} [mm], θ_i offset [rad], d_i [mm]
    frame0: np.ndarray  # (4, 4) base → DH frame 0
    tool_point: np.ndarray  # (3,) tip origin in DH frame n (mm)
    joint_offsets: np.ndarray  # (n, 4, 4) DH frame i → the joint's own frame
    tip_offset: np.ndarray  # (4, 4) DH frame n → tip
    snapped: tuple[tuple[int, float], ...]  # (i, angle rad): axes i, i+1 made parallel


def _up2(x: float) -> float:
    """Round x up to two significant digits."""
    step = 10.0 ** (np.floor(np.log10(x)) - 1)
    return float(np.ceil(x / step) * step)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _frame(x: np.ndarray, z: np.ndarray, o: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, o
    return T


def _inv(T: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def dh_row(T: np.ndarray) -> tuple[float, float, float, float]:
    """(α, a, θ, d) of a transform of the form RotX(α)·TransX(a)·RotZ(θ)·TransZ(d)."""
    alpha = float(np.arctan2(-T[1, 2], T[2, 2]))
    theta = float(np.arctan2(-T[0, 1], T[0, 0]))
    d = float(-np.sin(alpha) * T[1, 3] + np.cos(alpha) * T[2, 3])
    return alpha, float(T[0, 3]), theta, d


def dh_frames(dh: np.ndarray, q: np.ndarray) -> np.ndarray:
    """4×4 DH frames 0…n (N, n+1, 4, 4) for configurations q (N, n) in radians."""
    f = frames(Model(np.asarray(dh, dtype=float), np.zeros(3)), q)
    T = np.zeros((*f.o.shape[:2], 4, 4))
    T[..., :3, 0], T[..., :3, 2], T[..., :3, 3] = f.x, f.z, f.o
    T[..., :3, 1] = np.cross(f.z, f.x)
    T[..., 3, 3] = 1.0
    return T


def _closest(p1, z1, p2, z2):
    """Closest points of two non-parallel lines p + t·z."""
    w = p1 - p2
    b = z1 @ z2
    denom = 1 - b * b
    t1 = (b * (z2 @ w) - (z1 @ w)) / denom
    t2 = ((z2 @ w) - b * (z1 @ w)) / denom
    return p1 + t1 * z1, p2 + t2 * z2


def _toward(x: np.ndarray, ref: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Return x or −x, whichever is nearer ref (ties: the one at +90° about z)."""
    c = x @ ref
    if abs(c) > 1e-12:
        return x if c > 0 else -x
    return x if np.cross(ref, x) @ z > 0 else -x


def dh_from_axes(
    points: np.ndarray,
    axes: np.ndarray,
    tip: np.ndarray,
    joint_frames: np.ndarray,
    names: list[str],
    parallel_tol: float = PARALLEL_TOL,
) -> DhChain:
    """Return the modified-DH description of joint axes given as lines.

    The modified-DH description of axes ``points[i] + t·axes[i]`` (base frame, q = 0) with
    tip pose ``tip`` (4, 4) and the joints' own frames ``joint_frames`` (n, 4, 4); ``names``
    are used in messages. See the module doc for the conventions.
    """
    points = np.asarray(points, dtype=float)
    z = np.array([_unit(a) for a in np.asarray(axes, dtype=float)])
    n = len(z)
    # Snap nearly parallel neighbours first, so every later construction sees exact lines.
    snapped = _snap_parallel(z, names, parallel_tol)
    F0, foot = _frame0(z[0], points[0])
    x_prev = F0[:3, 0]
    F = [F0]
    for i in range(n):
        o, x = _origin_and_x(i, points, z, x_prev, foot, tip, names)
        F.append(_frame(x, z[i], o))
        x_prev = x
        foot = o + ((points[i + 1] - o) @ x) * x if i < n - 1 else foot

    dh = np.array([dh_row(_inv(F[i]) @ F[i + 1]) for i in range(n)])
    # Rebuild the frames from the table: every later transform refers to exactly these.
    T = F0 @ dh_frames(dh, np.zeros((1, n)))[0]
    offsets = np.array([_inv(T[i + 1]) @ joint_frames[i] for i in range(n)])
    tip_offset = _inv(T[n]) @ tip
    return DhChain(
        dh=dh,
        frame0=F0,
        tool_point=tip_offset[:3, 3].copy(),
        joint_offsets=offsets,
        tip_offset=tip_offset,
        snapped=tuple(snapped),
    )


def _snap_parallel(z: np.ndarray, names: list[str], parallel_tol: float) -> list[tuple[int, float]]:
    """Make axes within ``parallel_tol`` (sine) of their neighbour's exactly parallel, in place.

    Returns (joint index, sine) of each snapped pair; refuses a pair near parallel beyond
    the tolerance (its common normal lies far away: the URDF's angles look rounded).
    """
    snapped = []
    for i in range(len(z) - 1):
        s = np.linalg.norm(np.cross(z[i], z[i + 1]))
        if 0 < s < parallel_tol:
            z[i + 1] = z[i] if z[i] @ z[i + 1] > 0 else -z[i]
            snapped.append((i, float(s)))
        elif parallel_tol <= s < NEAR_PARALLEL:
            raise ChainError(
                f"the axes of joints {names[i]!r} and {names[i + 1]!r} are {np.degrees(s):.3g}° "
                "from parallel: their common normal lies far away. The URDF's angles look "
                "rounded (e.g. 1.5708 for π/2): write them with full precision, or accept "
                f"them as parallel with --parallel-tol-deg {_up2(np.degrees(s) * 1.01):.2g} (the "
                "import then reports how far the tip moves)"
            )
    return snapped


def _frame0(z1: np.ndarray, p1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return frame 0 (4, 4) and the foot of x0 on axis 1 (the line p1 + t·z1)."""
    if abs(z1[0]) < 1e-12 and abs(p1[1] * z1[2] - p1[2] * z1[1]) < 1e-9:
        t = -(p1[1] * z1[1] + p1[2] * z1[2])  # z1 ⊥ x: the line meets the x axis here
        return np.eye(4), p1 + t * z1
    foot = p1 - (p1 @ z1) * z1
    ref = np.array([1.0, 0, 0]) if abs(z1[0]) < 0.9 else np.array([0, 1.0, 0])
    return _frame(_unit(ref - (ref @ z1) * z1), z1, foot), foot


def _origin_and_x(
    i: int,
    points: np.ndarray,
    z: np.ndarray,
    x_prev: np.ndarray,
    foot: np.ndarray,
    tip: np.ndarray,
    names: list[str],
) -> tuple[np.ndarray, np.ndarray]:
    """Return joint ``i``'s frame origin and x axis.

    On the common normal of axes i and i+1; for parallel axes where x_{i-1} meets axis i;
    for the last joint at the tip's foot on its axis, x along x_{i-1}.
    """
    n = len(z)
    if i == n - 1:
        o = points[i] + ((tip[:3, 3] - points[i]) @ z[i]) * z[i]
        return o, _unit(x_prev - (x_prev @ z[i]) * z[i])
    if np.linalg.norm(np.cross(z[i], z[i + 1])) == 0:  # parallel: o_i where x_{i-1} meets
        o = points[i] + ((foot - points[i]) @ z[i]) * z[i]
        gap = points[i + 1] - o
        gap = gap - (gap @ z[i]) * z[i]
        if np.linalg.norm(gap) > 1e-9:
            return o, _toward(_unit(gap), x_prev, z[i])
        # the same line: joints i and i+1 turn about one axis
        raise ChainError(
            f"joints {names[i]!r} and {names[i + 1]!r} turn about the same line: "
            "the two angles cannot be told apart"
        )
    o, f = _closest(points[i], z[i], points[i + 1], z[i + 1])
    x = _unit(np.cross(z[i], z[i + 1]))
    if np.linalg.norm(f - o) > 1e-6:
        x = _unit(f - o)  # equals ±(z_i × z_{i+1}) up to round-off
        x = _unit(x - (x @ z[i]) * z[i] - (x @ z[i + 1]) * z[i + 1])
    return o, _toward(x, x_prev, z[i])
