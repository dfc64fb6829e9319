"""A 3-D calibration from a laser tracker's x, y, z, and the held-out figure of any model.

A tracker measures the tool point in its own frame: x_i = R·p(q_i; e) + t, with p the
robot model's tool point (:func:`~wirecal.solver.kinematics.tool_jacobian`), e the DH errors
and the tool point, (R, t) the base frame in the tracker's, R = exp([ω]×)·R0 from the
nominal model's registration R0; wirecal's Levenberg–Marquardt
(:func:`~wirecal.solver.fit.solver.levenberg_marquardt`, as ``wirecal fit``'s) on

    ∂x/∂e = R·∂p/∂e,   ∂x/∂ω = −[R·p]×·J_l(ω),   ∂x/∂t = I,

J_l the left Jacobian of the rotations (:func:`_left_jacobian`).

Parameters: the tool point and the base frame always; then the DH errors of rows 2…n in
:func:`~wirecal.solver.fit.calibrate.candidates`' order, each kept when it raises the rank and
leaves every σ (from the residual of the tool-and-frame fit) below
:data:`~wirecal.solver.verdict.POORLY_IDENTIFIED` deg or mm
(:func:`~wirecal.solver.identifiability.select_columns`, which leaves a column zero to
round-off out: θ6 with the tool point on its axis). Row 1 is a rigid motion of the arm that
the base frame absorbs.

A model is judged on poses it was not fitted to by :func:`registered_rms_mm`: its tool
points rigidly registered onto the measured ones (Arun, Huang & Blostein 1987: the SVD of
the cross-covariance), then the RMS of the 3-D distance. A wire sees no base frame, so
every method is judged the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from wirecal.solver import params as P
from wirecal.solver.fit.calibrate import candidates
from wirecal.solver.fit.solver import minimised
from wirecal.solver.identifiability import select_columns
from wirecal.solver.kinematics import Model, tool_jacobian, tool_position, with_errors
from wirecal.solver.verdict import POORLY_IDENTIFIED

FRAME_NAMES = ("frame_rx", "frame_ry", "frame_rz", "frame_x", "frame_y", "frame_z")
"""The base frame's small rotation (rad) and translation (mm) in the tracker's frame."""


@dataclass(frozen=True)
class TrackerFit:
    """A 3-D calibration: the parameters (internal units), the model and the base frame."""

    names: tuple[str, ...]
    values: np.ndarray  # (m,) rad, mm
    model: Model
    rotation: np.ndarray  # (3, 3) base frame → tracker frame
    translation_mm: np.ndarray  # (3,)
    rms_mm: float  # 3-D RMS of the fitted poses


def register(p: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the rotation R and translation t that best map points ``p`` onto ``x`` (N, 3)."""
    pc, xc = p - p.mean(axis=0), x - x.mean(axis=0)
    u, _, vt = np.linalg.svd(pc.T @ xc)
    flip = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    rotation = (u @ flip @ vt).T
    return rotation, x.mean(axis=0) - p.mean(axis=0) @ rotation.T


def registered_rms_mm(p: np.ndarray, x: np.ndarray) -> float:
    """Return the 3-D RMS of ``x`` − ``p`` after ``p`` is rigidly registered onto ``x``."""
    rotation, t = register(p, x)
    return float(np.sqrt(np.mean(np.sum((p @ rotation.T + t - x) ** 2, axis=1))))


def _skew(v: np.ndarray) -> np.ndarray:
    """Return [v]× (N, 3, 3) of vectors (N, 3)."""
    s = np.zeros((len(v), 3, 3))
    s[:, 0, 1], s[:, 0, 2], s[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    return s - s.transpose(0, 2, 1)


def _jacobian(
    model: Model, q_rad: np.ndarray, names: tuple[str, ...], rotation: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return R·p (N, 3) and ∂x/∂(e, ω, t) stacked over the rows (3N, m + 6)."""
    p, jp = tool_jacobian(model, q_rad, names)
    rp = p @ rotation.T
    j = np.concatenate(
        [
            np.einsum("ij,njm->nim", rotation, jp),
            -_skew(rp),
            np.broadcast_to(np.eye(3), (len(p), 3, 3)),
        ],
        axis=2,
    )
    return rp, j.reshape(3 * len(p), -1)


def _left_jacobian(w: np.ndarray) -> np.ndarray:
    """Return J_l(ω) (3, 3): exp([ω + δ]×) ≈ exp([J_l(ω)·δ]×)·exp([ω]×) for small δ."""
    theta = float(np.linalg.norm(w))
    k = _skew(w[None])[0]
    if theta < 1e-8:
        return np.eye(3) + k / 2
    return (
        np.eye(3)
        + (1 - np.cos(theta)) / theta**2 * k
        + (theta - np.sin(theta)) / theta**3 * (k @ k)
    )


def residual_and_jacobian(
    base: Model,
    q_rad: np.ndarray,
    xyz_mm: np.ndarray,
    names: tuple[str, ...],
    rotation0: np.ndarray,
    v: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Return R·p + t − x (3N,) and its Jacobian (3N, m + 6) at v = (e, ω, t).

    R = exp([ω]×)·R0, ``rotation0`` R0 the rigid registration the fit starts from; the
    rotation's columns are :func:`_jacobian`'s (a turn δω applied on the left) times
    :func:`_left_jacobian` (module docstring).
    """
    m = len(names)
    rotation = Rotation.from_rotvec(v[m : m + 3]).as_matrix() @ rotation0
    rp, j = _jacobian(with_errors(base, names, v[:m]), q_rad, names, rotation)
    j[:, m : m + 3] = j[:, m : m + 3] @ _left_jacobian(v[m : m + 3])
    return (rp + v[m + 3 :] - xyz_mm).reshape(-1), j


def _least_squares(
    base: Model, q_rad: np.ndarray, xyz_mm: np.ndarray, names: tuple[str, ...]
) -> TrackerFit:
    """Return the least-squares fit of ``names`` and the base frame (module docstring).

    From the nominal model's rigid registration, by wirecal's Levenberg–Marquardt
    (:func:`~wirecal.solver.fit.solver.levenberg_marquardt`).
    """
    rotation0, t0 = register(tool_position(base, q_rad), xyz_mm)
    v0 = np.concatenate([np.zeros(len(names) + 3), t0])

    def evaluate(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return residual_and_jacobian(base, q_rad, xyz_mm, names, rotation0, v)

    v, r, _ = minimised(evaluate, v0)  # r: the residual at v, as the solver left it
    m = len(names)
    rotation = Rotation.from_rotvec(v[m : m + 3]).as_matrix() @ rotation0
    model = with_errors(base, names, v[:m])
    return TrackerFit(names, v[:m], model, rotation, v[m + 3 :], float(np.sqrt(r @ r / len(q_rad))))


def calibrate(
    base: Model, q_rad: np.ndarray, xyz_mm: np.ndarray, names: tuple[str, ...] | None = None
) -> TrackerFit:
    """Calibrate ``base`` from measured tool points ``xyz_mm`` (N, 3) at ``q_rad`` (N, n).

    ``names``: the parameters to fit (the tool point alone gives the nominal model's best
    case); None chooses the tool point and the identifiable DH errors (module docstring).
    """
    if names is not None:
        return _least_squares(base, q_rad, xyz_mm, names)
    first = _least_squares(base, q_rad, xyz_mm, P.TOOL_NAMES)
    full = (*P.TOOL_NAMES, *candidates(base))
    _, j = _jacobian(base, q_rad, full, first.rotation)
    j = np.concatenate(
        [P.ErrorSet(full, base.n_joints).per_boundary(j[:, : len(full)]), j[:, len(full) :]], axis=1
    )
    order = [*range(3), *range(len(full), len(full) + 6), *range(3, len(full))]
    limit = np.full(len(order), POORLY_IDENTIFIED)
    limit[:9] = np.inf
    sel = select_columns(
        j[:, order],
        [(*full, *FRAME_NAMES)[k] for k in order],
        9,
        sigma_mm=first.rms_mm / np.sqrt(3),
        max_std=limit,
    )
    kept = sorted(order[k] for k in sel.kept if order[k] < len(full))
    return _least_squares(base, q_rad, xyz_mm, tuple(full[k] for k in kept))
