"""Which DH errors a cable-length fit keeps: those the rows carry beyond their noise (BIC).

:func:`~wirecal.solver.fit.calibrate.choose` keeps every DH error the rows *identify* (its σ below
the gate's limit). Identified is not enough: a DH error estimated at 1.5σ from zero moves
the tool point by its noise, and a patch carrying a dozen of them predicts other rows (the
next session, the rest of the workspace) worse than one without them. The fit therefore
eliminates DH errors backward by the **Bayesian information criterion**, BIC = χ²/σ² +
k·ln N: dropping parameter k (fixing it at 0, the robot file's value) raises χ²/σ² by
z_k² = x_k²/C_kk (C = σ²·(JᵀJ)⁻¹) and saves ln N; the DH error of least z² is dropped while
z² < ln N, and the others' estimates and covariance updated exactly as the linearised
least squares with it fixed (x ← x − C_{:k}·x_k/C_kk, C ← C − C_{:k}C_{k:}/C_kk), no refit.
The attachment, anchor, offsets and scale are never dropped.

Why BIC, not a cross-validated choice: BIC is consistent (with more rows it keeps the
parameters that are there and no others), while cross-validation and AIC keep a few noise
parameters in expectation — the ones that did not carry across sessions; and the
elimination costs k×k algebra, where cross-validating twenty candidates refits each fold
twenty times (100,000 rows: minutes). Held-out figures then check the choice on rows the fit
did not see (:mod:`~wirecal.solver.fit.holdout`).
"""

from __future__ import annotations

import numpy as np


def bic_eliminated(
    cov: np.ndarray, x: np.ndarray, candidates: list[int], n_rows: int
) -> list[tuple[int, float]]:
    """Return (column, |z| when dropped) of each candidate BIC drops, in order (docstring).

    ``cov`` (m, m): σ²·(JᵀJ)⁻¹ of the estimate ``x`` (m,) over the ``n_rows`` rows fitted;
    ``candidates``: the columns that may be dropped (the DH errors).
    """
    cov = np.array(cov, dtype=float)
    x = np.array(x, dtype=float)
    penalty = np.log(n_rows)
    left = list(candidates)
    dropped: list[tuple[int, float]] = []
    while left:
        z2 = np.array([x[k] ** 2 / cov[k, k] if cov[k, k] > 0 else 0.0 for k in left])
        worst = int(np.argmin(z2))
        if z2[worst] >= penalty:
            break
        k = left.pop(worst)
        if cov[k, k] > 0:  # else the rows do not see it: nothing to update
            x -= cov[:, k] * x[k] / cov[k, k]
            cov -= np.outer(cov[:, k], cov[k, :]) / cov[k, k]
        dropped.append((k, float(np.sqrt(z2[worst]))))
    return dropped
