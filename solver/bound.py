"""The 95 % bound of a calibration's tool-point error, from the error budget's model.

The quantity bounded is the one a calibration is judged by against the truth (the demo's
"tool-point error vs truth"): the mean over the workspace's configurations q (the
budget's 1,000, :func:`~wirecal.solver.accuracy.workspace`) of ‖p_true(q) − p_est(q)‖.
Linearised, the parameter error is δe = M·δd (:mod:`wirecal.solver.budget`) and

    E(δe) = mean_q ‖J_p(q)·δe‖.

The budget's sources enter δe in three ways, each with a stated distribution:

* random, Gaussian: δe ~ N(0, Σ) (reading noise, a measured scale, the zero drift, the
  identified compliances' σ);
* known only by its limits: δe gains Σ_k ε_k·v_k, ε_k uniform in [−1, 1] and independent
  (the GUM's rectangular distribution for a quantity of which only the limits are known,
  JCGM 100:2008 §4.3.7: the scale known only to its datasheet tolerance, the assumed
  temperature change, a one-sided term between 0 and v as the bias v/2 and the edge v/2);
* of a known size but either sign: δe gains Σ_l s_l·w_l, s_l = ±1 with equal probability
  (the temperature's change over the run, of the size assumed);
* known: a fixed bias b (an eyelet's edge wrap, always a longer wire);
* a Gaussian restricted to a box (:class:`Truncated`): δe gains Σ t_j·u_j, t the
  posterior of quantities known to lie in a box (their prior, uniform there) that the
  readings estimate as N(μ, S) together: N(μ, S) restricted to the box
  (:class:`~wirecal.solver.box_gaussian.BoxGaussian`, weighted draws) — the uniform where
  the readings say nothing, a half-Gaussian at an edge where μ lies there (the unidentified
  compliances, :func:`~wirecal.solver.budget.compliance_errors`).

The bound is the 95 % quantile of E(x + b + Σ ε_k v_k + Σ s_l w_l + Σ t_j u_j) over
x ~ N(0, Σ), the ε_k, the s_l and the t_j jointly: P(E ≤ bound) = 95 % (up to the
linearisation) when each term has its stated distribution. E is not a generalised χ² (a
mean of norms, not a quadratic form), so the quantile is taken from :data:`DRAWS` draws of
(x, ε, s, t): the R_d low-discrepancy sequence (Roberts 2018: x_n = frac(s + n·α),
α_k = φ_d^−k with φ_d the root of x^(d+1) = x + 1), shifted by a fixed random s, through
the normal's inverse for x, 2u − 1 for ε, the sign of u − ½ for s and the GHK sampler
for t, whose weights make the quantile a weighted one (quasi-random: a half-normal's 95 %
point to under 1 %, where as many independent draws scatter by 1.5 %; the same inputs give
the same bound; no scipy.stats, whose import alone doubled ``wirecal solve``'s start-up).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri

from wirecal.solver.box_gaussian import BoxGaussian
from wirecal.solver.memo import Kept, digest

BOUND_PROBABILITY = 0.95
"""The probability the bound holds with."""

DRAWS = 4096
"""Draws the quantile is taken from: with 1,024, a compliance run's bound (30 dimensions)
scattered by 1.1 % over the sequence's shifts, with 4,096 by 0.25 %."""

SEED = 20261124
"""The draws' seed: the bound is deterministic."""

_CHUNK = 64  # draws per block: (3, chunk, Q) floats stay in the cache


@dataclass(frozen=True)
class Truncated:
    """A vector t of quantities known in a box, posterior ``posterior``, moving δe by Uᵀ·t.

    ``directions`` U (k, m). Centred: δe gains Uᵀ·(t − E[t]); E[t] is in the bias of the
    :class:`ErrorModel` that holds it (:func:`truncated_model`). Its moments are those of
    :data:`DRAWS` draws of the sequence the bound uses (the same rule as the bound's).
    """

    directions: np.ndarray
    posterior: BoxGaussian

    @functools.cached_property
    def moments(self) -> tuple[np.ndarray, np.ndarray]:
        """Return E[t] (k,) and Cov[t] (k, k)."""
        return self.posterior.moments(_probabilities(len(self.posterior.mean), DRAWS, SEED))


def truncated_model(directions: np.ndarray, posterior: BoxGaussian) -> ErrorModel:
    """Return the error Uᵀ·t of a box-restricted Gaussian t (:class:`Truncated`)."""
    t = Truncated(np.asarray(directions, dtype=float), posterior)
    m = t.directions.shape[1]
    return ErrorModel(np.zeros((m, m)), t.moments[0] @ t.directions, np.zeros((0, m)), None, t)


@dataclass(frozen=True)
class ErrorModel:
    """The parameter error δe = x + bias + Σ ε_k·edges[k] + Σ s_l·signs[l] + Σ t_j·u_j.

    x ~ N(0, cov), ε_k ~ U(−1, 1), s_l = ±1, t_j the centred :class:`Truncated` along
    u_j (module docstring). Internal units (rad, mm); ``edges`` (k, m) and ``signs`` (l, m),
    k, l ≥ 0.
    """

    cov: np.ndarray
    bias: np.ndarray
    edges: np.ndarray
    signs: np.ndarray | None = None  # None: (0, m)
    truncated: Truncated | None = None

    def sign_terms(self) -> np.ndarray:
        """Return ``signs`` as an (l, m) array."""
        return np.zeros((0, len(self.bias))) if self.signs is None else self.signs

    def second_moment(self) -> np.ndarray:
        """Return E[δe·δeᵀ] = cov + bias·biasᵀ + edgesᵀ·edges/3 + signsᵀ·signs + Uᵀ·Var t·U.

        A uniform ε has variance 1/3, a sign 1. The expected (RMS) error of the budget's
        terms uses it: the same distributions as the bound.
        """
        w = self.sign_terms()
        out = self.cov + np.outer(self.bias, self.bias) + self.edges.T @ self.edges / 3.0 + w.T @ w
        if self.truncated is not None:
            u = self.truncated.directions
            out = out + u.T @ self.truncated.moments[1] @ u
        return out

    def padded(self, size: int) -> ErrorModel:
        """Return the model over ``size`` ≥ m parameters, the extra ones without error."""
        extra = size - len(self.bias)
        t = self.truncated
        moved = None if t is None else np.pad(t.directions, ((0, 0), (0, extra)))
        return ErrorModel(
            np.pad(self.cov, ((0, extra), (0, extra))),
            np.pad(self.bias, (0, extra)),
            np.pad(self.edges, ((0, 0), (0, extra))),
            np.pad(self.sign_terms(), ((0, 0), (0, extra))),
            None if t is None or moved is None else Truncated(moved, t.posterior),
        )


def joined(models: list[ErrorModel]) -> ErrorModel:
    """Return the error of independent sources together.

    Covariances and biases add; the terms known by their limits are all kept (the all-zero
    edges dropped), and the one box-restricted term if any.
    """
    edges = np.vstack([m.edges for m in models])
    signs = np.vstack([m.sign_terms() for m in models])
    ts = [m.truncated for m in models if m.truncated is not None]
    if len(ts) > 1:
        raise ValueError("one box-restricted term per error model")  # none joins two
    return ErrorModel(
        np.sum([m.cov for m in models], axis=0),
        np.sum([m.bias for m in models], axis=0),
        edges[np.any(edges != 0, axis=1)],
        signs[np.any(signs != 0, axis=1)],
        ts[0] if ts else None,
    )


def mean_tool_error(Jp: np.ndarray, de: np.ndarray) -> np.ndarray:
    """Return E = mean_q ‖J_p(q)·δe‖ (mm) for parameter errors ``de`` (K, m).

    ``Jp`` (Q, 3, m) is the tool-point Jacobian over the workspace in internal units.
    """
    de = np.atleast_2d(de)
    p = (de @ Jp.reshape(-1, Jp.shape[2]).T).reshape(len(de), -1, 3)
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


@functools.lru_cache(maxsize=16)
def _probabilities(dim: int, draws: int, seed: int) -> np.ndarray:
    """Return the sequence's points kept off 0 and 1 (the normal's inverse is finite).

    The same every call: kept (read-only) for the next bound of as many dimensions.
    """
    u = np.clip(low_discrepancy(dim, draws, seed), 1e-12, 1 - 1e-12)
    u.setflags(write=False)
    return u


@functools.lru_cache(maxsize=16)
def _normal_scores(dim: int, m: int, draws: int, seed: int) -> np.ndarray:
    """Return the normal's inverse of the first ``m`` coordinates of the points (read-only)."""
    x = ndtri(_probabilities(dim, draws, seed)[:, :m])
    x.setflags(write=False)
    return x


def draws_of(
    model: ErrorModel, draws: int = DRAWS, seed: int = SEED
) -> tuple[np.ndarray, np.ndarray | None]:
    """Return ``draws`` parameter errors δe of ``model`` (draws, m) and their weights.

    The Gaussian's coordinates come first in the sequence, the uniform ε_k after them,
    the signs s_l, then the box-restricted t (centred: its mean is in the bias; weighted,
    :class:`~wirecal.solver.box_gaussian.BoxGaussian`; None: equal weights).
    """
    w, U = np.linalg.eigh((model.cov + model.cov.T) / 2)
    root = U * np.sqrt(np.clip(w, 0.0, None))  # cov = root·rootᵀ, also when singular
    m, k, signs, t = len(w), len(model.edges), model.sign_terms(), model.truncated
    n = m + k + len(signs)
    dim = n + (0 if t is None else len(t.posterior.mean))
    u = _probabilities(dim, draws, seed)
    x = _normal_scores(dim, m, draws, seed) @ root.T + model.bias
    x += (2.0 * u[:, m : m + k] - 1.0) @ model.edges.reshape(k, m)
    x += np.sign(u[:, m + k : n] - 0.5) @ signs
    if t is None:
        return x, None
    drawn, weights = t.posterior.sample(u[:, n:])
    return x + (drawn - t.moments[0]) @ t.directions, weights


def bound_mm(
    Jp: np.ndarray,
    model: ErrorModel,
    probability: float = BOUND_PROBABILITY,
    draws: int = DRAWS,
    seed: int = SEED,
) -> float:
    """Return the ``probability`` quantile of E over the model's draws (module docstring).

    Weighted draws (a box-restricted term) give the weighted quantile: the least E whose
    draws at or below it weigh ``probability``. Single precision for the products (1e-7
    beside the draws' 1 %, and half the time). Kept by its inputs' contents
    (:mod:`~wirecal.solver.memo`): a bound asked for again is not drawn again.
    """
    key = digest(Jp, model, probability, draws, seed)
    return _BOUNDS.get(key, lambda: _bound_mm(Jp, model, probability, draws, seed))


_BOUNDS: Kept[float] = Kept(64)
"""The last bounds (a float each)."""


def _bound_mm(
    Jp: np.ndarray, model: ErrorModel, probability: float, draws: int, seed: int
) -> float:
    """Return :func:`bound_mm` computed."""
    de, weights = draws_of(model, draws, seed)
    de = de.astype(np.float32)
    q = Jp.shape[0]
    A = np.ascontiguousarray(Jp.transpose(1, 2, 0)).astype(np.float32)  # (3, m, Q)
    ones = np.full(q, 1.0 / q, dtype=np.float32)  # the mean over configurations as a product
    E = np.empty(draws)
    block = np.empty((3, _CHUNK, q), dtype=np.float32)  # written over: no array per block
    for start in range(0, draws, _CHUNK):
        x = de[start : start + _CHUNK]
        p = np.matmul(x, A, out=block[:, : len(x)])  # (3, chunk, Q)
        p *= p
        sq = np.add(p[0], p[1], out=p[0])  # the sum over the axis, in its order, in place
        sq += p[2]
        E[start : start + _CHUNK] = np.sqrt(sq, out=sq) @ ones
    if weights is None:
        return float(np.quantile(E, probability))
    order = np.argsort(E)
    below = np.cumsum(weights[order])
    at = min(int(np.searchsorted(below, probability)), draws - 1)
    return float(E[order][at])
