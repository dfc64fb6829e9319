"""Identifiability of error parameters from wire lengths.

Identifiability of error parameters from wire lengths: rank, singular values,
unobservable parameters or combinations, and the observability indices O1–O5
(Sun & Hollerbach's list) of the distance Jacobian in boundary units.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from wirecal.solver.kinematics import Model
from wirecal.solver.memo import Kept, digest
from wirecal.solver.sensitivity import sensitivity

BASE_PARAMETERS = frozenset({"al0", "a0", "th1", "d1"})
"""Row 1 of the table: a rigid motion of everything, invisible to any wire length."""

RANK_RTOL = 1e-9
"""Singular values below RANK_RTOL·σ_max are structural zeros (round-off is ~1e-15)."""


@dataclass(frozen=True)
class Identifiability:
    """Rank, singular values, unobservable parameters and observability indices."""

    names: tuple[str, ...]
    n_points: int
    singular_values: np.ndarray
    rank: int
    unobservable: tuple[str, ...]  # single parameters
    combinations: tuple[tuple[tuple[str, float], ...], ...]  # null-space combinations
    indices: dict[str, float]  # O1..O5

    def describe(self) -> list[str]:
        """Return the analysis in words, one sentence per line."""
        m = len(self.names)
        lines = [
            f"{self.n_points} points, {m} parameters: the distance Jacobian has rank "
            f"{self.rank} of {m}."
        ]
        for name in self.unobservable:
            if name in BASE_PARAMETERS:
                why = (
                    "it moves every calibration point and the encoder location alike "
                    "(a rigid motion of the whole arm), so no wire length changes"
                )
            else:
                why = "no wire length of these points depends on it; add points that move it"
            lines.append(f"{name} is unobservable: {why}.")
        for combo in self.combinations:
            terms = " ".join(f"{c:+.4g}·{n}" for n, c in combo)
            lines.append(
                f"{terms} is unobservable: changing these parameters together in "
                "this ratio leaves every wire length unchanged (they are redundant; "
                "fix all but one)."
            )
        if self.rank == m:
            lines.append("Every parameter is identifiable from these points.")
        o = self.indices
        lines.append(
            "Observability: O1 = {O1:.4g}, O2 = {O2:.4g} (inverse condition number), "
            "O3 = {O3:.4g} (smallest singular value), O4 = {O4:.4g} (noise amplification), "
            "O5 = {O5:.4g}.".format(**o)
        )
        return lines


def covariance(J: np.ndarray, sigma2: float) -> tuple[np.ndarray, np.ndarray]:
    """σ²·(JᵀJ)⁺ over the directions the data sees, and which parameters it identifies.

    Singular values of ``J`` (N, m) below RANK_RTOL·σ_max are structural zeros. A parameter
    with a component along such a direction is not identified: its variance is infinite,
    where the plain pseudo-inverse would call it 0. Returns the covariance (m, m; finite,
    restricted to the seen directions) and the (m,) mask of identified parameters.
    """
    m = J.shape[1]
    s, vt = right_svd(J)
    s = np.concatenate([s, np.zeros(m - s.size)])
    seen = s > RANK_RTOL * (s[0] if s[0] > 0 else 1.0)
    cov = sigma2 * (vt[seen].T / s[seen] ** 2) @ vt[seen]
    identified = ~np.any(np.abs(vt[~seen]) > NULL_COMPONENT, axis=0)
    return cov, identified


TALL_ROWS = 1000
"""From this many rows (and twice the columns) :func:`right_svd` factors J = QR first."""


def right_svd(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the singular values and the right vectors vt (m, m) of ``J`` (N, m).

    Not the left vectors: N × N of them for 20,000 rows would be 3 GB, and N × m of them
    half the time at 200,000 rows. A tall J (:data:`TALL_ROWS`) goes through its triangular
    factor R (J = QR, m × m): the singular values and right vectors of R are J's, and
    LAPACK's SVD (gesdd) of a J that tall starts with that very factorisation, so they are
    the same numbers (``tests/test_identifiability.py``).
    """
    J = np.asarray(J)
    return _FACTORED.get(digest(J), lambda: _right_svd(J))


_FACTORED: Kept[tuple[np.ndarray, np.ndarray]] = Kept(16)
"""The last factorisations: a Jacobian is often factored again (its covariance, then its
rank or null space; a budget's check, then its covariance), the same numbers each time."""


def _right_svd(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return :func:`right_svd` of ``J`` computed, read-only (the results are kept)."""
    if J.shape[0] >= max(TALL_ROWS, 2 * J.shape[1]):
        J = cast(np.ndarray, np.linalg.qr(J, mode="r"))  # R alone (the stubs say a pair)
    _, s, vt = np.linalg.svd(J, full_matrices=J.shape[0] < J.shape[1])
    s.setflags(write=False)
    vt.setflags(write=False)
    return s, vt


def std_and_correlation(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the σ (a negative rounding of a variance as 0) and correlations of ``cov``.

    A correlation of a parameter with σ = 0 is NaN (0/0) or ±inf.
    """
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        return sd, cov / np.outer(sd, sd)


NULL_COMPONENT = 1e-6
"""A parameter whose share of a unit null-space vector exceeds this is not identified."""


def observability_indices(s: np.ndarray, n_rows: int) -> dict[str, float]:
    """O1–O5 from the singular values σ1 ≥ … ≥ σm of an n_rows × m Jacobian.

    O1 = (σ1⋯σm)^(1/m)/√n (Borm & Menq), O2 = σm/σ1 (Driels & Pathre), O3 = σm
    (Nahvi & Hollerbach), O4 = σm²/σ1 (noise amplification), O5 = 1/Σ(1/σi).
    """
    s = np.asarray(s, dtype=float)
    if s.size == 0 or s[-1] <= 0:
        return dict.fromkeys(("O1", "O2", "O3", "O4", "O5"), 0.0)
    return {
        "O1": float(np.exp(np.mean(np.log(s))) / np.sqrt(n_rows)),
        "O2": float(s[-1] / s[0]),
        "O3": float(s[-1]),
        "O4": float(s[-1] ** 2 / s[0]),
        "O5": float(1.0 / np.sum(1.0 / s)),
    }


def analyse(
    model: Model, q_deg: np.ndarray, theta0_deg: np.ndarray, names: Sequence[str]
) -> Identifiability:
    """Rank, null space and observability of ∂d/∂e over the points ``q_deg``."""
    names = tuple(names)
    return analyse_jacobian(sensitivity(model, q_deg, theta0_deg, names).psi, names)


def analyse_jacobian(J: np.ndarray, names: tuple[str, ...]) -> Identifiability:
    """:func:`analyse` of a distance Jacobian (N, m) already computed, boundary units."""
    s = np.linalg.svd(J, compute_uv=False) if J.size else np.zeros(0)
    # Pad to m values: a Jacobian with fewer rows than columns has m − N zero values.
    s = np.concatenate([s, np.zeros(len(names) - s.size)])
    tol = RANK_RTOL * (s[0] if s.size and s[0] > 0 else 1.0)
    rank = int(np.sum(s > tol))

    col_norm = np.linalg.norm(J, axis=0)
    alone = [k for k in range(len(names)) if col_norm[k] <= tol]
    rest = [k for k in range(len(names)) if k not in alone]
    combos: list[tuple[tuple[str, float], ...]] = []
    if rest and rank < len(rest):
        sr, vt = right_svd(J if len(rest) == J.shape[1] else J[:, rest])  # J: its kept factors
        sr = np.concatenate([sr, np.zeros(len(rest) - sr.size)])
        null = vt[sr <= tol]
        for row in _rref(null):
            combo = tuple((names[rest[k]], float(c)) for k, c in enumerate(row) if abs(c) > 1e-6)
            combos.append(combo)
    return Identifiability(
        names=names,
        n_points=int(J.shape[0]),
        singular_values=s,
        rank=rank,
        unobservable=tuple(names[k] for k in alone),
        combinations=tuple(combos),
        indices=observability_indices(np.where(s > tol, s, 0.0), J.shape[0]),
    )


def _rref(a: np.ndarray) -> np.ndarray:
    """Reduced row echelon form: a sparse, readable basis of the same row space."""
    a = np.array(a, dtype=float)
    rows, cols = a.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        piv = r + int(np.argmax(np.abs(a[r:, c])))
        if abs(a[piv, c]) < 1e-9:
            continue
        a[[r, piv]] = a[[piv, r]]
        a[r] /= a[r, c]
        for k in range(rows):
            if k != r:
                a[k] -= a[k, c] * a[r]
        r += 1
    return a[:r]


@dataclass(frozen=True)
class Selection:
    """The columns :func:`select_columns` kept, and why each other candidate was left out."""

    kept: tuple[int, ...]  # indices into the Jacobian's columns, required ones first
    dropped: tuple[tuple[str, str], ...]  # (name, reason) of each candidate left out


def select_columns(
    J: np.ndarray,
    names: Sequence[str],
    n_required: int,
    *,
    sigma_mm: float | None = None,
    max_std: float | np.ndarray = math.inf,
) -> Selection:
    """Choose the identifiable parameters of a Jacobian, greedily in column order.

    The first ``n_required`` columns are always kept; each later one is kept when it raises
    the rank of the kept columns, scaled to unit length (:data:`RANK_RTOL`; a column zero
    to round-off, no longer than RANK_RTOL times the longest, stays zero), when
    :func:`covariance` identifies every kept parameter with it, and, with a noise
    ``sigma_mm``, when it leaves every kept parameter's σ (σ²·(JᵀJ)⁻¹, boundary units of
    ``J``) below ``max_std`` (one limit, or one per column). A candidate left out is named
    with the degenerate combination it completes.
    """
    names = tuple(names)
    if J.shape[0] > J.shape[1]:  # R of J = QR has J's singular values and right vectors
        J = np.asarray(np.linalg.qr(J, mode="r"))
    unit = _unit_columns(J)
    limit = np.broadcast_to(np.asarray(max_std, dtype=float), (len(names),))
    kept = list(range(n_required))
    rank = _rank(unit[:, kept]) if kept else 0
    known = covariance(J[:, kept], 1.0)[1] if kept else np.zeros(0, dtype=bool)  # so far
    dropped: list[tuple[str, str]] = []
    for k in range(n_required, len(names)):
        trial = [*kept, k]
        r = _rank(unit[:, trial])
        cov, identified = covariance(J[:, trial], 1.0 if sigma_mm is None else sigma_mm**2)
        if r <= rank or not identified[-1] or np.any(known & ~identified[:-1]):
            why = "degenerate: " if r <= rank else "not identified: nearly "
            dropped.append((names[k], why + _null_combination(J[:, trial], names, trial)))
            continue
        if sigma_mm is not None:
            std = np.sqrt(np.diag(cov))
            over = std / limit[trial]
            if np.max(over) >= 1:
                worst = int(np.argmax(over))
                dropped.append(
                    (
                        names[k],
                        f"poorly identified: with it {names[trial[worst]]}'s σ is "
                        f"{std[worst]:.3g}, beyond {limit[trial[worst]]:g}; nearly: "
                        + _null_combination(J[:, trial], names, trial),
                    )
                )
                continue
        kept.append(k)
        rank, known = r, identified
    return Selection(tuple(kept), tuple(dropped))


def _unit_columns(J: np.ndarray) -> np.ndarray:
    """Return J's columns scaled to unit length, those zero to round-off left zero.

    Zero to round-off: no longer than :data:`RANK_RTOL` times the longest column. Scaled,
    such a column would be a unit column of round-off, of any direction: it would raise the
    rank of any set it joins.
    """
    norm = np.linalg.norm(J, axis=0)
    zero = norm <= RANK_RTOL * (np.max(norm) if norm.size else 0.0)
    return np.where(zero, 0.0, J / np.where(zero, 1.0, norm))


def _null_combination(J: np.ndarray, names: tuple[str, ...], columns: list[int]) -> str:
    """Return the direction J sees least, in words, scaled to the last column's +1.

    Terms are kept by their share of the direction with the columns scaled to unit length
    (above 0.1 %; :func:`_unit_columns`), so a scale in ppm beside lengths in mm is not
    lost; coefficients are in the columns' own units.
    """
    norm = np.linalg.norm(J, axis=0)
    unit = _unit_columns(J)
    v = right_svd(unit)[1][-1]
    keep = np.abs(v) > 1e-3 * np.max(np.abs(v))
    c = v / np.where(np.any(unit, axis=0), norm, 1.0)
    c = c / c[-1] if keep[-1] else c / c[np.argmax(np.abs(v))]
    terms = " ".join(
        f"{x:+.3g}·{names[k]}" for k, x, ok in zip(columns, c, keep, strict=True) if ok
    )
    return f"{terms} changes no length"


def _rank(unit: np.ndarray) -> int:
    """Return the rank of columns scaled to unit length (:func:`_unit_columns`)."""
    s = np.linalg.svd(unit, compute_uv=False)
    return int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0


def propose_parameters(
    model: Model, q_deg: np.ndarray, theta0_deg: np.ndarray, nominal_dh: np.ndarray
) -> tuple[str, ...]:
    """Return the error parameters to calibrate (in the style of the paper's eq. 20).

    Error parameters to calibrate, in the style of the paper's eq. 20: the θ offsets of
    joints 2…n and every non-zero length a_{i-1}, d_i of rows 2…n (row 1 is a rigid motion
    of the whole arm, :data:`BASE_PARAMETERS`), each kept only when it raises the rank of the
    distance Jacobian over the points ``q_deg`` (:func:`select_columns`) — so of redundant
    ones (the d's of parallel axes, θ_n with a tool point on axis n) the first is kept.
    """
    n = model.n_joints
    lengths = [
        name
        for i in range(1, n)
        for name, value in ((f"a{i}", nominal_dh[i, 1]), (f"d{i + 1}", nominal_dh[i, 3]))
        if abs(value) > 1e-9
    ]
    candidates = [f"th{i + 1}" for i in range(1, n)] + sorted(lengths, key=lambda s: s[0])
    J = sensitivity(model, q_deg, theta0_deg, candidates).psi
    return tuple(candidates[k] for k in select_columns(J, candidates, 0).kept)
