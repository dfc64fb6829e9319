"""Provide ``wirecal solve`` as a Python function.

Measurements in, both methods' estimates out, with residuals and the predicted
post-calibration accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from wirecal.solver.accuracy import stepwise_map, tool_error, workspace
from wirecal.solver.errors import WirecalError
from wirecal.solver.identifiability import covariance
from wirecal.solver.identify import (
    DEFAULT_OMEGA,
    Estimate,
    Problem,
    joint,
    omega_vector,
    run_stepwise,
)
from wirecal.solver.measurements import Measurements
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity

METHODS = ("stepwise", "joint")
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

    @property
    def names(self) -> tuple[str, ...]:
        """The identified parameters (the plan's order, less ``left_nominal``)."""
        return tuple(n for n in self.plan.order if n not in self.left_nominal)

    @property
    def recommended(self) -> str:
        """The method with the smaller predicted tool-point error (joint when tied)."""
        return min(self.estimates, key=lambda m: (self.predicted[m]["mean"], m != "joint"))

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
                entry["std"] = {n: _finite(s) for n, s in zip(est.names, est.std, strict=True)}
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
            "notes": list(m.notes),
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
) -> SolveResult:
    """Identify the plan's parameters from checked measurements.

    Refuses an incomplete log unless ``partial``; then parameters whose step has no
    points stay at nominal and are listed in ``left_nominal``.
    """
    if not m.complete and not partial:
        raise WirecalError(
            f"{m.source}: the log is incomplete: missing {m.missing_text()}. "
            "Finish the run (repeat from the first missing step), or pass "
            "--partial to solve from the points that are there"
        )
    present = m.present
    step = m.step[present]
    left = tuple(n for j, n in enumerate(plan.order) if not np.any(step == j + 1))
    names = tuple(n for n in plan.order if n not in left)
    renumber = {plan.order.index(n) + 1: k + 1 for k, n in enumerate(names)}
    step = np.array([renumber[s] for s in step])
    if not names:
        raise WirecalError(f"{m.source}: no calibration point was measured; nothing to solve")

    base = robot.nominal
    q_deg = m.joints_deg[present]
    problem = Problem(
        base, names, np.radians(q_deg), np.radians(m.theta0_deg), m.distance_mm[present], step
    )
    psi = sensitivity(base, q_deg, m.theta0_deg, names).psi
    omega = omega_vector(names, robot.n_joints, plan, omega_default)

    estimates: dict[str, Estimate] = {}
    sw = run_stepwise(problem, omega, psi)
    if not np.all(np.isfinite(sw.values)):
        bad = [n for n, v in zip(names, sw.values, strict=True) if not np.isfinite(v)]
        raise WirecalError(
            f"{robot.source}: the step-by-step identification gave no finite value for "
            f"{', '.join(bad)}: the model's wire lengths are not finite numbers; check the "
            "robot file's sizes and units (mm, deg)"
        )
    if "stepwise" in methods:
        estimates["stepwise"] = sw
    jt = joint(
        problem, problem.errors.to_internal(sw.values), loss="soft_l1" if robust else "linear"
    )
    if "joint" in methods:
        estimates["joint"] = jt

    r = problem.residuals(problem.errors.to_internal(jt.values))
    sigma = _noise_sigma(r, len(names), robust)
    J = problem.errors.per_internal(psi)  # internal units
    cov, identified = covariance(J, sigma**2)
    predicted = dict.fromkeys(estimates, UNIDENTIFIED)
    if identified.all():  # otherwise the tool error is unbounded along the unseen directions
        ws = workspace(robot)
        if "joint" in estimates:
            predicted["joint"] = tool_error(base, names, cov, ws).as_dict()
        if "stepwise" in estimates:
            A = stepwise_map(J, step)
            predicted["stepwise"] = tool_error(base, names, sigma**2 * A @ A.T, ws).as_dict()
    return SolveResult(robot, plan, m, estimates, predicted, sigma, left, psi, m.step[present])
