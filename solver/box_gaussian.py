"""A Gaussian restricted to a box: the posterior of quantities known to lie in a range.

The prior of each quantity is uniform over its range [lo, hi] (known only by its limits:
the GUM's rectangular distribution, JCGM 100:2008 §4.3.7); the readings say N(μ, S) of them
together. The posterior is N(μ, S) restricted to the box: a truncated Gaussian where the
readings are sharp against the range, the uniform where they say nothing, and in between
whatever their correlations leave (two compliances the readings know only as a sum are
bounded apart by the box alone).

Its draws come from the GHK sampler (Geweke 1991, Hajivassiliou 1994, Keane 1994: the
standard importance sampler of a truncated multivariate normal): with S = L·Lᵀ, each
coordinate in turn from the one-dimensional normal truncated to what the box leaves it
given the earlier ones, each draw weighted by the product of those truncations'
probabilities. The coordinates go most informative first (smallest variance). A
coordinate with an infinite variance is uniform over its range, apart from the others.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import log_ndtr, ndtri_exp


@dataclass(frozen=True)
class BoxGaussian:
    """N(``mean``, ``cov``) restricted to [``lo``, ``hi``] (k,) (module docstring).

    ``cov`` (k, k) over the coordinates with ``flat`` False; a ``flat`` coordinate is
    uniform over its range (its rows and columns of ``cov`` are not used).
    """

    mean: np.ndarray
    cov: np.ndarray
    flat: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def sample(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return draws t (n, k) of the probabilities ``u`` (n, k) and their weights (n,).

        The weights sum to 1 (module docstring).
        """
        n = len(u)
        t = self.lo + u * (self.hi - self.lo)  # the flat coordinates; the others overwritten
        g = np.flatnonzero(~self.flat)
        g = g[np.argsort(np.diag(self.cov)[g], kind="stable")]
        log_w = np.zeros(n)
        if g.size:
            L = _root(self.cov[np.ix_(g, g)])
            z = np.zeros((n, g.size))
            for i, j in enumerate(g):
                centre = self.mean[j] + z[:, :i] @ L[i, :i]
                a, b = (self.lo[j] - centre) / L[i, i], (self.hi[j] - centre) / L[i, i]
                z[:, i], log_p = truncated_standard(a, b, u[:, j])
                log_w += log_p
                t[:, j] = np.clip(centre + L[i, i] * z[:, i], self.lo[j], self.hi[j])
        w = np.exp(log_w - log_w.max())
        return t, w / w.sum()

    def moments(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the posterior's mean (k,) and covariance (k, k) from the draws of ``u``."""
        t, w = self.sample(u)
        mean = w @ t
        d = t - mean
        return mean, (d.T * w) @ d


def _root(S: np.ndarray) -> np.ndarray:
    """Return the Cholesky factor of ``S``.

    Of S + 10⁻¹² of its diagonal's largest where round-off left it not quite positive
    definite.
    """
    try:
        return np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        return np.linalg.cholesky(S + 1e-12 * np.max(np.diag(S)) * np.eye(len(S)))


def truncated_standard(
    a: np.ndarray, b: np.ndarray, u: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return z of the standard normal restricted to [a, b] at probabilities u, and log P.

    P = Φ(b) − Φ(a). All in logs of Φ's lower tail (mirrored when the range lies above 0):
    a range far in a tail has P below any float, and z = Φ⁻¹((1 − u)·Φ(a) + u·Φ(b)) is taken
    from the log of its argument.
    """
    flip = a + b > 0
    lo, hi = np.where(flip, -b, a), np.where(flip, -a, b)
    la, lb = log_ndtr(lo), log_ndtr(hi)
    with np.errstate(divide="ignore"):
        log_p = lb + np.log1p(-np.exp(la - lb))
        v = np.where(flip, 1.0 - u, u)
        z = ndtri_exp(np.logaddexp(np.log1p(-v) + la, np.log(v) + lb))
    z = np.clip(z, lo, hi)
    return np.where(flip, -z, z), log_p
