"""The least-squares solver of ``wirecal fit``: Levenberg–Marquardt on the normal equations.

A fit has N rows (up to 100,000 and more) and k parameters (k ≈ 20–30). A trust-region
solver that factors the N × k Jacobian at every iteration (``scipy.optimize.least_squares``
takes its SVD) spends as long on that as on the model; here each iteration forms
H = Jᵀ W J and g = Jᵀ ρ′ r (k × k and k, linear in N) and solves the damped normal
equations (H + λ·diag H) δ = −g, scaled to unit diagonal (the columns' scales, as
``x_scale="jac"``). The squared condition number is harmless: ``choose`` keeps only
parameters whose σ stays small, so the scaled H is well conditioned.

The soft-L1 loss, ρ(z) = 2(√(1 + z) − 1) with z = (r/f)², f the scale, is minimised with
the weights of ``scipy.optimize.least_squares`` (Triggs et al., "Bundle adjustment — a
modern synthesis", 2000): W = ρ′ + 2ρ″z, clipped at a small positive value, the gradient
Jᵀ ρ′ r; its minimum is the same whatever the weights, only the path differs.

Stop when an accepted step's predicted decrease of the cost is below ½ :data:`STEP_TOL`²
of the residual's variance: the step is then below 10⁻⁴ of the parameters' σ, and the next
one, on a nearly linear problem, far smaller (``least_squares``' default, a change of the
cost below 10⁻⁸ of it, stops at steps of about 0.03 σ at 100,000 rows).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

import numpy as np

SolverLoss = Literal["linear", "soft_l1"]

STEP_TOL = 1e-4
"""The last step, in units of the parameters' σ, below which the fit has converged."""

MAX_EVALUATIONS = 100
"""Evaluations of the model before the solver stops where it is (a fit's solve takes 3–15)."""

_MIN_WEIGHT = np.finfo(float).eps


def _weights(
    r: np.ndarray, loss: SolverLoss, f_scale: float
) -> tuple[float, np.ndarray, np.ndarray]:
    """Return the cost, ρ′ (N,) and the Hessian weights W (N,) of residuals ``r``."""
    if loss == "linear":
        one = np.ones_like(r)
        return 0.5 * float(r @ r), one, one
    z = (r / f_scale) ** 2
    root = np.sqrt(1 + z)
    cost = f_scale**2 * float(np.sum(root - 1))  # ½ f² Σ ρ(z)
    d1 = 1 / root
    w = np.maximum(d1 - z / root**3, _MIN_WEIGHT)  # ρ′ + 2ρ″z, ρ″ = −½(1 + z)^−3/2
    return cost, d1, w


def _normal_equations(
    r: np.ndarray, J: np.ndarray, d1: np.ndarray, w: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return H = Jᵀ W J, g = Jᵀ ρ′ r, the columns' scales √diag H and H scaled by them."""
    H = J.T @ (w[:, None] * J)
    g = J.T @ (d1 * r)
    scale = np.sqrt(np.maximum(np.diag(H), np.finfo(float).tiny))
    return H, g, scale, H / np.outer(scale, scale)


def _negligible(predicted: float, cost: float, dof: int) -> bool:
    """Return whether a step's predicted decrease is below ½ STEP_TOL² σ², σ² = 2·cost/dof."""
    return predicted <= STEP_TOL**2 * cost / max(dof, 1)


Evaluation = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray | Callable[[], np.ndarray]]]
"""x ↦ the residual r (N,) and ∂r/∂x (N, k), or a function giving ∂r/∂x when asked: the
solver asks for it only at the points it accepts (a refused step's is never taken)."""


def _jacobian(J: np.ndarray | Callable[[], np.ndarray]) -> np.ndarray:
    """Return ∂r/∂x as :data:`Evaluation` gave it: the array, or what its function gives."""
    return J() if callable(J) else J


def levenberg_marquardt(
    evaluate: Evaluation,
    x0: np.ndarray,
    *,
    loss: SolverLoss = "linear",
    f_scale: float = 1.0,
) -> np.ndarray:
    """Return the ``x`` that minimises the cost of ``evaluate(x)``'s residual (module docstring).

    ``evaluate(x)`` returns the residual r (N,) and ∂r/∂x (N, k) at ``x`` (:data:`Evaluation`);
    a point where either is not finite is a failed step (a start there: ``ValueError``).
    """
    return minimised(evaluate, x0, loss=loss, f_scale=f_scale)[0]


def minimised(
    evaluate: Evaluation,
    x0: np.ndarray,
    *,
    loss: SolverLoss = "linear",
    f_scale: float = 1.0,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return :func:`levenberg_marquardt`'s ``x`` with the residual and ∂r/∂x there.

    ``start``: ``evaluate(x0)`` when the caller has it (not evaluated again).
    """
    x = np.asarray(x0, dtype=float).copy()
    r, at_start = evaluate(x) if start is None else start
    J = _jacobian(at_start)
    cost, d1, w = _weights(r, loss, f_scale)
    if not (np.isfinite(cost) and np.all(np.isfinite(J))):
        raise ValueError("the residual or its Jacobian is not finite at the start")  # as scipy
    lam = 0.0  # a good start: Gauss–Newton first, damped only when a step fails
    normal = None  # H, g, the scales and the scaled H at x: kept while steps fail
    for _ in range(MAX_EVALUATIONS):
        if normal is None:
            normal = _normal_equations(r, J, d1, w)
        H, g, scale, Hs = normal
        step = -np.linalg.lstsq(Hs + lam * np.eye(len(x)), g / scale, rcond=None)[0] / scale
        predicted = -(g @ step + 0.5 * step @ H @ step)
        r_new, at_new = evaluate(x + step)
        new_cost, d1_new, w_new = _weights(r_new, loss, f_scale)
        gain = cost - new_cost > 0.25 * predicted > 0 and np.all(
            np.isfinite(J_new := _jacobian(at_new))
        )
        if gain:
            x, r, J, cost, d1, w, normal = x + step, r_new, J_new, new_cost, d1_new, w_new, None
            lam = lam / 10 if lam > 1e-6 else 0.0
        if _negligible(predicted, cost, len(r) - len(x)):
            break  # converged, or at the minimum to rounding: no step can lower the cost
        if not gain:
            lam = max(10 * lam, 1e-3)
    return x, r, J
