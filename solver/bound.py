"""The 95 % bound of a calibration's tool-point error, from the error budget's model.

The quantity bounded is the one a calibration is judged by against the truth (the demo's
"tool-point error vs truth"): the mean over the workspace's configurations q (the
budget's 1,000, :func:`~wirecal.solver.accuracy.workspace`) of ‖p_true(q) − p_est(q)‖.
Linearised, the parameter error is δe = M·δd (:mod:`wirecal.solver.budget`) and

    E(δe) = mean_q ‖J_p(q)·δe‖.

The budget's sources enter δe in three ways:

* random, Gaussian: δe ~ N(0, Σ) (reading noise, a measured scale, the zero drift);
* bounded, of unknown sign and distribution: δe gains Σ_k ε_k·v_k with |ε_k| ≤ 1 (the
  scale known only to its datasheet tolerance, the assumed temperature change);
* known: a fixed bias b (an eyelet's edge wrap, always a longer wire).

E is convex in δe, so over the box |ε_k| ≤ 1 it is largest at a corner. The bound is the
95 % quantile of max over the corners of E(x + b + Σ ε_k v_k), x ~ N(0, Σ): whatever the
bounded errors are within their limits, P(E ≤ bound) ≥ 95 % (up to the linearisation). E
is not a generalised χ² (a mean of norms, not a quadratic form), so the quantile is taken
from :data:`DRAWS` Gaussian draws: the R_d low-discrepancy sequence (Roberts 2018: x_n =
frac(s + n·α), α_k = φ_d^−k with φ_d the root of x^(d+1) = x + 1), shifted by a fixed random
s, through the normal's inverse (quasi-random: a half-normal's 95 % point to under 1 %, where
1,000 independent draws scatter by 3 %; the same inputs give the same bound; no scipy.stats,
whose import alone doubled ``wirecal solve``'s start-up).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

BOUND_PROBABILITY = 0.95
"""The probability the bound holds with."""

DRAWS = 1024
"""Gaussian draws the quantile is taken from."""

SEED = 20261124
"""The draws' seed: the bound is deterministic."""

_CHUNK = 32  # draws per block: (chunk, corners, Q) floats stay in the cache (1 MB),
# and no large block is mapped and faulted in afresh per call


@dataclass(frozen=True)
class ErrorModel:
    """The parameter error δe = x + bias + Σ ε_k·edges[k], x ~ N(0, cov), |ε_k| ≤ 1.

    Internal units (rad, mm); ``edges`` is (k, m), k ≥ 0.
    """

    cov: np.ndarray
    bias: np.ndarray
    edges: np.ndarray

    def corners(self) -> np.ndarray:
        """Return the known bias plus every corner of the bounded terms' box (2^k, m)."""
        signs = np.array(list(itertools.product((-1.0, 1.0), repeat=len(self.edges))))
        if not len(self.edges):
            return self.bias[None, :]
        return self.bias + signs @ self.edges


def mean_tool_error(Jp: np.ndarray, de: np.ndarray) -> np.ndarray:
    """Return E = mean_q ‖J_p(q)·δe‖ (mm) for parameter errors ``de`` (K, m).

    ``Jp`` (Q, 3, m) is the tool-point Jacobian over the workspace in internal units.
    """
    de = np.atleast_2d(de)
    return _mean_norm((de @ Jp.reshape(-1, Jp.shape[2]).T).reshape(len(de), -1, 3))


def _mean_norm(p: np.ndarray) -> np.ndarray:
    """Return the mean over axis 1 of the norms over axis 2 of ``p`` (K, Q, 3)."""
    return np.sqrt(np.einsum("kqi,kqi->kq", p, p)).mean(axis=1)


def low_discrepancy(dim: int, draws: int, seed: int) -> np.ndarray:
    """Return ``draws`` points of the shifted R_d sequence in [0, 1)^dim (module docstring)."""
    phi = 2.0
    for _ in range(60):  # the fixed point of x = (1 + x)^(1/(d+1)): φ_d
        phi = (1.0 + phi) ** (1.0 / (dim + 1))
    alpha = phi ** -np.arange(1.0, dim + 1.0)
    shift = np.random.default_rng(seed).random(dim)
    n = np.arange(1.0, draws + 1.0)[:, None]
    return np.asarray((shift + n * alpha) % 1.0)


def bound_mm(
    Jp: np.ndarray,
    model: ErrorModel,
    probability: float = BOUND_PROBABILITY,
    draws: int = DRAWS,
    seed: int = SEED,
) -> float:
    """Return the ``probability`` quantile of the worst corner's E (module docstring).

    With p = J_p(q)·x and s_c = J_p(q)·c for a corner c, ‖p + s_c‖² = ‖p‖² + 2 x·(J_pᵀ s_c)
    + ‖s_c‖²: one product per block of draws gives every corner's squared norms, the 3-vectors
    are never formed per corner.
    """
    w, U = np.linalg.eigh((model.cov + model.cov.T) / 2)
    root = U * np.sqrt(np.clip(w, 0.0, None))  # cov = root·rootᵀ, also when singular
    u = np.clip(low_discrepancy(len(w), draws, seed), 1e-12, 1 - 1e-12)
    x = ndtri(u) @ root.T  # (draws, m)
    q, _, m = Jp.shape
    A = np.ascontiguousarray(Jp.transpose(1, 2, 0))  # (3, m, Q): component first
    s = model.corners() @ A  # (3, C, Q): each corner's tool-point errors
    # the terms linear in x and the constant, per corner and configuration: (m + 1, C·Q);
    # single precision: 1e-7 beside the draws' 1 %, and half the time
    W = np.concatenate([2 * np.einsum("imq,icq->mcq", A, s), np.sum(s * s, axis=0)[None]])
    W = W.reshape(m + 1, -1).astype(np.float32)
    X = np.hstack([x, np.ones((draws, 1))]).astype(np.float32)
    A = A.astype(np.float32)
    ones = np.ones(q, dtype=np.float32)  # sums over the configurations as a product
    worst = np.empty(draws)
    for start in range(0, draws, _CHUNK):
        block = slice(start, start + _CHUNK)
        p = X[block, :m] @ A  # (3, chunk, Q)
        p *= p
        sq = (X[block] @ W).reshape(-1, len(s[0]), q)
        sq += p.sum(axis=0)[:, None, :]
        # rounding may leave -1e-7·‖s‖² where the norm is 0: its size is as good as 0
        np.sqrt(np.abs(sq, out=sq), out=sq)
        worst[block] = (sq @ ones).max(axis=1) / q
    return float(np.quantile(worst, probability))
