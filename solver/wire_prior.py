"""One wire's fit with a prior where the data is weak (maximum a posteriori), and its plan's.

Sixty scalar readings of one wire carry the geometry unevenly: some combinations of DH
errors well, others barely (the ISO cubes of a tracker data set keep the tool's
orientation, and the wire then sees the wrist's errors hardly at all). Dropping the weakly
seen errors (an identifiability limit, then BIC) fixes them at the robot file's value,
all or nothing; keeping them fits the unmodelled part of the readings (gravity, heat, the
gears) into them. Here every DH error of rows 2…n (:func:`~wirecal.solver.fit.calibrate.candidates`)
is estimated, each with a zero-mean Gaussian prior: a length σ ``prior`` mm (the
planner's :attr:`~wirecal.solver.plan.options.PlanOptions.prior`, the size of a still
unknown offset), an angle the one that moves a point at the arm's longest link (a or d)
by as much (:func:`prior_sigma`; 0.05° for 0.5 mm on a UR10's 612 mm), so that neither
kind is favoured; each compliance asked with σ
:data:`~wirecal.solver.compliance.PRIOR_COMPLIANCE_URAD_PER_NM`: the data decide where they
are strong, the prior where they are weak, by the same weights for every combination (a
ridge in the identifiable combinations, not a choice of named parameters). The anchor,
the attachment and the length offset have no prior.

The estimate minimises Σ ρ(r_i²/f²)·f²/σ² + Σ (x_k/σ_k)², σ the readings' residual
(estimated from it, at least the readings' floor), refitted until σ settles; ρ is the
soft-L1 loss at f = :data:`ROBUST_SCALE`·σ (iteratively reweighted: each refit weighs a
reading by √ρ′ of its last residual; the first is least squares), since what is left of
a reading is not noise but the unmodelled part (0.2–0.27 mm on a UR10 against a tracker's
micrometres), and a few readings carry far more of it than the rest (series D, seed 0:
the largest 0.73 mm at σ 0.24 mm). How large the DH errors are
is the arm's: an arm far from its data sheet (the Tsinghua UR5, 2.6 mm before
calibration) widens the prior, by the evidence (:func:`map_fit`). The posterior
covariance (JᵀJ/σ² + Λ)⁻¹, Λ = diag(1/σ_k²), is what the pool planner minimises the tool
point's error with (:mod:`~wirecal.solver.plan.pool`), at the planner's ``prior``.

Why a prior and not BIC on the identifiable combinations: BIC keeps or drops whole
directions, and a weak direction dropped is fixed at the data sheet's value however large
the arm's own error along it, kept it is fitted to the unmodelled residual; the prior
shrinks each direction by how weakly the readings see it, continuously, the same for
every arm; and the planner's criterion (the posterior) is then the fit's own.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.compliance import PRIOR_COMPLIANCE_URAD_PER_NM
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import Pulley
from wirecal.solver.fit.calibrate import Data, candidates, nominal_floor, point_model, start
from wirecal.solver.fit.model import Layout, lengths_and_jacobian, model_of
from wirecal.solver.fit.solver import levenberg_marquardt
from wirecal.solver.identifiability import RANK_RTOL
from wirecal.solver.kinematics import Model
from wirecal.solver.memo import by_point
from wirecal.solver.params import TOOL_NAMES, ErrorSet
from wirecal.solver.robot import Robot

KEPT_POINTS = 8
"""Points whose lengths and Jacobian a fit keeps: the solver's end among the steps it
tried after it (:func:`~wirecal.solver.memo.by_point`)."""

SIGMA_PASSES = 3
"""Refits with the residual's σ: the first from the starting σ, each next from the last."""

PRIOR_SCALES = (1.0, 2.0, 4.0, 8.0)
"""The prior sizes tried, in units of the planner's ``prior``: the data choose by evidence."""


ROBUST_SCALE = 1.5
"""The soft-L1 loss's scale in units of the readings' σ: a reading off by more counts less."""


def soft_l1_weight(r: np.ndarray, f_scale: float) -> np.ndarray:
    """Return each row's weight √ρ′ of the soft-L1 loss ρ(z) = 2(√(1 + z) − 1), z = (r/f)²."""
    return (1.0 + (r / f_scale) ** 2) ** -0.25


def wire_layout(base: Model, compliances: tuple[str, ...] = ()) -> Layout:
    """Return the wire's parameters: the attachment, every DH error of rows 2…n, ``compliances``."""
    return Layout((*TOOL_NAMES, *candidates(base), *compliances), base.n_joints, 1, False)


def prior_sigma(base: Model, layout: Layout, prior: float) -> np.ndarray:
    """Return each parameter's prior σ, internal units (module docstring); inf: no prior."""
    sigma = np.full(len(layout.names), np.inf)
    g = len(layout.geometry)
    errors = ErrorSet(layout.geometry[len(TOOL_NAMES) :], layout.n_joints)
    link_mm = float(np.max(np.abs(base.dh[:, [1, 3]])))
    by_unit = {
        "mm": prior,
        "deg": np.degrees(prior / link_mm),
        "urad/Nm": PRIOR_COMPLIANCE_URAD_PER_NM,
    }
    sigma[len(TOOL_NAMES) : g] = errors.to_internal([by_unit[u] for u in errors.units])
    return sigma


@dataclass(frozen=True)
class WireMap:
    """The maximum a posteriori fit of one wire: model, parameters, the residual's σ."""

    model: Model
    layout: Layout
    x: np.ndarray  # internal units
    sigma_mm: float  # RMS of the readings' residual at x
    prior: float  # the prior's size the fit used (:func:`prior_sigma`'s ``prior``)


def _map_at(base: Model, layout: Layout, data: Data, prior: float) -> tuple[WireMap, float]:
    """Return the maximum a posteriori fit at prior size ``prior`` and its log evidence.

    σ of the readings starts at ``prior`` and is then the residual's RMS (at least
    ``data.floor_mm``), :data:`SIGMA_PASSES` times; each pass a Levenberg–Marquardt solve
    (:func:`~wirecal.solver.fit.solver.levenberg_marquardt`) of the readings' residual
    beside the prior's rows x_k·σ/σ_k. The evidence is Laplace's approximation
    (MacKay 1992): −χ²/2 − N·ln σ − ½ Σ (x_k/σ_k)² − Σ ln σ_k − ½ ln det H,
    H = JᵀJ/σ² + Λ, over the parameters with a prior (the others' terms do not depend on it).
    """
    sd = prior_sigma(base, layout, prior)
    weight = 1.0 / sd  # 0 where there is no prior
    q, length, session = data.q_rad, data.length_mm, data.session
    x, sigma = start(base, layout, data), prior
    robust = np.ones(len(length))  # the first pass: least squares
    at = by_point(lambda v: lengths_and_jacobian(base, layout, v, q, session), KEPT_POINTS)
    for _ in range(SIGMA_PASSES):
        w = sigma * weight

        def evaluate(
            v: np.ndarray, w: np.ndarray = w, robust: np.ndarray = robust
        ) -> tuple[np.ndarray, np.ndarray]:
            model_mm, jac = at(v)
            r, j = robust * (model_mm - length), robust[:, None] * jac
            return np.concatenate([r, w * v]), np.vstack([j, np.diag(w)])

        x = levenberg_marquardt(evaluate, x)
        r = at(x)[0] - length  # the solver's end: kept, as the next pass's start
        sigma = max(float(np.sqrt(np.mean(r**2))), data.floor_mm, 1e-9)
        robust = soft_l1_weight(r, ROBUST_SCALE * sigma)
    H, scale = _scaled_hessian(at(x)[1] / sigma, weight)
    has = np.isfinite(sd)
    evidence = (
        -len(r) / 2
        - len(r) * np.log(sigma)
        - 0.5 * float(np.sum((weight * x) ** 2))
        - float(np.sum(np.log(sd[has])))
        - 0.5 * (np.linalg.slogdet(H)[1] + 2 * float(np.sum(np.log(scale))))
    )
    return WireMap(model_of(base, layout, x), layout, x, sigma, prior), evidence


def map_fit(base: Model, layout: Layout, data: Data, prior: float) -> WireMap:
    """Return the maximum a posteriori estimate of ``layout`` from one session's ``data``.

    The prior's size is ``prior`` times the one of :data:`PRIOR_SCALES` of the largest
    evidence (:func:`_map_at`): an arm far from its data sheet widens its own prior.
    Starts at the nominal geometry (the anchor and offset by multilateration).
    """
    fits = [_map_at(base, layout, data, prior * k) for k in PRIOR_SCALES]
    return max(fits, key=lambda f: f[1])[0]


def check_exit(robot: Robot) -> None:
    """Refuse a guide pulley: the wire fit models a straight wire from a point (the anchor).

    Over a pulley the wire's length is an arc and a span the anchor cannot stand for, and
    the error budget leaves it out (the paper's model carries it); an eyelet's wrap is
    budgeted (``exit``), so it is taken.
    """
    if isinstance(robot.encoder.exit, Pulley):
        raise WirecalError(
            f'{robot.source}: [encoder] exit = "pulley": the wire fit of a plan from a pool '
            "models a straight wire from a point, which a guide pulley's arc is not: use "
            "'wirecal plan' (the paper's model carries the pulley), or an encoder with a "
            'point exit (exit = "point")'
        )


def fit_wire(
    robot: Robot,
    compliances: tuple[str, ...],
    q_deg: np.ndarray,
    length_mm: np.ndarray,
    prior: float,
    joint_resolution_deg: float,
) -> tuple[WireMap, Data]:
    """Return one wire's fit of ``robot`` from its readings, and the data it was fitted to.

    The one fit ``wirecal solve`` runs on a plan from a pool and the tracker replay scores:
    :func:`map_fit` of :func:`wire_layout` (``compliances`` beside the geometry) on
    :func:`~wirecal.solver.fit.calibrate.point_model`, one session, the floor from the
    encoder's count and ``joint_resolution_deg`` (a least σ of the readings). A guide
    pulley is refused (:func:`check_exit`).
    """
    check_exit(robot)
    base = point_model(robot)
    q_rad = np.radians(q_deg)
    session = np.zeros(len(q_rad), dtype=int)
    floor = nominal_floor(
        base,
        Data(q_rad, length_mm, session, 0.0),
        joint_resolution_deg,
        abs(robot.encoder.mm_per_count),
    )
    data = Data(q_rad, length_mm, session, floor)
    return map_fit(base, wire_layout(base, compliances), data, prior), data


@dataclass(frozen=True)
class Posterior:
    """The linearised posterior of a :class:`WireMap` at its estimate (internal units).

    With J the readings' Jacobian, σ the residual's, Λ the prior's precision and
    P = (JᵀJ/σ² + Λ)⁻¹: ``map`` M = P·Jᵀ/σ² (a length error δd moves the estimate by M·δd),
    ``noise`` σ²·M·Mᵀ (the readings' share of P), ``prior_share`` the prior's,
    (M·J − I)·Λ⁻¹·(M·J − I)ᵀ over the parameters with a prior (the shrinkage toward zero of
    what the readings see weakly); ``noise`` + ``prior_share`` = P. ``effective`` is the
    count of parameters the readings carry, trace(J·M) (≤ the parameters), ``sigma_mm`` the
    residual's σ on N − ``effective`` degrees of freedom (at least the readings' floor).
    """

    map: np.ndarray  # (k, N)
    noise: np.ndarray  # (k, k)
    prior_share: np.ndarray  # (k, k)
    prior_sd: np.ndarray  # (k,) inf: no prior
    effective: float
    sigma_mm: float
    residual_mm: np.ndarray  # (N,) model − measured at the estimate
    jacobian: np.ndarray  # (N, k) ∂L/∂x at the estimate


def _scaled_hessian(J: np.ndarray, weight: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return H = JᵀJ + diag(``weight``²) over its column scales, and the scales.

    ``J`` the readings' Jacobian over their σ; each column scaled by the larger of its
    norm and its prior's weight, so that H's conditioning is the problem's, not the units'.
    """
    scale = np.maximum(np.linalg.norm(J, axis=0), weight)
    return (J.T @ J + np.diag(weight**2)) / np.outer(scale, scale), scale


def _gain(J: np.ndarray, sigma_mm: float, weight: np.ndarray) -> np.ndarray:
    """Return M = P·Jᵀ/σ², P = (JᵀJ/σ² + Λ)⁻¹, Λ = diag(``weight``²)."""
    H, scale = _scaled_hessian(J / sigma_mm, weight)
    P = np.linalg.pinv(H, rcond=RANK_RTOL, hermitian=True) / np.outer(scale, scale)
    return P @ J.T / sigma_mm**2


def posterior(base: Model, fit: WireMap, data: Data) -> Posterior:
    """Return the posterior of ``fit`` (:class:`Posterior`) at the prior size it chose.

    The count the readings carry is taken at the σ the fit weighed the prior with
    (``fit.sigma_mm``, the residual's RMS); the posterior at the σ on the degrees of freedom
    left, N − ``effective`` (larger: the RMS of a fit of many parameters is short of the
    readings' σ).
    """
    layout, x = fit.layout, fit.x
    r, J = lengths_and_jacobian(base, layout, x, data.q_rad, data.session)
    r = r - data.length_mm
    sd = prior_sigma(base, layout, fit.prior)
    effective = float(np.trace(J @ _gain(J, fit.sigma_mm, 1.0 / sd)))
    sigma = max(float(np.sqrt(r @ r / max(len(r) - effective, 1.0))), data.floor_mm)
    M = _gain(J, sigma, 1.0 / sd)
    B = (M @ J - np.eye(len(x)))[:, np.isfinite(sd)]
    return Posterior(
        M, sigma**2 * M @ M.T, B * sd[np.isfinite(sd)] ** 2 @ B.T, sd, effective, sigma, r, J
    )
