"""The wire length and its derivatives (paper eq. 7).

The encoder is mounted so that the wire length is zero at θ0 (paper §2.1), so the
measured quantity at configuration θ_i is d_i = ‖p(θ_i) − p(θ_0)‖, both points
computed by the same (possibly perturbed) model. With a swivel guide pulley
(``model.pulley``) it is the arc on the pulley plus the free span
(:func:`~wirecal.solver.exit_geometry.wire_path`), the pulley at the exit p(θ_0).

Both functions accept one model with points q (k, n), or T models (a batched model,
dh (T, n, 4)) with shared points q (k, n) or per-model points q (T, k, n); θ0 is (n,)
or (T, n). Results are (k,)/(k, m), or (T, k)/(T, k, m) for T models.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.kinematics import Model, repeat, tool_jacobian, tool_position


def _stack(model: Model, q: np.ndarray, q0: np.ndarray) -> tuple[Model, np.ndarray, int]:
    """θ0 and the points of every model as one batch of T·(k+1) configurations."""
    T = model.dh.shape[0] if model.batched else 1
    q = np.asarray(q, dtype=float)
    q = np.broadcast_to(q, (T, *q.shape[-2:]))
    q0 = np.broadcast_to(np.asarray(q0, dtype=float), (T, q.shape[-1]))
    Q = np.concatenate([q0[:, None, :], q], axis=1).reshape(-1, q.shape[-1])
    k1 = q.shape[1] + 1
    big = repeat(model, k1) if model.batched else model
    return _load_at_points(big, T, k1), Q, k1


def _load_at_points(model: Model, T: int, k1: int) -> Model:
    """Return the model with its per-point load (kg) for the batch: none at θ0.

    The mass is mounted after the zero reading at θ0 (the plan's payload step), so the
    wire's exit, p(θ0), is that of the arm without it.
    """
    masses = model.masses
    if masses is None or masses.load_kg is None:
        return model
    kg = np.asarray(masses.load_kg, dtype=float)
    if kg.shape != (k1 - 1,):
        raise ValueError(f"the mounted load is given for {kg.size} points; there are {k1 - 1}")
    per = np.tile(np.concatenate([[0.0], kg]), T)
    return replace(model, masses=replace(masses, load_kg=per))


def _shape(model: Model, arr: np.ndarray) -> np.ndarray:
    return arr if model.batched else arr[0]


def wire_vectors(model: Model, q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """p(θ_i) − p(θ_0), the tool points from the exit, for points q and one θ0, radians."""
    big, Q, k1 = _stack(model, q, q0)
    p = tool_position(big, Q).reshape(-1, k1, 3)
    return _shape(model, p[:, 1:] - p[:, :1])


def wire_lengths(model: Model, q: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """d_i = ‖p(θ_i) − p(θ_0)‖ (or the pulley's path) for points q and one θ0, radians."""
    return wire_path(model.pulley, wire_vectors(model, q, q0))[0]


def wire_jacobian(
    model: Model, q: np.ndarray, q0: np.ndarray, names: Sequence[str]
) -> tuple[np.ndarray, np.ndarray]:
    """D and ∂d/∂e = ν̂ᵀ (Φ_i − Φ_0) in mm/rad and mm/mm (paper eq. 14–16).

    Evaluated at the model given, so the same function serves the Ψ analysis at
    nominal and Gauss–Newton steps at any estimate. With a pulley ν̂ is the direction of
    the free span, the gradient of arc plus span (the pulley moves with p(θ_0)).
    """
    big, Q, k1 = _stack(model, q, q0)
    p, J = tool_jacobian(big, Q, names)
    p = p.reshape(-1, k1, 3)
    J = J.reshape(-1, k1, 3, len(names))
    d, nu_hat = wire_path(model.pulley, p[:, 1:] - p[:, :1])
    dd = np.einsum("tkc,tkcm->tkm", nu_hat, J[:, 1:] - J[:, :1])
    return _shape(model, d), _shape(model, dd)
