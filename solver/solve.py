"""Provide ``wirecal solve`` as a Python function.

Measurements in, both methods' estimates out, with residuals and the predicted
post-calibration accuracy.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from wirecal.solver.accuracy import workspace
from wirecal.solver.budget import (
    Budget,
    ComplianceTerms,
    Sources,
    budget,
    least_squares_map,
    sources,
)
from wirecal.solver.compliance import (
    COMPLIANCE_RANGE_URAD_PER_NM,
    ComplianceObservability,
    compliance_observability,
)
from wirecal.solver.distance import wire_jacobian
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.identifiability import covariance
from wirecal.solver.identify import (
    DEFAULT_OMEGA,
    Estimate,
    Loss,
    Problem,
    ScalePrior,
    joint,
    omega_vector,
    run_stepwise,
)
from wirecal.solver.kinematics import Model
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.exit import unmodelled_exit_mm
from wirecal.solver.robot import Robot
from wirecal.solver.scale import PPM, Drift, ScaleEstimate, estimate_scale, fit_drift
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.simulate import sag_lengths_mm
from wirecal.solver.solve_pool import PoolSolution, PriorFit, pool_estimate
from wirecal.solver.verdict import READING_NOISE_MM
from wirecal.solver.zero_reading import length_sigma_mm

METHODS = ("stepwise", "joint")
STEPWISE_BUDGET_MISS = 1.36
"""How far the stepwise budget fell short of its Monte Carlo error at worst
(``bench/bench_encoder.py``, the designed plan with the reference step)."""

UNIDENTIFIED = {"mean": math.inf, "max": math.inf}
"""The predicted tool error when the points leave a direction of the parameters unseen."""


@dataclass(frozen=True)
class SolveResult:
    """The estimates of a solve, their predicted accuracy, and what they were solved from."""

    robot: Robot
    plan: Plan
    measurements: Measurements
    estimates: dict[str, Estimate]
    predicted: dict[str, dict[str, float]]  # method -> tool-point error mean/max (mm)
    sigma_mm: float  # noise σ estimated from the joint residual
    left_nominal: tuple[str, ...]  # parameters whose step has no points
    psi: np.ndarray  # (N, k) Ψ at the measured points, columns the estimates' names (paper §2.2)
    step: np.ndarray  # (N,) 1-based step in the plan's order of each measured point
    budgets: dict[str, Budget] = field(default_factory=dict)  # method -> error budget
    scale: ScaleEstimate | None = None  # from the log's reference rows
    drift: Drift | None = None  # the zero readings' drift (timed logs)
    encoder_notes: tuple[str, ...] = ()  # what was done about the scale and the drift
    compliance: ComplianceObservability | None = None  # the compliances the file asked for
    prior: PriorFit | None = None  # a plan from a pool: the wire fit with a prior it ran

    @property
    def names(self) -> tuple[str, ...]:
        """The identified parameters (the plan's order, less ``left_nominal``)."""
        return tuple(n for n in self.plan.order if n not in self.left_nominal)

    @property
    def listed(self) -> tuple[str, ...]:
        """The parameters the estimates list: the plan's order, or a pool fit's own.

        A plan from a pool is solved for every DH error of rows 2…n, the attachment and the
        compliances (:mod:`~wirecal.solver.solve_pool`), not its ``order`` alone.
        """
        return self.plan.order if self.prior is None else self.estimates["joint"].names

    @property
    def unchecked(self) -> tuple[str, ...]:
        """Name each step whose closing zero check is missing, and what that hides.

        E.g. 'step 10 (a1) unchecked: the closing zero reading at θ0 is missing, so a wire
        slip during step 10 is invisible'.
        """
        m, n_steps = self.measurements, len(self.plan.steps)
        out = []
        for s in m.unchecked:
            after = (
                "the closing zero reading" if s == n_steps else f"the zero reading of step {s + 1}"
            )
            old = " (a version 1 log has none)" if s == n_steps and m.log.version < 2 else ""
            out.append(
                f"step {s} ({self.plan.order[s - 1]}) unchecked: {after} at θ0 is missing{old}, "
                f"so a wire slip during step {s} is invisible"
            )
        return tuple(out)

    @property
    def recommended(self) -> str:
        """The method with the smaller predicted tool-point error (joint when tied).

        The stepwise prediction counts :data:`STEPWISE_BUDGET_MISS` times its budget, which
        leaves out the bias later parameters leak into earlier steps: when the scale or the
        sag dominate both budgets alike, a near tie goes to the joint method.
        """

        def key(m: str) -> tuple[float, bool]:
            miss = STEPWISE_BUDGET_MISS if m == "stepwise" else 1.0
            return (miss * self.predicted[m]["mean"], m != "joint")

        return min(self.estimates, key=key)

    def as_json(self) -> dict[str, Any]:
        """Return what ``wirecal solve --json`` prints."""
        methods: dict[str, Any] = {}
        for name, est in self.estimates.items():
            entry: dict[str, Any] = {
                "parameters": est.as_dict(),
                "residual_rms_mm": est.residual_rms_mm,
                "predicted_tool_error_mm": {k: _finite(v) for k, v in self.predicted[name].items()},
            }
            if est.std is not None and est.correlation is not None:  # set together
                entry["std"] = {n: _finite(s) for n, s in est.std_by_name().items()}
                entry["correlation"] = {
                    a: {b: _finite(est.correlation[i, k]) for k, b in enumerate(est.names)}
                    for i, a in enumerate(est.names)
                }
            if est.steps:
                entry["steps"] = [
                    {
                        "step": j + 1,
                        "parameter": s.parameter,
                        "estimate": s.estimate,
                        "points": s.n_points,
                        "rms_before_mm": s.rms_before_mm,
                        "rms_after_mm": s.rms_after_mm,
                        "psi_strength": s.psi_strength,
                        "omega": s.omega,
                        "on_bound": s.on_bound,
                        "leak": s.leak,
                        "iterations": s.iterations,
                    }
                    for j, s in enumerate(est.steps)
                ]
            methods[name] = entry
        m = self.measurements
        extra = {} if self.compliance is None else {"compliance": self.compliance.as_json()}
        if self.prior is not None:
            extra["pool_fit"] = self.prior.as_json()
        return {
            "robot": self.robot.name,
            "plan": self.plan.fingerprint(),
            "log": m.source,
            "log_sha256": m.sha256,
            "order": list(self.plan.order),
            "methods": methods,
            "recommended": self.recommended,
            "residual_rms_mm": {n: e.residual_rms_mm for n, e in self.estimates.items()},
            "sigma_mm": _finite(self.sigma_mm),
            "missing": [{"step": s, "index": i} for s, i in m.missing],
            "left_nominal": list(self.left_nominal),
            "unchecked": [
                {"step": s, "parameter": self.plan.order[s - 1], "warning": w}
                for s, w in zip(m.unchecked, self.unchecked, strict=True)
            ],
            "notes": list(m.notes),
            "encoder": self._encoder_json(),
            **extra,
        }

    def _encoder_json(self) -> dict[str, Any]:
        """Return the scale, the drift and each method's error budget for ``--json``."""
        sc, dr = self.scale, self.drift
        return {
            "scale": None
            if sc is None
            else {
                "ppm": sc.ppm,
                "std_ppm": sc.std_ppm,
                "pairs": sc.pairs,
                "reference_length_mm": sc.reference_length_mm,
                "measured_mm": sc.measured_mm.tolist(),
            },
            "scale_tolerance_ppm": self.robot.encoder.scale_tolerance_ppm,
            "drift": None
            if dr is None
            else {
                "mm_per_h": dr.rate_mm_per_h,
                "std_mm_per_h": dr.std_mm_per_h,
                "zeros": dr.zeros,
                "removed": dr.removed,
            },
            "budget": {k: b.as_json() for k, b in self.budgets.items()},
            "notes": list(self.encoder_notes),
        }


def _finite(x: float) -> float | None:
    """Return a number for JSON: None where not finite (σ of an unidentified parameter)."""
    return float(x) if math.isfinite(x) else None


def _noise_sigma(r: np.ndarray, k: int, robust: bool) -> float:
    """Return the noise σ in mm from the residuals ``r`` of a fit of ``k`` parameters.

    Taken from the joint fit (the best model of the data), dof-corrected; with the
    robust loss from the median absolute residual (1.4826·MAD), so outliers do not count.
    NaN when there are no more points than parameters.
    """
    n = len(r)
    if n <= k:
        return float("nan")
    if robust:
        return float(1.4826 * np.median(np.abs(r)) * np.sqrt(n / (n - k)))
    return float(np.sqrt(r @ r / (n - k)))


def solve(
    robot: Robot,
    plan: Plan,
    m: Measurements,
    *,
    methods: tuple[str, ...] = METHODS,
    omega_default: float = DEFAULT_OMEGA,
    robust: bool = False,
    partial: bool = False,
    corrections: bool = True,
    refine_scale: bool = False,
) -> SolveResult:
    """Identify the plan's parameters from checked measurements.

    Refuses an incomplete log unless ``partial`` (steps without points stay at nominal:
    ``left_nominal``). The reference rows' scale applies and a significant zero drift is
    removed (:mod:`wirecal.solver.scale`) unless ``corrections`` is False (the controller
    solver's view). The joint σ includes the scale's and the drift's uncertainty
    (:func:`_with_drift_sigma`); ``refine_scale`` refines the scale jointly (``ScalePrior``).
    A pool's plan gets the fit it was planned for (:func:`_solve_pool`).
    """
    refuse_options(robot, plan, methods, refine_scale, m)
    if plan.joint_only:
        return _solve_pool(robot, plan, m, partial=partial, corrections=corrections)
    left, names, step = _measured_steps(plan, m, partial)
    factor, notes = _reference_scale(robot, m)
    k = factor if factor is not None and corrections else 1.0
    problem, psi, comp = _problem(robot, plan, m, (names, step), k)
    omega = omega_vector(names, robot.n_joints, plan, omega_default)
    fit = _identify(robot, problem, omega, psi, robust)
    drift, clean = _judge_drift(robot, m, fit, k, problem, (omega, psi, robust))
    drift = _as_corrected(drift, corrections)
    notes.append(_drift_note(m, drift))
    problem, fit = clean if corrections and clean is not None else (problem, fit)
    sw, jt, sigma = fit
    scale, scale_std = _scale_estimate(robot, m, factor, sigma)
    refine = refine_scale and corrections
    jt = _joint_with_scale(jt, problem, scale, scale_std, sigma, refine=refine, robust=robust)
    estimates = {name: e for name, e in (("stepwise", sw), ("joint", jt)) if name in methods}
    src = functools.partial(
        _error_sources, robot, plan, m, sigma, problem.d, scale, scale_std, drift
    )
    budgets = _budgets(robot, problem, psi, step, sigma, src, len(names), comp, estimates)
    estimates = _with_drift_sigma(estimates, budgets, problem, m)
    return SolveResult(
        robot,
        plan,
        m,
        estimates,
        {name: _predicted(budgets.get(name)) for name in estimates},
        sigma,
        left,
        psi[:, : len(names)],
        m.step[m.present],
        budgets=budgets,
        scale=scale,
        drift=drift,
        encoder_notes=tuple(notes),
        compliance=comp,
    )


def refuse_options(
    robot: Robot,
    plan: Plan,
    methods: tuple[str, ...],
    refine_scale: bool,
    m: Measurements | None = None,
) -> None:
    """Refuse methods and a scale refinement the plan, robot file or log ``m`` cannot take.

    Asked before the log is read (the command line, ``m`` None) and by :func:`solve`. A
    pool's plan (``plan.joint_only``) isolates no parameter in its steps: the step-by-step
    estimate does not apply, and its wire fit refines no scale. ``refine_scale`` refines
    the scale in the joint method, from the reference gauge the robot file declares and
    the log's reference step measured.
    """
    if plan.joint_only and "joint" not in methods:
        raise WirecalError(
            f"{plan.source}: joint_only = true: the plan was written from a pool for the joint "
            "method and its steps do not isolate their parameters, so the step-by-step "
            "estimate does not apply: solve by the joint method (--method joint)"
        )
    if not refine_scale:
        return
    if plan.joint_only:
        raise WirecalError(
            f"{plan.source}: joint_only = true: --refine-scale refines the scale in the "
            "joint method of the file's [calibration] parameters; a plan from a pool is "
            "solved by the wire fit it was made for, which does not: leave it out (the "
            "reference rows' scale is applied either way)"
        )
    if "joint" not in methods:
        raise WirecalError(
            "--refine-scale refines the scale in the joint method; --method stepwise runs "
            "the step-by-step method alone, which takes the reference's scale as measured: "
            "leave --refine-scale out, or solve by --method joint or all"
        )
    if robot.encoder.reference_length_mm is None:
        raise WirecalError(
            f"--refine-scale refines the scale the reference gauge measured; {robot.source} "
            "declares no gauge ([encoder] reference_length_mm), so its logs have no "
            "reference step: leave it out"
        )
    if m is not None and not len(m.reference_mm):
        raise WirecalError(
            f"--refine-scale refines the scale the log's reference step measured; {m.source} "
            "has no reference step (a gauge, [encoder] reference_length_mm, and a run with "
            "it): leave it out"
        )


def _solve_pool(
    robot: Robot, plan: Plan, m: Measurements, *, partial: bool, corrections: bool
) -> SolveResult:
    """Solve a plan from a pool by the wire fit it was planned for (:mod:`.solve_pool`).

    The lengths as :func:`solve` takes them: the reference's scale, a significant drift
    removed (:func:`_pool_drift`). Ψ (the report's) is the file's parameters'. The
    budget's map and its prior's share are the posterior's; ``--robust`` and ``--omega``
    do not apply (the fit's loss is soft-L1 always, no step bounds a parameter).
    """
    # refuses an incomplete log unless partial; every parameter is fitted from every point
    # there is, none left at nominal for its step's lack of points
    _measured_steps(plan, m, partial)
    factor, notes = _reference_scale(robot, m)
    k = factor if factor is not None and corrections else 1.0
    drift, first, clean = _pool_drift(robot, m, k)
    # the controller's view (no corrections): the lengths as read, their fit
    sol, d = clean if corrections and clean is not None else first
    drift = _as_corrected(drift, corrections)
    notes.append(_drift_note(m, drift))
    scale, scale_std = _scale_estimate(robot, m, factor, sol.sigma_mm)
    src = _error_sources(robot, plan, m, sol.sigma_mm, d, scale, scale_std, drift)
    b = _pool_budget(robot, sol, src)
    psi = sensitivity(robot.nominal, m.joints_deg[m.present], m.theta0_deg, plan.order).psi
    return SolveResult(
        robot,
        plan,
        m,
        {"joint": sol.estimate},
        {"joint": _predicted(b)},
        sol.sigma_mm,
        (),
        psi,
        m.step[m.present],
        budgets={} if b is None else {"joint": b},
        scale=scale,
        drift=drift,
        encoder_notes=tuple(notes),
        prior=sol.fit,
    )


def _pool_drift(
    robot: Robot, m: Measurements, k: float
) -> tuple[Drift | None, tuple[PoolSolution, np.ndarray], tuple[PoolSolution, np.ndarray] | None]:
    """Return the zero readings' drift and the pool fits, as :func:`_judge_drift`.

    The fit of the lengths as read (×``k``) and, when the drift is removed, the fit without
    it (else None), each with its lengths. The first fit's σ still holds the drift, which
    then looks insignificant: it is judged again by the σ of a fit with the drift taken out.
    """
    q_deg = m.joints_deg[m.present]
    d = m.distance_mm[m.present] * k
    first = (pool_estimate(robot, q_deg, d), d)
    drift = _fit_drift(m, first[0].sigma_mm)
    if drift is None:
        return None, first, None
    d_clean = _drift_removed_mm(m, drift) * k
    clean = pool_estimate(robot, q_deg, d_clean)
    drift = _fit_drift(m, clean.sigma_mm)
    if drift is None or not drift.removed:
        return drift, first, None
    return drift, first, (clean, d_clean)


def _pool_budget(robot: Robot, sol: PoolSolution, src: Sources) -> Budget | None:
    """Return the pool fit's budget over the workspace; None when a parameter is unbounded."""
    if not np.all(np.isfinite(sol.terms.noise)):
        return None
    base = point_model(robot)
    names = sol.estimate.names
    return budget(base, names, sol.fit.jacobian, None, src, workspace(robot), prior=sol.terms)


def _measured_steps(
    plan: Plan, m: Measurements, partial: bool
) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray]:
    """Return the parameters left nominal, those solved and the present rows' steps renumbered.

    Refuses an incomplete log unless ``partial``, and a log without a calibration point.
    """
    if not m.complete and not partial:
        raise WirecalError(  # what a capture set aside may be the missing rows: say so
            [
                f"{m.source}: the log is incomplete: missing {m.missing_text()}. "
                "Finish the run (repeat from the first missing step), or pass "
                "--partial to solve from the points that are there",
                *m.log.notes,
            ]
        )
    step = m.step[m.present]
    left = tuple(n for j, n in enumerate(plan.order) if not np.any(step == j + 1))
    names = tuple(n for n in plan.order if n not in left)
    renumber = {plan.order.index(n) + 1: k + 1 for k, n in enumerate(names)}
    renumber[len(plan.order) + 1] = len(names) + 1  # the payload step: no parameter's
    step = np.array([renumber[s] for s in step])
    if not names:
        raise WirecalError(f"{m.source}: no calibration point was measured; nothing to solve")
    return left, names, step


def _problem(
    robot: Robot,
    plan: Plan,
    m: Measurements,
    measured: tuple[tuple[str, ...], np.ndarray],
    k: float,
) -> tuple[Problem, np.ndarray, ComplianceObservability | None]:
    """Return the identification problem of the measured points, its ψ and the compliances.

    ``measured``: the parameters solved and the points' steps. The lengths are scaled by
    ``k``; the compliances the points identify are solved beside the parameters; the
    points of a payload step carry its mass (:meth:`~wirecal.solver.identify.Problem.at`).
    """
    names, step = measured
    q_deg = m.joints_deg[m.present]
    d = m.distance_mm[m.present] * k
    pay = plan.payload_step
    load = plan.point_load_kg()[m.present] if pay is not None else None
    com = np.array(pay.payload_com_mm) if pay is not None else None
    problem = Problem(
        robot.nominal, names, np.radians(q_deg), np.radians(m.theta0_deg), d, step, load, com
    )
    comp = _compliances(robot, problem.at(), q_deg, m.theta0_deg, names)
    problem = replace(problem, names=names + (comp.identified if comp is not None else ()))
    psi = sensitivity(problem.at(), q_deg, m.theta0_deg, problem.names).psi
    return problem, psi, comp


def _scale_estimate(
    robot: Robot, m: Measurements, factor: float | None, sigma: float
) -> tuple[ScaleEstimate | None, float]:
    """Return the scale estimated from the log's reference rows and its σ.

    Without reference rows (``factor`` None) no estimate, and the σ is the encoder's
    scale tolerance.
    """
    enc = robot.encoder
    if factor is None:
        return None, enc.scale_tolerance_ppm * PPM
    reading = _gauge_reading_sigma(robot, m, sigma)
    scale = estimate_scale(m.reference_mm, valid_length(enc), enc.reference_uncertainty_mm, reading)
    return scale, scale.std


def _gauge_reading_sigma(robot: Robot, m: Measurements, sigma: float) -> float:
    """Return the σ (mm) of one reading of the reference gauge, from the residual's ``sigma``.

    The gauge is read with the wire's tip in its nests, without the arm: when the robot
    file declares the arm's repeatability, the residual's σ holds the scatter the arm's
    landing puts on the points' lengths (:func:`~wirecal.solver.zero_reading.length_sigma_mm`)
    and the gauge's readings do not, so it is taken off (in quadrature). Never below the
    counts' quantisation, mm_per_count/√12. Without the key: ``sigma`` (as before it).
    """
    if robot.repeatability_mm is None:
        return sigma
    q = np.radians(m.joints_deg[m.present])
    arm = length_sigma_mm(robot.nominal, q, np.radians(m.theta0_deg), robot.repeatability_mm)
    counts = abs(robot.encoder.mm_per_count) / math.sqrt(12)
    return max(math.sqrt(max(sigma**2 - arm**2, 0.0)), counts)


def _budgets(
    robot: Robot,
    problem: Problem,
    psi: np.ndarray,
    step: np.ndarray,
    sigma: float,
    sources_of: Callable[[], Sources],
    n_plan: int,
    comp: ComplianceObservability | None,
    estimates: dict[str, Estimate],
) -> dict[str, Budget]:
    """Return each method's error budget over the robot's workspace.

    Empty when the points leave a direction of the parameters unseen (the tool error is
    unbounded along it); ``sources_of`` is called only when every direction is seen.
    """
    J = problem.errors.per_internal(psi)  # internal units
    if not covariance(J, sigma**2)[1].all():
        return {}
    src = sources_of()
    ws = workspace(robot)
    return {
        method: _budget(robot, problem, J, step, src, ws, n_plan, comp, est)
        for method, est in estimates.items()
    }


def _predicted(budget: Budget | None) -> dict[str, float]:
    """Return a method's predicted tool error: unbounded without a budget."""
    return UNIDENTIFIED if budget is None else {"mean": budget.total, "max": budget.worst}


def _joint_with_scale(
    jt: Estimate,
    problem: Problem,
    scale: ScaleEstimate | None,
    scale_std: float,
    sigma: float,
    *,
    refine: bool,
    robust: bool,
) -> Estimate:
    """Return the joint estimate with the scale's uncertainty in it.

    Refined jointly with the scale (a :class:`~wirecal.solver.identify.ScalePrior`) when
    ``refine`` and a reference scale and a finite noise σ are there; otherwise the scale's
    σ is added to its covariance.
    """
    if refine and scale is not None and np.isfinite(sigma) and sigma > 0:
        prior = ScalePrior(scale.std, sigma / scale.std)
        x = problem.errors.to_internal(jt.values)
        return joint(problem, x, loss="soft_l1" if robust else "linear", scale=prior)
    return _with_length_error(jt, problem, scale_std, problem.d)  # ε moves it by ε·J⁺·d


def _error_sources(
    robot: Robot,
    plan: Plan,
    m: Measurements,
    sigma: float,
    d: np.ndarray,
    scale: ScaleEstimate | None,
    scale_std: float,
    drift: Drift | None,
) -> Sources:
    """Return the error budget's sources for the measured points (:func:`budget.sources`)."""
    present = m.present
    return sources(
        sigma,
        d,
        scale_std,
        scale is not None,
        robot.encoder.temperature_coefficient_ppm_per_k,
        None if m.t_s is None else m.t_s[present],
        drift,
        m.reference_t_s,
        unmodelled_exit_mm(robot, plan)[present],
        sag_lengths_mm(robot, plan)[present],
        sum(1 for s in m.zero_drift_mm if s <= len(plan.steps)),  # the reference's zeros
        zero_corrected=robot.repeatability_mm is not None,
    )


def _with_drift_sigma(
    estimates: dict[str, Estimate], budgets: dict[str, Budget], problem: Problem, m: Measurements
) -> dict[str, Estimate]:
    """Return the estimates, the joint one's covariance carrying the drift left in the lengths.

    A drift b left in them moves the estimate by b·J⁺·(t − t_ref)
    (:mod:`wirecal.solver.budget`); with the joint budget's posterior N(mean, σ²) of b
    (:func:`~wirecal.solver.budget.drift_posterior`, the robot file's ``compliances`` only)
    the covariance gains its second moment, (mean² + σ²)·(J⁺(t − t_ref))(J⁺(t − t_ref))ᵀ.
    """
    joint_budget = budgets.get("joint")
    if joint_budget is None or joint_budget.drift_left_mm_per_s is None:
        return estimates
    assert m.t_s is not None  # a drift was read: the log is timed
    assert m.reference_t_s is not None
    rms = math.hypot(*joint_budget.drift_left_mm_per_s)
    pattern = m.t_s[m.present] - m.reference_t_s
    return {**estimates, "joint": _with_length_error(estimates["joint"], problem, rms, pattern)}


def _with_length_error(
    est: Estimate, problem: Problem, rms: float, pattern: np.ndarray
) -> Estimate:
    """Return the estimate with a random error of the lengths added to its covariance.

    The lengths' error is a coefficient of RMS ``rms`` times ``pattern`` (N,): it moves the
    estimate by that coefficient times J⁺·pattern, so the covariance gains
    rms²·(J⁺·pattern)(J⁺·pattern)ᵀ, in boundary units.
    """
    if est.std is None or est.correlation is None or rms == 0:
        return est
    _, J = wire_jacobian(
        problem.at(problem.errors.to_internal(est.values)),
        problem.q,
        problem.q0,
        problem.names,
    )
    b = problem.errors.to_boundary(least_squares_map(J) @ pattern)
    finite = np.isfinite(est.std)
    sd = np.where(finite, est.std, 0.0)
    cov = np.nan_to_num(est.correlation) * np.outer(sd, sd) + rms**2 * np.outer(b, b)
    std = np.sqrt(np.diag(cov))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    corr[~finite] = np.nan
    corr[:, ~finite] = np.nan
    return replace(est, std=np.where(finite, std, np.inf), correlation=corr)


def valid_length(enc) -> float:
    """Return the reference gauge's length (the caller checked that there is one)."""
    assert enc.reference_length_mm is not None
    return float(enc.reference_length_mm)


def _budget(
    robot: Robot,
    problem: Problem,
    J: np.ndarray,
    step: np.ndarray,
    src: Sources,
    ws: np.ndarray,
    n_plan: int,
    comp: ComplianceObservability | None,
    est: Estimate,
) -> Budget:
    """Return a method's budget: the stepwise one of the plan's ``n_plan`` parameters."""
    if est.method == "stepwise":
        return budget(problem.base, problem.names[:n_plan], J[:, :n_plan], step, src, ws)
    terms = _compliance_terms(robot, problem, comp, est)
    return budget(problem.base, problem.names, J, None, src, ws, terms)


def _compliances(
    robot: Robot, model: Model, q_deg: np.ndarray, theta0_deg: np.ndarray, names: tuple[str, ...]
) -> ComplianceObservability | None:
    """Which of the robot file's ``compliances`` the measured points identify (None: none asked).

    ``model``: the nominal one as at the points (a payload step's mass on).
    """
    if not robot.compliances:
        return None
    return compliance_observability(
        model, q_deg, theta0_deg, names, robot.compliances, READING_NOISE_MM
    )


def _compliance_terms(
    robot: Robot, problem: Problem, comp: ComplianceObservability | None, est: Estimate
) -> ComplianceTerms | None:
    """Return the joint budget's compliances: the identified ones' values, the others' prior.

    The prior of the others is :data:`~wirecal.solver.compliance.COMPLIANCE_RANGE_URAD_PER_NM`
    as offsets from the file's values.
    With the joint fit's residuals, from which the budget reads what the points say of the
    others (:func:`~wirecal.solver.budget.compliance_likelihood`).
    """
    if comp is None:
        return None
    values = est.as_dict()
    errors = problem.errors
    left = np.array(
        [robot.nominal_value(n) + values[n] if n in comp.identified else 0.0 for n in errors.names]
    )
    others = tuple(n for n in robot.compliances if n in comp.reasons and n not in comp.no_torque)
    unit = ErrorSet(others, robot.n_joints)
    nominal = np.array([robot.nominal_value(n) for n in others])
    wire = (  # every compliance asked for identified: none at its prior
        wire_jacobian(problem.at(), problem.q, problem.q0, others)[1]
        if others
        else np.zeros((len(problem.q), 0))
    )
    return ComplianceTerms(
        errors.to_internal(left),
        others,
        np.reshape(wire, (len(problem.q), len(others))),
        unit.to_internal(np.subtract.outer(COMPLIANCE_RANGE_URAD_PER_NM, nominal)),
        unit.to_internal(nominal),
        problem.residuals(errors.to_internal(est.values)),
    )


def _identify(
    robot: Robot, problem: Problem, omega: np.ndarray, psi: np.ndarray, robust: bool
) -> Fit:
    """Run the stepwise and joint methods; their estimates and the noise σ (mm).

    The stepwise method solves the plan's parameters (``omega``'s); the joint method also
    the identified compliances after them, from the stepwise values and 0.
    """
    geometry = replace(problem, names=problem.names[: len(omega)])
    sw = run_stepwise(geometry, omega, psi[:, : len(omega)])
    if not np.all(np.isfinite(sw.values)):
        bad = [n for n, v in zip(problem.names, sw.values, strict=True) if not np.isfinite(v)]
        raise WirecalError(
            f"{robot.source}: the step-by-step identification gave no finite value for "
            f"{', '.join(bad)}: the model's wire lengths are not finite numbers; check the "
            "robot file's sizes and units (mm, deg)"
        )
    start = np.concatenate([sw.values, np.zeros(len(problem.names) - len(omega))])
    return (sw, *_joint_fit(problem, start, robust))


def _joint_fit(problem: Problem, start: np.ndarray, robust: bool) -> tuple[Estimate, float]:
    """Run the joint method from ``start`` (boundary units); its estimate and the noise σ."""
    loss: Loss = "soft_l1" if robust else "linear"
    jt = joint(problem, problem.errors.to_internal(start), loss=loss)
    r = problem.residuals(problem.errors.to_internal(jt.values))
    return jt, _noise_sigma(r, len(problem.names), robust)


Fit = tuple[Estimate, Estimate, float]
"""The stepwise and joint estimates and the noise σ (mm) of one identification."""


def _judge_drift(
    robot: Robot,
    m: Measurements,
    first: Fit,
    factor: float,
    problem: Problem,
    how: tuple[np.ndarray, np.ndarray, bool],
) -> tuple[Drift | None, tuple[Problem, Fit] | None]:
    """Fit the zero readings' drift and judge it by the σ left once it is removed.

    The points' σ of the ``first`` identification still holds the drift (their lengths
    drift with time): judged by it a real drift looks insignificant. So the fitted drift is
    taken out of the lengths (then scaled by the reference's ``factor``), σ taken again from
    the joint method (the one σ comes from, started at the first joint estimate), and the
    drift refitted with that σ. Only a drift that is then removed has the parameters
    identified again (``how``: ω, Ψ, robust, as :func:`_identify`). Returns the drift and,
    when it is significant, the problem without it and its identification.
    """
    drift = _fit_drift(m, first[2])
    if drift is None:
        return None, None
    clean = replace(problem, d=_drift_removed_mm(m, drift) * factor)
    drift = _fit_drift(m, _joint_fit(clean, first[1].values, how[2])[1])
    if drift is None or not drift.removed:
        return drift, None
    return drift, (clean, _identify(robot, clean, *how))


def _drift_removed_mm(m: Measurements, drift: Drift) -> np.ndarray:
    """Return the points' lengths with the fitted ``drift`` taken out (before any scale)."""
    assert m.t_s is not None  # a drift was fitted: the log is timed
    assert m.reference_t_s is not None
    present = m.present
    removed = replace(drift, removed=True).correction_mm(m.t_s[present], m.reference_t_s)
    return m.distance_mm[present] - removed


def _as_corrected(drift: Drift | None, corrections: bool) -> Drift | None:
    """Return the drift as the lengths saw it: not removed in the controller's view."""
    return drift if corrections or drift is None else replace(drift, removed=False)


def _fit_drift(m: Measurements, sigma_mm: float) -> Drift | None:
    """Fit the zero readings' drift; σ of a reading from the points' fit ``sigma_mm``."""
    if not m.timed or m.zero_t_s is None or m.zero_mm is None:
        return None
    floor = abs(m.mm_per_count) / math.sqrt(12)  # quantisation: the least noise there is
    return fit_drift(m.zero_t_s, m.zero_mm, max(sigma_mm, floor) if sigma_mm > 0 else floor)


def _drift_note(m: Measurements, drift: Drift | None) -> str:
    """Describe the drift fit (or why there is none) for the result's notes."""
    if drift is not None:
        return drift.text()
    if not m.timed:
        return "the log has no times (version 1): no drift fit"
    return "too few zero readings to fit a drift"


def _reference_scale(robot: Robot, m: Measurements) -> tuple[float | None, list[str]]:
    """Return the scale factor k̂ of the log's reference rows (None without) and notes."""
    enc = robot.encoder
    if len(m.reference_mm):
        if enc.reference_length_mm is None:
            raise WirecalError(
                f"{m.source}: the log has reference rows but {robot.source} gives no "
                "[encoder] reference_length_mm: give the gauge's certified length"
            )
        return enc.reference_length_mm / float(np.mean(m.reference_mm)), []
    if enc.reference_length_mm is not None:
        return None, [
            f"{robot.source} gives a reference gauge but the log has no reference rows: "
            "the scale is known only to its tolerance"
        ]
    return None, []
