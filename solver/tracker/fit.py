"""A 3-D calibration from a laser tracker's x, y, z, and the held-out figure of any model.

A tracker measures the tool point in its own frame: x_i = R·p(q_i; e) + t, with p the
robot model's tool point (:func:`~wirecal.solver.kinematics.tool_jacobian`), e the DH errors
and the tool point, (R, t) the base frame in the tracker's. Gauss–Newton, the rotation
updated multiplicatively (R ← exp([δω]×)·R), damped (Levenberg–Marquardt):

    ∂x/∂e = R·∂p/∂e,   ∂x/∂ω = −[R·p]×,   ∂x/∂t = I.

Parameters: the tool point and the base frame always; then the DH errors of rows 2…n in
:func:`~wirecal.solver.fit.calibrate.candidates`' order, each kept when it raises the rank and
leaves every σ (from the residual of the tool-and-frame fit) below
:data:`~wirecal.solver.verdict.POORLY_IDENTIFIED` deg or mm
(:func:`~wirecal.solver.identifiability.select_columns`). Row 1 is a rigid motion of the
arm that the base frame absorbs.

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
from wirecal.solver.identifiability import select_columns
from wirecal.solver.kinematics import Model, tool_jacobian, tool_position, with_errors
from wirecal.solver.verdict import POORLY_IDENTIFIED

FRAME_NAMES = ("frame_rx", "frame_ry", "frame_rz", "frame_x", "frame_y", "frame_z")
"""The base frame's small rotation (rad) and translation (mm) in the tracker's frame."""

ITERATIONS = 50
"""Levenberg–Marquardt steps at most; it stops earlier when a step gains nothing."""


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


State = tuple[np.ndarray, np.ndarray, np.ndarray]
"""A fit's state: the parameters e (internal units), the rotation R and the translation t."""


def _apply(fit: State, step: np.ndarray) -> State:
    """Return (e, R, t) moved by a step (δe, δω, δt)."""
    values, rotation, t = fit
    m = len(values)
    turn = Rotation.from_rotvec(step[m : m + 3]).as_matrix()
    return values + step[:m], turn @ rotation, t + step[m + 3 :]


def _residual(
    base: Model, q_rad: np.ndarray, xyz_mm: np.ndarray, names: tuple[str, ...], fit: State
) -> np.ndarray:
    """Return the residual x − (R·p + t) of every row (N, 3)."""
    values, rotation, t = fit
    return xyz_mm - tool_position(with_errors(base, names, values), q_rad) @ rotation.T - t


def _least_squares(
    base: Model, q_rad: np.ndarray, xyz_mm: np.ndarray, names: tuple[str, ...]
) -> TrackerFit:
    """Return the least-squares fit of ``names`` and the base frame (module docstring).

    Levenberg–Marquardt on the column-scaled Gauss–Newton steps: a step that does not lower
    the sum of squares is refused and the damping raised.
    """
    fit: State = (np.zeros(len(names)), *register(tool_position(base, q_rad), xyz_mm))
    cost = float(np.sum(_residual(base, q_rad, xyz_mm, names, fit) ** 2))
    damping = 1e-6
    for _ in range(ITERATIONS):
        _, j = _jacobian(with_errors(base, names, fit[0]), q_rad, names, fit[1])
        r = _residual(base, q_rad, xyz_mm, names, fit).reshape(-1)
        scale = np.maximum(np.linalg.norm(j, axis=0), 1e-12)
        js = j / scale
        a, g = js.T @ js, js.T @ r
        while damping < 1e6:
            step = np.linalg.solve(a + damping * np.eye(len(g)), g) / scale
            trial = _apply(fit, step)
            new = float(np.sum(_residual(base, q_rad, xyz_mm, names, trial) ** 2))
            if new < cost:
                break
            damping *= 10
        else:
            break
        fit, damping, small = trial, damping / 10, cost - new < 1e-12 * cost
        cost = new
        if small:
            break
    model = with_errors(base, names, fit[0])
    return TrackerFit(names, fit[0], model, fit[1], fit[2], float(np.sqrt(cost / len(q_rad))))


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
