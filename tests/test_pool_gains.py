"""The pool planner's greedy choice decided by bounds (solver/plan/pool.py, issue 34).

``greedy_rows`` computes einsum's gains only for the rows its bounds leave in the race;
the rows and the posterior must be those of einsum over every row, bit for bit, ties
included (the first of equal gains wins).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.solver.plan.pool import RIDGE, _best_row, greedy_rows


def _einsum_greedy_rows(J, W, n, prior_var=None):
    """The greedy choice with einsum's gain of every row (the definition, written out)."""
    norm = np.maximum(np.linalg.norm(J, axis=0), 1e-12)
    A, W = J / norm, W / np.outer(norm, norm)
    var = np.full(A.shape[1], np.inf) if prior_var is None else prior_var * norm**2
    var = np.minimum(var, 1.0 / (RIDGE * np.mean(np.sum(A**2, axis=0))))
    inv = np.diag(var)
    chosen = []
    free = np.ones(len(A), dtype=bool)
    for _ in range(min(n, len(A))):
        V = A @ inv
        gain = np.einsum("ij,jk,ik->i", V, W, V) / (1.0 + np.sum(A * V, axis=1))
        i = int(np.argmax(np.where(free, gain, -np.inf)))
        inv -= np.outer(V[i], V[i]) / (1.0 + A[i] @ V[i])
        free[i] = False
        chosen.append(i)
    return np.array(chosen), inv / np.outer(norm, norm)


def _problem(seed: int, m: int, k: int, repeats: int):
    """A random J (m, k) with ``repeats`` rows repeated (equal gains) and a PSD weight."""
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(m, k)) * rng.uniform(0.01, 100.0, k)
    J[rng.integers(0, m, repeats)] = J[rng.integers(0, m, repeats)]
    B = rng.normal(size=(k, k))
    return rng, J, B @ B.T


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    m=st.integers(1, 60),
    k=st.integers(1, 12),
    repeats=st.integers(0, 10),
    n=st.integers(1, 30),
    prior=st.booleans(),
)
def test_the_rows_and_the_posterior_are_einsums_bit_for_bit(seed, m, k, repeats, n, prior):
    rng, J, W = _problem(seed, m, k, repeats)
    prior_var = rng.uniform(1e-6, 10.0, k) if prior else None
    rows, post = greedy_rows(J, W, n, prior_var)
    want_rows, want_post = _einsum_greedy_rows(J, W, n, prior_var)
    assert rows.tolist() == want_rows.tolist()
    assert post.tobytes() == want_post.tobytes()


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 300), k=st.integers(1, 32))
def test_einsum_of_some_rows_is_those_rows_of_einsum_of_all(seed, m, k):
    """What the bounds rely on: einsum's gain of a row does not depend on the other rows."""
    rng, V, W = _problem(seed, m, k, 0)
    some = np.flatnonzero(rng.random(m) < 0.3)
    full = np.einsum("ij,jk,ik->i", V, W, V)
    part = np.einsum("ij,jk,ik->i", V[some], W, V[some])
    assert part.tobytes() == full[some].tobytes()


@pytest.mark.filterwarnings("ignore:divide by zero:RuntimeWarning")  # einsum's, as before
@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), bad=st.sampled_from([np.nan, np.inf, 0.0, -1.0]))
def test_without_sure_bounds_every_row_is_weighed(seed, bad):
    """A non-finite V or a denominator not above 0: the first largest gain of all free rows."""
    rng, V, W = _problem(seed, 20, 4, 3)
    denom = 1.0 + rng.uniform(0.0, 5.0, 20)
    free = rng.random(20) < 0.7
    free[rng.integers(0, 20)] = True
    if bad in (0.0, -1.0):
        denom[rng.integers(0, 20, 3)] = bad
    else:
        V[rng.integers(0, 20), rng.integers(0, 4)] = bad
    with np.errstate(all="ignore"):
        gain = np.einsum("ij,jk,ik->i", V, W, V) / denom
    assert _best_row(V, W, denom, free) == int(np.argmax(np.where(free, gain, -np.inf)))
