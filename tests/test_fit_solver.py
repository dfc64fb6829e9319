"""The fit's Levenberg–Marquardt solver against ``scipy.optimize.least_squares``."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import least_squares

from wirecal.solver.fit.solver import levenberg_marquardt


def _problem(seed: int, outliers: int):
    """y = a·exp(−b·t) + c·sin(d·t) with noise 0.01 and ``outliers`` rows off by 1–3."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 4, 400)
    truth = np.array([2.0, 0.7, 0.5, 3.0])
    y = truth[0] * np.exp(-truth[1] * t) + truth[2] * np.sin(truth[3] * t)
    y = y + rng.normal(0, 0.01, t.size)
    bad = rng.choice(t.size, outliers, replace=False)
    y[bad] += rng.uniform(1, 3, outliers)

    def residual(x):
        return x[0] * np.exp(-x[1] * t) + x[2] * np.sin(x[3] * t) - y

    def jac(x):
        e, s = np.exp(-x[1] * t), np.sin(x[3] * t)
        return np.column_stack([e, -x[0] * t * e, s, x[2] * t * np.cos(x[3] * t)])

    return residual, jac, truth


@pytest.mark.parametrize(("loss", "outliers"), [("linear", 0), ("soft_l1", 20)])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_minimum_is_scipys(loss, outliers, seed):
    """The same minimum as scipy's trust region (tight tolerances), to 10⁻⁶ of the
    estimates' size; from a start 20–30 % off."""
    residual, jac, truth = _problem(seed, outliers)
    x0 = truth * np.array([1.3, 0.8, 1.2, 1.05])
    f_scale = 0.05
    ref = least_squares(
        residual, x0, jac=jac, loss=loss, f_scale=f_scale, ftol=1e-14, xtol=1e-14, gtol=1e-14
    ).x
    got = levenberg_marquardt(lambda x: (residual(x), jac(x)), x0, loss=loss, f_scale=f_scale)
    assert np.max(np.abs(got - ref)) < 1e-6
    assert np.max(np.abs(got - truth)) < 0.02  # and the truth, to the noise


def test_a_degenerate_direction_is_not_run_along():
    """Two identical columns: the minimum-norm step, not a run to large values."""
    t = np.linspace(0, 1, 50)
    y = 3.0 * t + 1.0

    def evaluate(x):
        r = (x[0] + x[1]) * t + x[2] - y
        return r, np.column_stack([t, t, np.ones_like(t)])

    got = levenberg_marquardt(evaluate, np.zeros(3))
    assert got == pytest.approx([1.5, 1.5, 1.0], abs=1e-9)
