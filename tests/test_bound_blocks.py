"""The bound's blocks of draws written into one array: every draw counted, a short last block too.

``_bound_mm`` evaluates the draws in blocks of ``_CHUNK`` into one array it writes over
(issue 34: no array per block). Here the draws are not a whole number of blocks (one draw,
one short of a block, one over, 100), and the bound is checked against every norm taken
in double precision at once over the same draws (no blocks, no single precision).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import ndtri

from wirecal.solver.bound import (
    _CHUNK,
    BOUND_PROBABILITY,
    SEED,
    ErrorModel,
    bound_mm,
    low_discrepancy,
)


@pytest.mark.parametrize("draws", [1, _CHUNK - 1, _CHUNK + 1, 100])
def test_draws_not_a_whole_number_of_blocks_are_all_counted(draws):
    rng = np.random.default_rng(7)
    q, m = 50, 3
    Jp = rng.normal(size=(q, 3, m))
    root = rng.normal(size=(m, m)) * 0.1
    edges = rng.normal(size=(1, m)) * 0.2
    model = ErrorModel(root @ root.T, np.full(m, 0.05), edges)
    w, U = np.linalg.eigh(model.cov)
    u = np.clip(low_discrepancy(m + 1, draws, SEED), 1e-12, 1 - 1e-12)
    de = ndtri(u[:, :m]) @ (U * np.sqrt(np.clip(w, 0, None))).T + model.bias
    de += (2 * u[:, m:] - 1) @ edges
    E = np.linalg.norm(np.einsum("kim,dm->dki", Jp, de), axis=2).mean(axis=1)
    expected = np.quantile(E, BOUND_PROBABILITY)
    assert bound_mm(Jp, model, draws=draws) == pytest.approx(expected, rel=1e-5)
