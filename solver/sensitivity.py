"""The paper's sensitivity analysis (§2.2): Φ_i, Φ_0, Φ_{i−0}, ν̂_i and Ψ_i.

Ψ_{i_j} = ⟨Φ_{i−0, j}, ν̂_i⟩ (paper eq. 16–17) is the first-order change of the wire
length at point i per unit error of parameter j: mm/deg for angular parameters and
dimensionless for lengths (paper §2.2). ν̂_i uses Δz = f_z(θ_i) − f_z(θ_0); the paper's
eq. 12 writes f_y there by typo. With a swivel guide pulley ν̂_i is the direction of the
free span from the pulley to the tool point, the gradient of the wire length
(:mod:`~wirecal.solver.exit_geometry`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.gravity import unloaded
from wirecal.solver.kinematics import Model, tool_jacobian
from wirecal.solver.params import ErrorSet


@dataclass(frozen=True)
class Sensitivity:
    """Φ and Ψ for a batch of points, in boundary units (mm/deg, mm/mm)."""

    names: tuple[str, ...]
    phi_i: np.ndarray  # (N, 3, m)  ∂p/∂e at θ_i
    phi_0: np.ndarray  # (3, m)     ∂p/∂e at θ_0
    nu: np.ndarray  # (N, 3)     p(θ_i) − p(θ_0), nominal
    nu_hat: np.ndarray  # (N, 3)     wire direction (at the tool point)
    psi: np.ndarray  # (N, m)

    @property
    def phi_diff(self) -> np.ndarray:
        """Φ_{i−0} = Φ_i − Φ_0 (paper eq. 11)."""
        return self.phi_i - self.phi_0


def sensitivity(
    model: Model, q_deg: np.ndarray, theta0_deg: np.ndarray, names: Sequence[str]
) -> Sensitivity:
    """Φ_i, Φ_0, ν̂_i and Ψ_i at the given model for points ``q_deg`` (N, n) in degrees."""
    names = tuple(names)
    errors = ErrorSet(names, model.n_joints)
    p, J = tool_jacobian(model, np.radians(np.atleast_2d(q_deg)), names)
    at_zero = replace(model, masses=unloaded(model.masses))  # no load mounted at θ0
    p0, J0 = tool_jacobian(at_zero, np.radians(np.atleast_2d(theta0_deg)), names)
    nu = p - p0[0]
    nu_hat = wire_path(model.pulley, nu)[1]
    phi_i, phi_0 = errors.per_boundary(J), errors.per_boundary(J0[0])
    psi = np.einsum("nk,nkm->nm", nu_hat, phi_i - phi_0)
    return Sensitivity(names, phi_i, phi_0, nu, nu_hat, psi)


@dataclass(frozen=True)
class Verdict:
    """Whether a point isolates its step's parameter (paper eq. 18–19)."""

    ok: bool
    violations: tuple[str, ...]  # later parameters whose |Ψ| exceeds the tolerance


DEFAULT_TOL = 0.15
"""Default tolerance: a later parameter's |Ψ| may reach 15 % of the step's own |Ψ_j|."""

PSI_FLOOR = 0.005
"""|Ψ| below this (half the paper's printed precision) counts as zero."""


def within_tolerance(psi_j: np.ndarray, psi_t: np.ndarray, tol: float) -> np.ndarray:
    """Return where |Ψ_t| ≤ max(tol·|Ψ_j|, PSI_FLOOR): the isolation rule of eq. 18–19.

    ``psi_j`` (k,): each point's Ψ of the step's parameter; ``psi_t`` (k, m): its Ψ of m
    other parameters; the result (k, m). The one rule of :func:`verdict` and the planner.
    """
    limit = np.maximum(tol * np.abs(psi_j), PSI_FLOOR)
    return np.abs(psi_t) <= limit[..., None]


def verdict(
    psi_row: dict[str, float], parameter: str, later: Sequence[str], tol: float = DEFAULT_TOL
) -> Verdict:
    """Judge a point of step j: ``ok`` when |Ψ_t| ≤ max(tol·|Ψ_j|, PSI_FLOOR) for every t > j.

    The set S_j of eq. 19 asks Ψ_t = 0 for every parameter identified after step j
    (the flowchart's ``t < j`` is the reversed typo listed in DESIGN.md);
    :func:`within_tolerance` is the rule.
    """
    ok = within_tolerance(
        np.asarray(psi_row[parameter]), np.array([psi_row[t] for t in later]), tol
    )
    bad = tuple(t for t, fine in zip(later, ok, strict=True) if not fine)
    return Verdict(ok=not bad, violations=bad)
