"""The wire length and its derivatives (paper eq. 7).

The encoder is mounted so that the wire length is zero at θ0 (paper §2.1), so the
measured quantity at configuration θ_i is d_i = ‖p(θ_i) − p(θ_0)‖, both points
computed by the same (possibly perturbed) model.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .kinematics import Model, tool_jacobian, tool_position


def wire_lengths(model: Model, q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """d_i = ‖p(θ_i) − p(θ_0)‖ for a batch q (N, n) and one θ0 (n,), radians; shape (N,)."""
    p = tool_position(model, q)
    p0 = tool_position(model, np.atleast_2d(q0))[0]
    return np.linalg.norm(p - p0, axis=1)


def wire_jacobian(model: Model, q: np.ndarray, q0: np.ndarray,
                  names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """d (N,) and ∂d/∂e (N, m) = ν̂ᵀ (Φ_i − Φ_0) in mm/rad and mm/mm (paper eq. 14–16).

    Evaluated at the model given, so the same function serves the Ψ analysis at
    nominal and Gauss–Newton steps at any estimate.
    """
    p, J = tool_jacobian(model, q, names)
    p0, J0 = tool_jacobian(model, np.atleast_2d(q0), names)
    diff = p - p0[0]
    d = np.linalg.norm(diff, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        nu_hat = diff / d[:, None]
    dd = np.einsum("nk,nkm->nm", nu_hat, J - J0[0])
    return d, dd
