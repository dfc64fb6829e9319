"""Identification of the error parameters from wire lengths.

* :func:`stepwise` — the paper's procedure (§2.3 and its flowchart): for step j, minimise
  f_cost(δe_j) = Σ_{i∈S_j} (d_i(δe) − d̃_i)² (eq. 4) over δe_j ∈ Ω_j (eq. 20), earlier
  parameters at their estimates and later ones at nominal. The bounded scalar minimisation
  is a projected Gauss–Newton iteration with the analytic derivative and step halving,
  so the cost never increases; it runs for T data sets at once (Monte Carlo).
* :func:`joint` — all parameters together by nonlinear least squares
  (``scipy.optimize.least_squares``, analytic Jacobian) from the stepwise result, with
  standard deviations and correlations from the residual.

Values are internal units (rad, mm) inside; :class:`Estimate` reports deg and mm.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.identifiability import covariance, std_and_correlation
from wirecal.solver.kinematics import Model, loaded, with_errors
from wirecal.solver.memo import Kept, by_point, digest
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.scale import PPM

DEFAULT_OMEGA = 5.0
"""Default bound Ω_j: ±5 deg for angles, ±5 mm for lengths."""

Loss = Literal["linear", "soft_l1", "huber", "cauchy", "arctan"]
"""The losses of ``scipy.optimize.least_squares`` that :func:`joint` accepts."""


def omega_vector(
    names: tuple[str, ...], n_joints: int, plan: Plan, default: float = DEFAULT_OMEGA
) -> np.ndarray:
    """Ω_j per parameter in internal units: the plan's per-step ``omega`` or the default."""
    by_step = {s.parameter: s.omega for s in plan.steps}
    bound = np.array([by_step.get(n) or default for n in names], dtype=float)
    return ErrorSet(names, n_joints).to_internal(bound)


def at_points(model: Model, plan: Plan, present: np.ndarray | None = None) -> Model:
    """Return ``model`` as it is at ``plan``'s points (those ``present``): loads mounted.

    The points of a payload step carry its mass (:meth:`Plan.loads`); without one, the
    model itself.
    """
    loads = plan.loads()
    if loads is None:
        return model
    kg = loads[0] if present is None else loads[0][present]
    return loaded(model, kg, loads[1])


@dataclass(frozen=True)
class Problem:
    """The data of one calibration: points, θ0, measured lengths, the plan's steps.

    ``d`` is (N,) for one data set or (T, N) for T data sets measured at the same points.
    """

    base: Model
    names: tuple[str, ...]  # identification order (the plan's order)
    q: np.ndarray  # (N, n) radians
    q0: np.ndarray  # (n,) radians
    d: np.ndarray  # (N,) or (T, N) mm
    step: np.ndarray  # (N,) 1-based step of each point
    load_kg: np.ndarray | None = None  # (N,) the mass at the flange per point (payload step)
    load_com_mm: np.ndarray | None = None  # its centre in the last frame

    @property
    def errors(self) -> ErrorSet:
        """The parameters, in identification order, with their units."""
        return ErrorSet(self.names, self.base.n_joints)

    def at(self, x: np.ndarray | None = None) -> Model:
        """Return the model at offsets ``x`` (None: the base) at the points ``q``: loads on."""
        model = self.base if x is None else with_errors(self.base, self.names, x)
        if self.load_kg is None:
            return model
        return loaded(
            model, self.load_kg, np.zeros(3) if self.load_com_mm is None else self.load_com_mm
        )

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Return the model's wire lengths minus the measured ones (mm) at offsets ``x``."""
        return wire_lengths(self.at(x), self.q, self.q0) - self.d


@dataclass(frozen=True)
class StepResult:
    """Diagnostics of one step (boundary units: deg, mm)."""

    parameter: str
    estimate: float
    n_points: int
    rms_before_mm: float  # with δe_j = 0, earlier estimates in place
    rms_after_mm: float
    psi_strength: float  # RMS of |Ψ_j| over the step's points
    omega: float
    on_bound: bool
    leak: dict[str, float]  # later t: bias of this estimate per unit error of t
    iterations: int

    @property
    def worst_leak(self) -> tuple[str, float] | None:
        """Return the later parameter with the largest leak and its coefficient (None: none)."""
        if not self.leak:
            return None
        name = max(self.leak, key=lambda t: abs(self.leak[t]))
        return name, self.leak[name]


@dataclass(frozen=True)
class Estimate:
    """Identified offsets in boundary units (deg for th*/al*, mm for a*/d*)."""

    method: str
    names: tuple[str, ...]
    values: np.ndarray
    residual_rms_mm: float
    std: np.ndarray | None = None
    correlation: np.ndarray | None = None
    steps: tuple[StepResult, ...] = ()
    scale_ppm: float | None = None  # the joint method's refinement of the encoder scale
    scale_std_ppm: float | None = None

    def as_dict(self) -> dict[str, float]:
        """Return the offsets by parameter name (boundary units)."""
        return {n: float(v) for n, v in zip(self.names, self.values, strict=True)}

    def std_by_name(self) -> dict[str, float]:
        """Return the σ by parameter name (boundary units; inf: unidentified); empty without."""
        if self.std is None:
            return {}
        return {n: float(s) for n, s in zip(self.names, self.std, strict=True)}


@dataclass(frozen=True)
class StepDiagnostics:
    """What one step of :func:`stepwise` did, per data set (arrays of length T)."""

    n_points: int
    iterations: int
    rms_before_mm: np.ndarray  # (T,) with δe_j = 0, earlier estimates in place; NaN if no points
    rms_after_mm: np.ndarray  # (T,)


STEP_TOL = 1e-10
"""A step's iteration stops when δe_j moves less than this (rad or mm): far below any
physical effect, and above the round-off of the Gauss–Newton step itself."""


def stepwise(
    problem: Problem, omega: np.ndarray, *, max_iter: int = 50
) -> tuple[np.ndarray, list[StepDiagnostics]]:
    """Run the paper's step-by-step identification for T data sets at once.

    ``omega`` (m,) bounds each parameter in internal units. Returns the estimates
    (T, m) or (m,) and, per step, its :class:`StepDiagnostics` over T. Kept by the contents
    of its inputs (:data:`KEPT_SOLUTIONS`); each caller is given its own copy.
    """
    key = digest("stepwise", problem, omega, max_iter)
    return _SOLUTIONS.copy_of(key, lambda: _stepwise(problem, omega, max_iter))


KEPT_SOLUTIONS = 64
"""How many identifications (:func:`stepwise`, :func:`joint`) are kept by their inputs'
contents (:mod:`~wirecal.solver.memo`): a log is solved again with the same plan and
robot (the report solves it, then its comparison with the controller's answer; the
plausibility gate's refusal, then the override), and it is the same computation."""

_SOLUTIONS: Kept = Kept(KEPT_SOLUTIONS)


def _stepwise(
    problem: Problem, omega: np.ndarray, max_iter: int
) -> tuple[np.ndarray, list[StepDiagnostics]]:
    """Return :func:`stepwise` computed."""
    d = np.atleast_2d(problem.d)
    x = np.zeros((d.shape[0], len(problem.names)))
    info = []
    for j in range(len(problem.names)):
        sel = problem.step == j + 1
        info.append(_solve_step(problem, x, j, sel, d[:, sel], omega[j], max_iter))
    return (x if np.ndim(problem.d) == 2 else x[0]), info


def _solve_step(
    problem: Problem,
    x: np.ndarray,
    j: int,
    sel: np.ndarray,
    dj: np.ndarray,
    omega_j: float,
    max_iter: int,
) -> StepDiagnostics:
    """Minimise step j's cost over x[:, j] ∈ [−Ω_j, Ω_j] in place (eq. 20)."""
    T, k = dj.shape
    if k == 0:
        return StepDiagnostics(0, 0, np.full(T, np.nan), np.full(T, np.nan))
    qj, name = problem.q[sel], problem.names[j]

    def evaluated(xj: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x[:, j] = xj
        dist, dd = wire_jacobian(
            with_errors(problem.base, problem.names, x), qj, problem.q0, [name]
        )
        r = dist.reshape(T, k) - dj
        return (r * r).sum(axis=1), r, dd.reshape(T, k)

    # The point and a trial kept: a step clipped at the bound asks for the point again.
    evaluate = by_point(evaluated, 2)
    xj = np.zeros(T)
    cost, r, g = evaluate(xj)
    before = cost
    active = np.ones(T, dtype=bool)
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        gn = -(r * g).sum(axis=1) / np.maximum((g * g).sum(axis=1), 1e-300)
        trial = np.where(active, np.clip(xj + gn, -omega_j, omega_j), xj)
        new_cost, new_r, new_g = evaluate(trial)
        # Halve the step where the cost rose, so the cost never increases.
        for _ in range(30):
            worse = active & (new_cost > cost * (1 + 1e-10))
            if not np.any(worse):
                break
            trial = np.where(worse, 0.5 * (xj + trial), trial)
            new_cost, new_r, new_g = evaluate(trial)
        active &= np.abs(trial - xj) > STEP_TOL
        xj, cost, r, g = trial, new_cost, new_r, new_g
        if not np.any(active):
            break
    x[:, j] = xj
    return StepDiagnostics(k, it, np.sqrt(before / k), np.sqrt(cost / k))


def leak_coefficients(psi: np.ndarray, step: np.ndarray, names: tuple[str, ...]) -> list[dict]:
    """Return, per step j, the bias of δê_j per unit error of each later parameter t.

    From the linearised step (Ψ_j·Ψ_t / Ψ_j·Ψ_j over the step's points, boundary units).
    """
    out = []
    for j in range(len(names)):
        sel = step == j + 1
        pj = psi[sel, j]
        denom = float(pj @ pj)
        out.append(
            {
                names[t]: (float(pj @ psi[sel, t]) / denom if denom > 0 else np.nan)
                for t in range(j + 1, len(names))
            }
        )
    return out


def run_stepwise(problem: Problem, omega: np.ndarray, psi: np.ndarray) -> Estimate:
    """Run the stepwise method on one data set, with its per-step diagnostics."""
    x, info = stepwise(problem, omega)
    x_b, omega_b = problem.errors.to_boundary(x), problem.errors.to_boundary(omega)
    leaks = leak_coefficients(psi, problem.step, problem.names)
    steps = []
    for j, name in enumerate(problem.names):
        sel = problem.step == j + 1
        steps.append(
            StepResult(
                parameter=name,
                estimate=float(x_b[j]),
                n_points=info[j].n_points,
                rms_before_mm=float(info[j].rms_before_mm[0]),
                rms_after_mm=float(info[j].rms_after_mm[0]),
                psi_strength=float(np.sqrt(np.mean(psi[sel, j] ** 2))) if np.any(sel) else 0.0,
                omega=float(omega_b[j]),
                on_bound=bool(abs(x[j]) >= omega[j] * (1 - 1e-9)),
                leak=leaks[j],
                iterations=info[j].iterations,
            )
        )
    r = problem.residuals(x)
    return Estimate(
        "stepwise", problem.names, x_b, float(np.sqrt(np.mean(r**2))), steps=tuple(steps)
    )


@dataclass(frozen=True)
class ScalePrior:
    """The encoder scale as an extra unknown of the joint method.

    The lengths are read as (1 + s)·d̃; the reference gauge says s = 0 ± ``std`` (the
    lengths already carry its estimate). ``weight`` = σ_reading/σ_s turns the prior into
    one more residual row, w·s, of the same units as the others.
    """

    std: float
    weight: float


def joint(
    problem: Problem,
    x0: np.ndarray,
    *,
    loss: Loss = "linear",
    f_scale_mm: float = 0.05,
    scale: ScalePrior | None = None,
) -> Estimate:
    """All parameters together, nonlinear least squares from ``x0`` (internal units).

    σ of the residual, (JᵀJ)⁻¹ and the correlations come from the solution, rank-aware:
    a parameter the points do not identify gets σ = inf and NaN correlations; a robust
    ``loss`` (e.g. "soft_l1", with ``f_scale_mm`` the inlier scale) resists outliers.
    With ``scale`` the encoder's scale s is refined too: residuals d(e) − (1 + s)·d̃ and the
    prior row w·s, Jacobian column ∂/∂s = −d̃ (and w on the prior row); its estimate and σ
    are ``scale_ppm``/``scale_std_ppm``, and the parameters' σ then carry the scale's
    uncertainty. Kept by the contents of its inputs (:data:`KEPT_SOLUTIONS`); each caller
    is given its own copy.
    """
    key = digest("joint", problem, x0, loss, f_scale_mm, scale)
    return _SOLUTIONS.copy_of(key, lambda: _joint(problem, x0, loss, f_scale_mm, scale))


def _joint(
    problem: Problem, x0: np.ndarray, loss: Loss, f_scale_mm: float, scale: ScalePrior | None
) -> Estimate:
    """Return :func:`joint` computed."""
    m = len(problem.names)
    evaluate = _evaluator(problem, scale)

    x = _minimise(evaluate, x0 if scale is None else np.append(x0, 0.0), loss, f_scale_mm)
    r, J = evaluate(x)
    # Boundary units, so that the rank tolerance compares deg with mm, not rad with mm.
    Jb = problem.errors.per_boundary(J[:, :m])
    if scale is not None:
        Jb = np.column_stack([Jb, J[:, m]])
    std, corr = _std_and_correlation(r, Jb, problem.d.size, m)
    scale_ppm = scale_std_ppm = None
    if scale is not None:
        scale_ppm = float(x[m]) / PPM
        scale_std_ppm = None if std is None else float(std[m]) / PPM
        std = None if std is None else std[:m]
        corr = None if corr is None else corr[:m, :m]
    return Estimate(
        "joint",
        problem.names,
        problem.errors.to_boundary(x[:m]),
        float(np.sqrt(np.mean(r[: problem.d.size] ** 2))),
        std=std,
        correlation=corr,
        scale_ppm=scale_ppm,
        scale_std_ppm=scale_std_ppm,
    )


KEPT_POINTS = 4
"""Points whose residuals and Jacobian :func:`joint`'s evaluator keeps (the solution is
often one the solver evaluated a step or two before it stopped)."""


def _evaluator(
    problem: Problem, scale: ScalePrior | None
) -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Return x ↦ (residuals, Jacobian) of :func:`joint`'s problem (internal units).

    One pass over the chain gives both, kept for the same x (the solver asks for the
    residuals and the Jacobian of a point one after the other, and a point it moved from
    again: :data:`KEPT_POINTS` of them are kept, :func:`~wirecal.solver.memo.by_point`).
    """
    m = len(problem.names)

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Residuals and Jacobian from one pass over the chain."""
        d, J = wire_jacobian(problem.at(x[:m]), problem.q, problem.q0, problem.names)
        if scale is None:
            return d - problem.d, J
        s = x[m]
        r = np.append(d - (1 + s) * problem.d, scale.weight * s)
        col = np.append(-problem.d, scale.weight)
        return r, np.column_stack([np.vstack([J, np.zeros(m)]), col])

    kept = by_point(evaluate, KEPT_POINTS)

    def copied(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return copies of the kept residuals and Jacobian.

        With a robust loss SciPy's "trf" scales the arrays it is given in place
        (``scale_for_robust_loss_function``): the kept ones must stay as evaluated.
        """
        r, J = kept(x)
        return r.copy(), J.copy()

    return copied


def _minimise(
    evaluate: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]],
    x0: np.ndarray,
    loss: Loss,
    f_scale_mm: float,
) -> np.ndarray:
    """Return the x that minimises the residuals of ``evaluate`` from ``x0``.

    MINPACK's Levenberg–Marquardt for plain least squares; a robust loss needs "trf".
    """
    from scipy.optimize import least_squares  # imported here: code generation needs Ω only

    def residuals(x: np.ndarray) -> np.ndarray:
        return evaluate(x)[0]

    def jacobian(x: np.ndarray) -> np.ndarray:
        return evaluate(x)[1]

    method: Literal["lm", "trf"] = "lm" if loss == "linear" else "trf"
    res = least_squares(
        residuals,
        x0,
        jac=jacobian,
        method=method,
        loss=loss,
        f_scale=f_scale_mm,
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=200,
    )
    return res.x


def _std_and_correlation(
    r: np.ndarray, Jb: np.ndarray, n_lengths: int, m: int
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Return the σ and correlations of a solution, rank-aware (None without spare rows).

    ``r`` and ``Jb`` (boundary units) are the residuals and Jacobian at the solution;
    σ² of a reading from the first ``n_lengths`` residuals over the ``m`` parameters. A
    parameter the points do not identify gets σ = inf and NaN correlations.
    """
    if r.size <= Jb.shape[1]:
        return None, None
    sigma2 = float(r[:n_lengths] @ r[:n_lengths]) / (n_lengths - m)
    cov, identified = covariance(Jb, sigma2)
    sd, corr = std_and_correlation(cov)
    corr[~identified] = np.nan
    corr[:, ~identified] = np.nan
    return np.where(identified, sd, np.inf), corr
