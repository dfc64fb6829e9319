"""Inverse kinematics: every solution for a flange pose, with V+ configuration names.

Analytic for 6R arms of the common industrial structure in Craig's convention — α1 = ±90°,
α2 = 0, α3, α4, α5 = ±90° and a spherical wrist (a4 = a5 = d5 = 0), any lengths and joint
offsets (row 1's α0, a0 act as a fixed base transform). With φ_i the DH angles
(q_i + offset_i), s_k = sin α_k:

* wrist centre c = o6 − d6·z6 = o4, which depends on φ1..φ3 only;
* in frame 1 the wrist centre is (a1 + u_x, −s1(d2 + d3), s1·u_y) with
  (u_x, u_y) = RotZ(φ2)·(a2 + a3 cφ3 + s3 d4 sφ3, a3 sφ3 − s3 d4 cφ3): the horizontal
  reach fixes x1 = ±√(r² − (d2 + d3)²) (shoulder: righty/lefty) and φ1, then
  a3 cφ3 + s3 d4 sφ3 = (|u|² − a2² − a3² − d4²) / 2a2 gives φ3 (elbow: above/below) and φ2;
* the wrist rotation M = RotX(α3)ᵀ R3ᵀ R6 = RotZ(φ4) RotX(α4) RotZ(φ5) RotX(α5) RotZ(φ6)
  has m33 = −s4 s5 cφ5, (m13, m23) = s5 sφ5 (cφ4, sφ4), (m31, m32) = s4 sφ5 (cφ6, −sφ6):
  two solutions ±sφ5 (wrist: noflip/flip).

Each analytic solution is polished by Gauss–Newton on the exact model; arms outside the
class are solved numerically (damped least squares from many starts). Configuration
names (wirecal's convention; the V+ manual's exact definitions are unconfirmed):
righty when the wrist centre lies ahead of the joint-1 axis along the arm (x1 ≥ 0);
above when the elbow is above the line from joint 2 to the wrist centre; flip when
the DH angle φ5 = q5 + offset5 is negative (a small offset must not merge the two wrist
solutions).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from wirecal.solver.gravity import cross3
from wirecal.solver.ik import ur as ik_ur
from wirecal.solver.kinematics import Model, flange_jacobian, frames, one_chain, table_property
from wirecal.solver.robot import Robot

HALF_PI = np.pi / 2


@dataclass(frozen=True)
class Solution:
    """One inverse-kinematics solution, its configuration and whether it is within limits."""

    q: np.ndarray  # joint angles (rad)
    config: tuple[str, str, str]  # ("righty"|"lefty", "above"|"below", "noflip"|"flip")
    within_limits: bool


def flange_pose(model: Model, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (3, 3) and origin (3,) of the last frame for one configuration (rad)."""
    chain = one_chain(model, q)
    if chain is None:
        f = frames(model, np.atleast_2d(q))
        return f.R_last[0], f.o[0, -1]
    stored, axes = chain
    return np.array(axes).T.copy(), np.array(stored[-1][2])  # laid out as frames' arrays


@table_property
def analytic_structure(dh: np.ndarray) -> bool:
    """Whether :func:`solve` can use the closed form for this model."""
    if dh.shape[0] != 6:
        return False
    alpha = dh[:, 0]
    right = [np.isclose(abs(np.sin(alpha[k])), 1, atol=1e-12) for k in (1, 3, 4, 5)]
    return bool(
        all(right)
        and np.isclose(np.sin(alpha[2]), 0, atol=1e-12)
        and np.cos(alpha[2]) > 0
        and abs(dh[4, 1]) < 1e-12
        and abs(dh[5, 1]) < 1e-12
        and abs(dh[4, 3]) < 1e-12
        and abs(dh[2, 1]) > 1e-9
    )


def _rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


FOLD_SLACK = 1e-2
"""A structural table seeding another model (:func:`solve`'s numeric fallback) clips an elbow
cosine this far beyond ±1, not drops it: the wrist offsets the table leaves out (0.8 mm of a4
and 0.3 mm of d5 on the tests' non-spherical wrist, 0.12 % beyond) move the wrist centre
further than a calibration's errors move a UR's (:data:`~wirecal.solver.ik.ur.SEED_SLACK`)."""


def _analytic(
    model: Model, R: np.ndarray, o: np.ndarray, near_deg: float = 0.0
) -> list[np.ndarray]:
    """Closed-form DH angles φ (8 at most) for a flange pose; see the module doc.

    ``near_deg`` > 0 when the model is another's structural table, seeding Newton on that
    one: a pose just out of reach (by :data:`FOLD_SLACK`) is clipped, and within
    ``near_deg`` of the elbow's fold φ3 is also seeded either side of it
    (:func:`~wirecal.solver.ik.ur.pulled`; hypothesis found a Viper with a non-spherical
    wrist whose two elbow branches, 3.9° apart in φ3, lie where the structural table
    reaches neither).
    """
    dh = model.dh
    alpha, a, off, d = dh.T
    base = _rot_x(alpha[0])
    Rb, ob = base.T @ R, base.T @ o - np.array([a[0], 0, 0])
    s1, s3 = (np.sign(np.sin(alpha[k])) for k in (1, 3))
    c = ob - d[5] * Rb[:, 2]
    y1 = -s1 * (d[1] + d[2])
    r2 = c[0] ** 2 + c[1] ** 2
    out: list[np.ndarray] = []
    if r2 < y1**2:
        return out
    slack = FOLD_SLACK if near_deg > 0 else 1e-12
    for shoulder in (1, -1):
        x1 = shoulder * np.sqrt(r2 - y1**2)
        phi1 = np.arctan2(c[1], c[0]) - np.arctan2(y1, x1)
        ux, uy = x1 - a[1], s1 * (c[2] - d[0])
        k = (ux**2 + uy**2 - a[2] ** 2 - a[3] ** 2 - d[3] ** 2) / (2 * a[2])
        rr = np.hypot(a[3], d[3])
        if abs(k) > rr * (1 + slack):
            continue
        beta = np.arctan2(s3 * d[3], a[3])
        bends = ik_ur.pulled(float(np.arccos(np.clip(k / rr, -1, 1))), near_deg)
        for phi3 in (beta + elbow * bend for elbow in (1, -1) for bend in bends):
            px = a[2] + a[3] * np.cos(phi3) + s3 * d[3] * np.sin(phi3)
            py = a[3] * np.sin(phi3) - s3 * d[3] * np.cos(phi3)
            phi2 = np.arctan2(uy, ux) - np.arctan2(py, px)
            q123 = np.array([phi1, phi2, phi3]) - off[:3]
            chain = one_chain(Model(dh, model.tool_point), np.concatenate((q123, np.zeros(3))))
            assert chain is not None  # a rigid model's one configuration
            X3, Z3 = chain[0][3][0], chain[0][3][1]
            R3 = np.column_stack([X3, cross3(Z3, X3), Z3])
            M = _rot_x(alpha[3]).T @ R3.T @ R
            out += [np.array([phi1, phi2, phi3, *w]) for w in _wrist_angles(alpha, M)]
    return out


def _wrist_angles(alpha: np.ndarray, M: np.ndarray) -> list[tuple[float, float, float]]:
    """Return (φ4, φ5, φ6) per wrist branch from the wrist rotation M (see the module doc)."""
    s4, s5 = (np.sign(np.sin(alpha[k])) for k in (4, 5))
    h = np.hypot(M[0, 2], M[1, 2])
    out = []
    for wrist in (1, -1):
        s_phi5 = wrist * h
        phi5 = np.arctan2(s_phi5, -s4 * s5 * M[2, 2])
        if h > 1e-9:
            phi4 = np.arctan2(s5 * M[1, 2] * wrist, s5 * M[0, 2] * wrist)
            phi6 = np.arctan2(-s4 * M[2, 1] * wrist, s4 * M[2, 0] * wrist)
        else:  # wrist singular: φ4 and φ6 turn about one axis; keep φ4 = 0
            phi4 = 0.0
            N = _rot_x(alpha[4]) @ _rot_z(phi5) @ _rot_x(alpha[5])
            X = N.T @ M
            phi6 = np.arctan2(X[1, 0], X[0, 0])
            return [(phi4, phi5, phi6)]
        out.append((phi4, phi5, phi6))
    return out


def _pose_error(model, q, R, o, f=None):
    """Return the pose error (mm, and mrad-weighted rotation) of q; ``f``: q's frames."""
    f = frames(model, np.atleast_2d(q)) if f is None else f
    Rq, oq = f.R_last[0], f.o[0, -1]
    E = R @ Rq.T
    rotvec = 0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
    return np.concatenate((o - oq, rotvec * 1000.0))  # 1 rad of orientation weighs as 1 m


CONVERGED = 1e-10
"""Newton stops when no component of the pose error (mm, and mrad as mm per metre) exceeds this."""

ACCEPTED = 1e-7
"""A short :func:`follow` accepts an error up to this; :func:`solve` accepts only
:data:`CONVERGED`."""

PRE_ITERATIONS = 12
"""Newton steps before candidates that have met are merged (:func:`_distinct_starts`)."""

MAX_STEP_RAD = 0.2
"""Largest joint step of one Newton iteration. Near a singularity the least-squares step is
long and wrong (the first model error the seed does not know is divided by a small singular
value); capping it keeps Newton in the basin it started in."""


SAME_RAD = 1e-6
"""Two converged solutions are one when no joint differs by more than this (rad)."""

MET_RAD = 1e-2
"""A candidate after :data:`PRE_ITERATIONS` Newton steps this near a start runs to it (rad)."""


def _newton_terms(model, q, R, o) -> tuple[np.ndarray, Callable[[], np.ndarray]]:
    """Return q's pose error and a function giving its flange Jacobian (one chain evaluation).

    On Python floats where the model allows (:func:`~wirecal.solver.kinematics.one_chain`):
    the same numbers as :func:`_pose_error` and
    :func:`~wirecal.solver.kinematics.flange_jacobian` (the same operations in the same
    order; the rotations multiplied as the same arrays), at a fraction of the cost.
    """
    chain = one_chain(model, q)
    if chain is None:
        f = frames(model, q[None])
        return _pose_error(model, q, R, o, f), lambda: flange_jacobian(model, q, f)
    stored, axes = chain
    Rq = np.array(axes).T.copy()  # columns X, Y, Z, laid out as frames' R_last
    E = (R @ Rq.T).tolist()  # then on floats: the arrays' element-wise operations
    (o0, o1, o2), (f0, f1, f2) = np.asarray(o).tolist(), stored[-1][2]
    e = np.array(
        [
            o0 - f0,
            o1 - f1,
            o2 - f2,
            0.5 * (E[2][1] - E[1][2]) * 1000.0,
            0.5 * (E[0][2] - E[2][0]) * 1000.0,
            0.5 * (E[1][0] - E[0][1]) * 1000.0,
        ]
    )
    return e, lambda: _flange_jacobian_floats(stored)


def _flange_jacobian_floats(stored: list[tuple]) -> np.ndarray:
    """Return :func:`~wirecal.solver.kinematics.flange_jacobian` from one chain's floats."""
    p0, p1, p2 = (c + 0.0 for c in stored[-1][2])  # the flange (a zero tool point added)
    cols = []
    for _, (z0, z1, z2), (o0, o1, o2) in stored[1:]:
        b0, b1, b2 = p0 - o0, p1 - o1, p2 - o2
        turn = (z1 * b2 - z2 * b1, z2 * b0 - z0 * b2, z0 * b1 - z1 * b0)
        cols.append((*turn, z0 * 1000.0, z1 * 1000.0, z2 * 1000.0))
    return np.array(cols).T.copy()


def _polish(model, q, R, o, iterations=60, accept=CONVERGED, done=CONVERGED):
    """Newton from ``q``: stop once no pose error exceeds ``done``; ok if within ``accept``."""
    for _ in range(iterations):
        e, jacobian = _newton_terms(model, q, R, o)  # one evaluation of the chain per step
        if np.abs(e).max() < done:  # the method: numpy's same reduction, less overhead
            return q, True
        step = np.linalg.lstsq(jacobian(), e, rcond=None)[0]
        q = q + step * min(1.0, MAX_STEP_RAD / max(np.abs(step).max(), 1e-300))
    return q, np.max(np.abs(_pose_error(model, q, R, o))) < accept


def follow(model: Model, q: np.ndarray, R: np.ndarray, o: np.ndarray) -> tuple[np.ndarray, bool]:
    """Return the solution nearest ``q`` by Newton from it.

    A small Cartesian step in the same configuration (much cheaper than :func:`solve`).
    Newton stops within :data:`ACCEPTED`: its next step, to :data:`CONVERGED`, would move
    the joints by less than a controller's single-precision joint angle resolves.
    """
    q = np.asarray(q, dtype=float)
    return _polish(model, q, R, o, iterations=8, accept=ACCEPTED, done=ACCEPTED)


def solve(
    robot: Robot,
    R: np.ndarray,
    o: np.ndarray,
    *,
    model: Model | None = None,
    margin_deg: float = 0.0,
    seed: int = 0,
) -> list[Solution]:
    """Return every distinct solution for the flange pose (R, o).

    Each is put into the robot's joint limits less ``margin_deg`` where a turn of ±360°
    allows it (:func:`each_solution` yields them one by one, in this order).

    ``model`` is the kinematic model the controller believes (default: the robot's
    nominal model; a calibrated controller's is patched).
    """
    return list(each_solution(robot, R, o, model=model, margin_deg=margin_deg, seed=seed))


def each_solution(
    robot: Robot,
    R: np.ndarray,
    o: np.ndarray,
    *,
    model: Model | None = None,
    margin_deg: float = 0.0,
    seed: int = 0,
) -> Iterator[Solution]:
    """Yield :func:`solve`'s solutions one by one, in its order, each polished when asked for.

    A caller that takes the first solution of a configuration (the V+ controller) stops
    there; the solutions after it are never polished.
    """
    model = robot.nominal if model is None else model
    lo, hi = (np.radians(b).tolist() for b in robot.limits_deg(margin_deg, body=False))
    dh = np.asarray(model.dh)
    if analytic_structure(model):  # exact already: nothing to merge before polishing
        starts = [phi - dh[:, 2] for phi in _analytic(model, R, o)]
    elif ik_ur.ur_structure(model):  # three parallel axes, offset wrist: solver/ik/ur.py
        starts = _distinct_starts(model, ik_ur.candidates(model, R, o), R, o)
    else:
        rng = np.random.default_rng(seed)
        structural = dh.copy()
        structural[:, 0] = np.round(structural[:, 0] / HALF_PI) * HALF_PI
        structural[4:, 1] = 0.0
        structural[4, 3] = 0.0
        near = ik_ur.NEAR_SINGULAR_DEG
        seeds = [
            phi - dh[:, 2] for phi in _analytic(Model(structural, model.tool_point), R, o, near)
        ]
        seeds += list(rng.uniform(-np.pi, np.pi, (24, 6)))
        starts = _distinct_starts(model, seeds, R, o)
    found: list[list[float]] = []
    for q0 in starts:
        q, ok = _polish(model, q0, R, o)
        if not ok:
            continue
        wrapped, inside = _into_limits([_wrapped(x) for x in q.tolist()], lo, hi)
        if _same_as_any(wrapped, found, SAME_RAD):
            continue
        found.append(wrapped)
        q = np.array(wrapped)
        yield Solution(q, configuration(model, q), inside)


def _distinct_starts(model, candidates, R, o, iterations=PRE_ITERATIONS):
    """Return the candidates after a few Newton steps, those that met another dropped.

    Near a UR wrist singularity many samples run to the same solution; polishing each to
    the end would cost several times as much. A candidate still on its way is dropped
    within :data:`MET_RAD` of a start; a converged one only when it is the same solution
    (:data:`SAME_RAD`): near the elbow fold two distinct solutions lie closer than
    :data:`MET_RAD` (hypothesis found a UR5 folded to 180.02°, its elbow branches 0.04°,
    0.49° and 0.53° apart in joints 3, 2 and 4).
    """
    starts: list[np.ndarray] = []
    for q0 in candidates:
        q, done = _polish(model, np.asarray(q0, dtype=float), R, o, iterations)
        if not any(_same(q, s, SAME_RAD if done else MET_RAD) for s in starts):
            starts.append(q)
    return starts


def _same(q1, q2, atol_rad):
    """Whether two joint vectors are the same solution: every joint within ``atol_rad`` mod 2π."""
    return bool(np.all(np.abs(_wrapped(q1 - q2)) <= atol_rad))


def _same_as_any(q: list[float], others: list[list[float]], atol_rad: float) -> bool:
    """Whether ``q`` is the same solution as any of ``others`` (:func:`_same`, on floats)."""
    return any(
        all(abs(_wrapped(a - b)) <= atol_rad for a, b in zip(q, other, strict=True))
        for other in others
    )


def _wrapped(x):
    """Return angles ``x`` (rad, an array or a float) wrapped into [-π, π).

    On a float the same number as numpy's: Python's ``%`` takes the divisor's sign as
    numpy's remainder does.
    """
    return (x + np.pi) % (2 * np.pi) - np.pi


def _into_limits(q: list[float], lo: list[float], hi: list[float]) -> tuple[list[float], bool]:
    """Return ``q`` (rad) with each joint turned by ±360° into [lo, hi] (rad) where that fits.

    And whether every joint is then within its limits (1e-12 rad of slack).
    """
    into = list(q)
    for j, (qj, lo_j, hi_j) in enumerate(zip(q, lo, hi, strict=True)):
        for turn in (0.0, 2 * np.pi, -2 * np.pi):
            if lo_j <= qj + turn <= hi_j:
                into[j] = qj + turn
                break
    inside = all(x >= a - 1e-12 and x <= b + 1e-12 for x, a, b in zip(into, lo, hi, strict=True))
    return into, inside


def configuration(model: Model, q: np.ndarray) -> tuple[str, str, str]:
    """Return wirecal's names of a solution's configuration (see the module doc)."""
    if ik_ur.ur_structure(model):
        return ik_ur.configuration(model, q)
    chain = one_chain(model, q)
    if chain is not None:
        names = _configuration_floats(model, q, chain[0])
        if names is not None:
            return names
        x, z, o = (np.array([k[axis] for k in chain[0][:5]]) for axis in range(3))
    else:
        f = frames(model, np.atleast_2d(q))
        x, z, o = f.x[0], f.z[0], f.o[0]
    o2, o3 = o[2], o[3]
    centre = o[4]
    z1 = z[1]
    r = centre - o[1]
    x1 = r - np.dot(r, z1) * z1
    ahead = np.dot(x1, x[1])
    line = centre - o2
    t = np.dot(o3 - o2, line) / max(np.dot(line, line), 1e-300)
    offset = (o3 - o2) - t * line
    return (
        "righty" if ahead >= 0 else "lefty",
        "above" if offset[2] >= 0 else "below",
        "flip" if _wrapped(q[4] + model.dh[4, 2]) < 0 else "noflip",
    )


SIGN_SURE = 1e-12
""":func:`_configuration_floats` decides a sign only where the value exceeds this times the
1-norm of the vectors it is made of: numpy's dot products may add in another order (or
fused), so the two ways differ by a few ulps of those norms (below 1e-14 of them), never
across a margin this wide."""


def _configuration_floats(model: Model, q: np.ndarray, stored: list[tuple]):
    """:func:`configuration`'s names on the chain's floats, or None where a sign is close.

    The same names as numpy's arrays give (their dot products round alike to within
    :data:`SIGN_SURE`, so a sign decided here is theirs); None leaves a sign within that
    of zero to the arrays.
    """
    x1_axis, (z0, z1, z2), p1 = stored[1]
    o2, o3, centre = stored[2][2], stored[3][2], stored[4][2]
    r0, r1, r2 = centre[0] - p1[0], centre[1] - p1[1], centre[2] - p1[2]
    rz = r0 * z0 + r1 * z1 + r2 * z2
    h0, h1, h2 = r0 - rz * z0, r1 - rz * z1, r2 - rz * z2
    ahead = h0 * x1_axis[0] + h1 * x1_axis[1] + h2 * x1_axis[2]
    d0, d1, d2 = o3[0] - o2[0], o3[1] - o2[1], o3[2] - o2[2]
    l0, l1, l2 = centre[0] - o2[0], centre[1] - o2[1], centre[2] - o2[2]
    ll = l0 * l0 + l1 * l1 + l2 * l2
    if ll < 1e-100:
        return None
    t = (d0 * l0 + d1 * l1 + d2 * l2) / ll
    above = d2 - t * l2
    if abs(ahead) <= SIGN_SURE * (abs(r0) + abs(r1) + abs(r2)):
        return None
    if abs(above) <= SIGN_SURE * (abs(d0) + abs(d1) + abs(d2)):
        return None
    phi5 = float(q[4]) + float(model.dh[4, 2])
    return (
        "righty" if ahead >= 0 else "lefty",
        "above" if above >= 0 else "below",
        "flip" if _wrapped(phi5) < 0 else "noflip",
    )
