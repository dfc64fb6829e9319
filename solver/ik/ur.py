"""Closed-form inverse kinematics of UR-type arms.

Closed-form inverse kinematics of UR-type arms: axes 2, 3, 4 parallel and perpendicular to
axis 1, an offset wrist (axes 5 and 6 each perpendicular to the one before, a4 = a5 = 0,
any d5, d6). In Craig's convention: α1, α4, α5 = ±90°, α2 = α3 = 0, a4 = a5 = 0; row 1's
α0, a0, d1 act as a fixed base transform. Up to eight solutions: shoulder × wrist × elbow.

With φ_i = q_i + θ_i offset, s_k = sin α_k, D = d2 + d3 + d4 and (in the frame of axis 1)
the flange pose (R, o):

* o5 = o − d6·z6 (a5 = 0). Every link from 2 to 5 moves in planes normal to z2 = −s1·y1,
  so o5·y1 = −s1·D: with r = |o5 in the xy plane|, o5 = ±√(r² − D²)·x1 − s1·D·y1 gives
  two φ1 (shoulder).
* z2 seen from the flange: R6ᵀ z2 = (s4 sφ5 cφ6, −s4 sφ5 sφ6, −s4 s5 cφ5), so
  cφ5 = −z6·z2 / (s4 s5) gives ±φ5 (wrist) and then φ6 (free when sφ5 = 0: φ6 = 0).
* R4 = R · (RotX(α4) RotZ(φ5) RotX(α5) RotZ(φ6))ᵀ and o4 = o5 − d5·z5. In the plane of
  the parallel axes (frame 1 · RotX(α1) · TransX(a1)), o4 = RotZ(φ2)·(a2 + a3 cφ3, a3 sφ3):
  ±φ3 (elbow) from the law of cosines, then φ2, and φ2 + φ3 + φ4 from R4.

Arms near this structure (a calibrated UR) are solved from the closed form of their
structural model (α rounded to multiples of 90°, a4 = a5 = 0) polished by Newton in
:func:`wirecal.solver.ik.solutions.solve`.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.gravity import cross
from wirecal.solver.kinematics import Model, flange_jacobian, frames, table_property

HALF_PI = np.pi / 2
STRUCTURE_TOL_RAD = np.radians(5.0)
"""A model counts as UR-type if rounding its twists moves none by more than this."""

SEED_SLACK = 1e-3
"""A cosine this far beyond ±1 is clipped, not dropped: a calibrated arm stretched straight
has a structural model just out of reach, and Newton from the clipped seed finds it."""

NEAR_SINGULAR_DEG = 15.0
"""Within this of the wrist singularity (φ5 = 0 or 180°) a calibrated model's solutions are
sought from φ6 sampled round the turn, not from the structural table's one φ6 per branch."""

WRIST_SAMPLES = 12
"""φ6 samples per wrist branch near the wrist singularity (every 30°)."""

PULL_DEG = 2.0
"""Where two branches of the structural table nearly meet (the elbow stretched or folded, the
wrist point near the shoulder's cylinder), a calibrated model's are also seeded this far from
the fold on each side (:func:`pulled`)."""


ELBOW_NEAR_DEG = 2.0
"""Within this of the elbow stretched or folded, :func:`configuration` names the elbow branch
by the sign of the Jacobian's determinant, not the elbow's side of the shoulder–wrist line."""


def _rot_x(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_z(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def pulled(half: float, near_deg: float) -> list[float]:
    """Return a half-angle between two branches, and one pulled from a fold if near it.

    ``half`` (rad, 0 … π); within ``near_deg`` of 0 or π, also :data:`PULL_DEG` from it.

    Near a fold the true model's two branches may lie where the structural table has one
    seed or two that nearly meet, and Newton from between them finds only one.
    """
    out = [half]
    if min(half, np.pi - half) < np.radians(near_deg):
        pull = np.radians(PULL_DEG)
        out.append(pull if half < np.pi / 2 else np.pi - pull)
    return out


def structural(dh: np.ndarray) -> np.ndarray:
    """Return the nearest exact UR-type table: twists rounded to multiples of 90°, a4 = a5 = 0."""
    out = np.array(dh, dtype=float)
    out[:, 0] = np.round(out[:, 0] / HALF_PI) * HALF_PI
    out[4:, 1] = 0.0
    return out


@table_property
def ur_structure(dh: np.ndarray) -> bool:
    """Whether the model is UR-type, exactly or near enough for the closed form to seed."""
    if dh.shape[0] != 6:
        return False
    s = structural(dh)
    alpha = s[:, 0]
    return (
        bool(np.all(np.abs(dh[:, 0] - alpha) < STRUCTURE_TOL_RAD))
        and all(abs(abs(np.sin(alpha[k])) - 1) < 1e-12 for k in (1, 4, 5))
        and all(np.cos(alpha[k]) > 0.5 for k in (2, 3))
        and abs(s[2, 1]) > 1e-9
        and abs(s[3, 1]) > 1e-9
    )


def _arm(
    dh: np.ndarray,
    Rb: np.ndarray,
    o5: np.ndarray,
    phi1: float,
    phi5: float,
    phi6: float,
    near_deg: float = 0.0,
) -> list[np.ndarray]:
    """Return the elbow solutions (φ2, φ3, φ4) completing φ1, φ5, φ6; see the module doc.

    Within ``near_deg`` of the elbow stretched (φ3 = 0) or folded (φ3 = ±180°) the two
    elbow branches nearly meet, and a calibrated arm's may lie where the structural table
    has none (hypothesis found a calibrated UR5 folded to 179.6°, the structural seeds both
    at 180°): φ3 is then also seeded :data:`PULL_DEG` away from the fold on each side.
    """
    alpha, a, _, d = dh.T
    R1 = _rot_z(phi1)
    W = _rot_x(alpha[4]) @ _rot_z(phi5) @ _rot_x(alpha[5]) @ _rot_z(phi6)
    R4 = Rb @ W.T
    z5 = R4 @ np.array([0.0, -np.sin(alpha[4]), np.cos(alpha[4])])
    o4 = o5 - d[4] * z5
    RP = R1 @ _rot_x(alpha[1])
    p = RP.T @ (o4 - a[1] * R1[:, 0])
    c3 = (p[0] ** 2 + p[1] ** 2 - a[2] ** 2 - a[3] ** 2) / (2 * a[2] * a[3])
    if abs(c3) > 1 + SEED_SLACK:
        return []
    bends = pulled(float(np.arccos(np.clip(c3, -1.0, 1.0))), near_deg)  # 0 stretched … π folded
    M = RP.T @ R4
    out = []
    for elbow in (1.0, -1.0):
        for b in bends:
            phi3 = elbow * b
            phi2 = np.arctan2(p[1], p[0]) - np.arctan2(
                a[3] * np.sin(phi3), a[2] + a[3] * np.cos(phi3)
            )
            phi4 = np.arctan2(M[1, 0], M[0, 0]) - phi2 - phi3
            out.append(np.array([phi1, phi2, phi3, phi4, phi5, phi6]))
    return out


def _wrist(
    Rb: np.ndarray, z2: np.ndarray, s4: float, s5: float, near_deg: float
) -> list[tuple[float, list[float], bool]]:
    """Return (φ5, [φ6, ...], whether the first φ6 the arm reaches is enough) per branch.

    Away from the wrist singularity one φ6 per branch. At it, axes 2, 3, 4 and 6 are
    parallel and φ4 + φ6 forms a continuum, but the offset wrist's φ6 moves the wrist
    point, so only some φ6 let the arm reach it (hypothesis found a stretched arm that
    φ6 = 0 could not): φ6 = 0, else the first of φ6 sampled round the turn
    (:data:`WRIST_SAMPLES`) that the arm reaches. Within ``near_deg`` of it the two branches
    nearly meet; a calibrated arm's solutions there may differ in number and place from the
    structural table's, so every sample is a seed for Newton.
    """
    c5 = -(Rb[:, 2] @ z2) / (s4 * s5)  # |c5| ≤ 1 but for rounding: unit vectors, |s4 s5| = 1
    v = Rb.T @ z2
    turn = list(np.linspace(-np.pi, np.pi, WRIST_SAMPLES, endpoint=False))
    out = []
    for wrist in (1.0, -1.0):
        phi5 = wrist * float(np.arccos(np.clip(c5, -1.0, 1.0)))
        sin5 = np.sin(phi5)
        phi6 = _phi6(v, s4, sin5)
        if abs(sin5) < np.sin(np.radians(near_deg)):
            out.append((phi5, [phi6, *turn], False))
        elif abs(sin5) <= 1e-9:
            out.append((phi5, [phi6, *turn], True))
        else:
            out.append((phi5, [phi6], False))
    return out


def _phi6(v: np.ndarray, s4: float, sin5: float) -> float:
    """φ6 from z2 seen in the flange frame, v = R6ᵀ z2 (module doc); 0 at the singularity."""
    if abs(sin5) <= 1e-9:
        return 0.0
    sg = s4 * np.sign(sin5)
    return float(np.arctan2(-v[1] * sg, v[0] * sg))


def closed_form(
    dh: np.ndarray, R: np.ndarray, o: np.ndarray, near_deg: float = 0.0
) -> list[np.ndarray]:
    """Return the DH angles φ of an exact UR-type table for the flange pose (R, o).

    Up to 8 solutions; within ``near_deg`` of the wrist singularity, φ6 sampled round the turn
    (see :func:`_wrist`). A pose whose wrist point lies just inside the cylinder of radius
    D about axis 1 (shoulder singular; a calibrated arm's pose can, the structural table's
    cannot reach it; 0.25 % of D inside at a pose found in testing) gives the one shoulder
    seed on the cylinder, and Newton on the true model decides whether it is reachable.
    With ``near_deg`` > 0 and the two shoulders' φ1 within 2·:data:`PULL_DEG` (nearer
    would seed them nearer each other), they are also seeded :data:`PULL_DEG` either side
    of the cylinder (:func:`pulled`): hypothesis found a calibrated UR5 whose two shoulder
    branches are 1.6° apart in φ1, the structural table's one seed between them, Newton
    from it reaching only one.
    """
    dh = np.asarray(dh, dtype=float)
    alpha, a, _, d = dh.T
    base = _rot_x(alpha[0])
    Rb = base.T @ R
    ob = base.T @ o - np.array([a[0], 0.0, d[0]])
    s1, s4, s5 = (float(np.sign(np.sin(alpha[k]))) for k in (1, 4, 5))
    o5 = ob - d[5] * Rb[:, 2]
    y1v = -s1 * (d[1] + d[2] + d[3])
    r2 = o5[0] ** 2 + o5[1] ** 2
    x1 = np.sqrt(max(r2 - y1v**2, 0.0))  # inside the cylinder: Newton decides reachability
    half = float(np.arctan2(x1, abs(y1v)))  # half the angle between the shoulders' φ1
    reaches = [x1] + [abs(y1v) * np.tan(h) for h in pulled(half, min(near_deg, PULL_DEG))[1:]]
    out: list[np.ndarray] = []
    for x1v in [v for x in reaches for v in ((x, -x) if x > 0 else (0.0,))]:
        phi1 = float(np.arctan2(o5[1], o5[0]) - np.arctan2(y1v, x1v))
        z2 = -s1 * _rot_z(phi1)[:, 1]
        for phi5, phi6s, first_only in _wrist(Rb, z2, s4, s5, near_deg):
            for phi6 in phi6s:
                arm = _arm(dh, Rb, o5, phi1, phi5, phi6, near_deg)
                out += arm
                if arm and first_only:
                    break
    return out


def candidates(model: Model, R: np.ndarray, o: np.ndarray) -> list[np.ndarray]:
    """Joint angles q (rad) to polish: the closed form of the model's structural table."""
    dh = np.asarray(model.dh)
    s = structural(dh)
    near_deg = 0.0 if np.allclose(s, dh, rtol=0, atol=1e-12) else NEAR_SINGULAR_DEG
    return [phi - dh[:, 2] for phi in closed_form(s, R, o, near_deg)]


def configuration(model: Model, q: np.ndarray) -> tuple[str, str, str]:
    """Return wirecal's names of a UR-type solution's branches.

    Righty when o5 lies ahead of the joint-1 axis along x1 (the shoulder root's sign); flip
    when φ5 < 0. Above/below is the elbow's side of the line from o2 to o4 in the plane of
    the parallel axes, seen along the joint-2 axis, relative to the shoulder: above when
    z2 · ((o4 − o2) × (o3 − o2)) < 0 on a lefty arm, > 0 on a righty one (the elbow sign
    times the arm sign of Paul's PUMA solution). It is the elbow above the line wherever o4
    lies on the same side of the joint-1 axis as o5, and it changes only where the elbow
    is stretched or folded or the shoulder changes: the elbow's height alone changes where
    the line passes vertical, and on a calibrated arm the two elbow branches' lines pass it
    at different poses (hypothesis found a pose whose two branches' lines were 0.87° and
    1.17° from vertical, on either side of a switch between the two rules, both "below").

    Within :data:`ELBOW_NEAR_DEG` of the elbow stretched or folded, the side is read from
    the sign of the flange Jacobian's determinant instead: on the structural table
    det J = c · sin φ3 · sin φ5 · (o5 · x1) with c > 0, and z2 · ((o4 − o2) × (o3 − o2)) < 0
    exactly when sign(det J) · sign(sin φ5) · (1 if righty else −1) > 0; on any arm that
    sign changes exactly at the arm's own elbow singularity, which a calibrated arm moves
    off the fold (by about 0.3° on the tests' calibrated UR5): the two branches that meet
    there get two names (a scan near the fold found two lefty solutions 0.05° short of it,
    both "above" by their side of the line). The tests check that the name carries across
    the switch between the two rules.
    """
    q = np.asarray(q, dtype=float)
    f = frames(model, q[None])
    z1, x1 = f.z[0, 1], f.x[0, 1]
    o5 = f.o[0, 5] - f.o[0, 1]
    ahead = np.dot(o5 - np.dot(o5, z1) * z1, x1) >= 0
    phi = q + model.dh[:, 2]
    if abs(np.sin(phi[2])) < np.sin(np.radians(ELBOW_NEAR_DEG)):
        sin5 = np.sin(phi[4])
        side = (np.linalg.det(flange_jacobian(model, q, f)) > 0) ^ (sin5 > 0) ^ ahead
    else:
        o2, o3, o4 = f.o[0, 2], f.o[0, 3], f.o[0, 4]
        side = np.dot(f.z[0, 2], cross(o4 - o2, o3 - o2)) < 0
    phi5 = (phi[4] + np.pi) % (2 * np.pi) - np.pi
    return (
        "righty" if ahead else "lefty",
        "above" if side != ahead else "below",
        "flip" if phi5 < 0 else "noflip",
    )
