"""What an arm that does not return exactly to its poses does to the wire's readings.

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
:func:`expected_zero_mm`. The same rule sizes what the repeatability adds to the lengths'
scatter (:func:`length_sigma_mm`, the plausibility gates' noise model: ``solve``'s and,
through :func:`landing_sigma_mm`, ``fit``'s) and how far two zero readings may differ before
a slipped wire is suspected (:func:`slip_tolerance_mm`, the generated programs' check and
the log reader's).
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.distance import wire_vectors
from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.kinematics import Model, joint_jacobian

REACH_MM = 600.0
"""Lever (mm) at which the tool point scatters by half the repeatability (1σ) when every
joint errs by σ_q: the twin's rule for an arm of the Viper's size."""

CUBATURE_NODES = 16
"""Gauss–Hermite nodes per axis of the 3-D cubature of E‖δ‖ (16³ points: within 1 % of a
Monte Carlo of the twin's zero readings on the shipped arms)."""

SLIP_FACTOR = 5.84
"""k of the slip tolerance k·E‖δ‖: two zero readings of an arm that repeats as declared differ
by more with probability below 10⁻⁶ (the gate's false alarm,
:data:`~wirecal.solver.verdict.FALSE_ALARM`). ‖δa‖ − ‖δb‖ of two independent returns,
δ ~ N(0, Σ): its 1 − 10⁻⁶ quantile over E‖δ‖ is largest when Σ has rank 1 (δ along one
line, ‖δ‖ = σ·|z|: 4.654σ over σ·√(2/π), k = 5.832), 2.99 for an isotropic Σ (‖δ‖ = σ·χ₃);
the worst shape is taken, as the Σ at θ0 depends on the arm and θ0."""

SLIP_STEP_MM = 0.01
"""The slip tolerance is rounded up to this (mm), so the programs print what the PC checks."""


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


def length_sigma_mm(
    model: Model, q_rad: np.ndarray, theta0_rad: np.ndarray, repeatability_mm: float
) -> float:
    """Return the RMS over the points of what the arm's repeatability adds to a length (σ, mm).

    At configuration q_i the arm lands at q_i + δq (module docstring) and the wire's length
    moves by ∇ℓᵀ·J(q_i)·δq, of variance σ_q²·‖J(q_i)ᵀ·∇ℓ‖² (∇ℓ the modelled length's
    gradient, :func:`~wirecal.solver.exit_geometry.wire_path`; J ∂p/∂q). The RMS is the
    σ of one reading that a residual of all the points estimates.
    """
    v = wire_vectors(model, q_rad, theta0_rad)
    _, gradient = wire_path(model.pulley, v)  # none at a point on θ0's: taken as 0 there
    _, J = joint_jacobian(model, q_rad)
    return landing_sigma_mm(np.einsum("kc,kcn->kn", np.nan_to_num(gradient), J), repeatability_mm)


def landing_sigma_mm(gradient_mm_per_rad: np.ndarray, repeatability_mm: float) -> float:
    """Return the RMS over the rows of what landing adds to a length (σ, mm), from ∂ℓ/∂q.

    ``gradient_mm_per_rad`` (N, n): each row's length gradient in the joints; the arm
    lands at q + δq, δq ~ N(0, σ_q²·I) (:func:`joint_sigma_rad`), so the length moves by
    σ_q·‖∂ℓ/∂q‖ (1σ). The rule of :func:`length_sigma_mm` (the wire from θ0's tool point)
    and of ``wirecal fit``'s gate (the wire from its fitted anchor).
    """
    g = np.asarray(gradient_mm_per_rad, dtype=float)
    return joint_sigma_rad(repeatability_mm) * float(np.sqrt(np.mean(np.sum(g**2, axis=1))))


def slip_tolerance_mm(
    model: Model, theta0_deg: np.ndarray, repeatability_mm: float | None, floor_mm: float
) -> float:
    """Return the largest change between two zero readings that is not taken as a slip (mm).

    ``floor_mm`` (the ``--zero-tol`` given) without a declared repeatability; with one,
    the larger of it and :data:`SLIP_FACTOR`·E‖δ‖ (:func:`expected_zero_mm` at θ0), rounded
    up to :data:`SLIP_STEP_MM`: the generated programs' check and the log reader's.
    """
    if repeatability_mm is None:
        return floor_mm
    spread = SLIP_FACTOR * expected_zero_mm(model, theta0_deg, repeatability_mm)
    return max(floor_mm, round(float(np.ceil(spread / SLIP_STEP_MM)) * SLIP_STEP_MM, 9))
