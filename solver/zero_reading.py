"""What the zero readings at θ0 read on an arm that does not return exactly to θ0.

The wire is mounted so that its tip touches the tool at θ0 (paper §2.2: the measured
distance is zero there). An arm of repeatability r lands at θ0 + δq each time it returns,
δq ~ N(0, σ_q²·I) with σ_q = r/2 / :data:`REACH_MM` (the twin's rule,
:class:`~wirecal.solver.simulate.Unmodelled`): the tool point misses θ0's by δ = J·δq, and
the wire reads its length from the exit, ‖δ‖ for a point exit, which is never negative.
Each zero reading, and so the reference every length is read from (their mean), is E‖δ‖
long on average, not 0: 0.011–0.019 mm on the shipped arms at r = 0.02 mm, which would
shorten every wire length by as much and bias the geometry (d6, th6 by up to 2 σ with a
gauge). When the robot file gives the arm's repeatability
(``[calibration] repeatability_mm``), the lengths are read from the reference plus
:func:`expected_zero_mm`.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.kinematics import Model, joint_jacobian

REACH_MM = 600.0
"""Lever (mm) at which the tool point scatters by half the repeatability (1σ) when every
joint errs by σ_q: the twin's rule for an arm of the Viper's size."""

CUBATURE_NODES = 16
"""Gauss–Hermite nodes per axis of the 3-D cubature of E‖δ‖ (16³ points: within 1 % of a
Monte Carlo of the twin's zero readings on the shipped arms)."""


def joint_sigma_rad(repeatability_mm: float) -> float:
    """Return the joints' σ (rad) of an arm of this repeatability (module docstring)."""
    return 0.5 * repeatability_mm / REACH_MM


def expected_zero_mm(model: Model, theta0_deg: np.ndarray, repeatability_mm: float) -> float:
    """Return the mean wire length (mm) a zero reading at θ0 reads: E[ℓ(J·δq)].

    ℓ the modelled wire length of a tool point relative to the exit
    (:func:`~wirecal.solver.exit_geometry.wire_path`), δq ~ N(0, σ_q²·I). δ = J·δq is
    Gaussian with covariance σ_q²·J·Jᵀ = V·Λ·Vᵀ; E[ℓ(V·√Λ·z)] over z ~ N(0, I₃) by a
    tensor Gauss–Hermite cubature (deterministic: the same log, the same lengths).
    """
    _, J = joint_jacobian(model, np.radians(np.asarray(theta0_deg, dtype=float))[None])
    cov = joint_sigma_rad(repeatability_mm) ** 2 * J[0] @ J[0].T
    lam, V = np.linalg.eigh(cov)
    x, w = np.polynomial.hermite_e.hermegauss(CUBATURE_NODES)
    w = w / w.sum()
    z = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1).reshape(-1, 3)
    weight = np.einsum("i,j,k->ijk", w, w, w).ravel()
    delta = (z * np.sqrt(np.clip(lam, 0.0, None))) @ V.T
    length, _ = wire_path(model.pulley, delta)
    return float(weight @ length)


def length_scatter_mm(
    model: Model, q_deg: np.ndarray, theta0_deg: np.ndarray, repeatability_mm: float
) -> float:
    """Return the RMS over the points of the σ (mm) the arm's landing puts on a wire length.

    An arm of this repeatability lands at q + δq (module docstring), so the length of point
    i scatters by σ_q·‖J_iᵀ·∇ℓ_i‖ (J_i the tool point's joint Jacobian, ∇ℓ_i the wire
    length's gradient, :func:`~wirecal.solver.exit_geometry.wire_path`, at q_i). The
    residual of the points holds it; the reference gauge's readings, taken without the arm,
    do not.
    """
    q = np.radians(np.atleast_2d(np.asarray(q_deg, dtype=float)))
    p, J = joint_jacobian(model, q)
    p0, _ = joint_jacobian(model, np.radians(np.asarray(theta0_deg, dtype=float))[None])
    _, grad = wire_path(model.pulley, p - p0[0])
    g = np.einsum("ni,nij->nj", grad, J)
    return float(joint_sigma_rad(repeatability_mm) * np.sqrt(np.mean(np.sum(g**2, axis=1))))
