"""Offset jumps of the cable length between sessions: change points of a row sequence.

A sensor re-mounted between sessions reads every later length with another offset. Ordered
by row, the lengths less the model without offsets are then piecewise constant plus noise.
Binary segmentation finds the jumps: a segment [a, b) splits at k where the drop of its sum
of squares about the mean,

    G(k) = n₁n₂/(n₁ + n₂)·(m₁ − m₂)²/σ²,

is largest, if G exceeds the penalty β = :data:`PENALTY_PER_LN_N`·ln N (a BIC-like penalty
in units of the noise σ, stricter than BIC's 2·ln N so that the quantisation noise's
tails do not cut a session), and each part has at least :data:`MIN_SESSION_ROWS` rows; the
parts are split again until no split pays. σ is the scatter of successive differences
(robust, median absolute deviation), which a jump does not inflate.

Outliers (a snagged or mistyped row) must not cut a session: before the search every value
is clipped to within :data:`CLIP_SIGMA` σ of the running median of
2·:data:`MIN_SESSION_ROWS` + 1 rows around it, which follows a jump but not a lone row.
"""

from __future__ import annotations

import numpy as np

PENALTY_PER_LN_N = 4.0
MIN_SESSION_ROWS = 5
CLIP_SIGMA = 3.0
MAD_TO_SIGMA = 1.4826
"""σ of normal noise per median absolute deviation."""


def robust_sigma(values: np.ndarray) -> float:
    """Return σ from the median absolute deviation (normal noise), robust to outliers."""
    v = np.asarray(values, dtype=float)
    return float(MAD_TO_SIGMA * np.median(np.abs(v - np.median(v)))) if v.size else 0.0


def difference_sigma(values: np.ndarray) -> float:
    """Return the noise σ of a piecewise-constant sequence from its successive differences."""
    return robust_sigma(np.diff(values)) / np.sqrt(2)


def change_points(
    values: np.ndarray, sigma: float | None = None, min_rows: int = MIN_SESSION_ROWS
) -> list[int]:
    """Return the sorted indices where a new level of ``values`` starts (module docstring)."""
    v = np.asarray(values, dtype=float)
    n = v.size
    if n < 2 * min_rows:
        return []
    s = difference_sigma(v) if sigma is None else sigma
    if s <= 0:
        s = float(np.finfo(float).eps * max(1.0, float(np.max(np.abs(v)))))
    v = _clipped(v, s, min_rows)
    penalty = PENALTY_PER_LN_N * np.log(n)
    found: list[int] = []
    todo = [(0, n)]
    while todo:
        a, b = todo.pop()
        k, gain = _best_split(v[a:b], min_rows)
        if k is not None and gain / s**2 > penalty:
            found.append(a + k)
            todo += [(a, a + k), (a + k, b)]
    return sorted(found)


def _clipped(v: np.ndarray, sigma: float, min_rows: int) -> np.ndarray:
    """Return ``v`` clipped to its running median ± CLIP_SIGMA·σ (module docstring)."""
    w = 2 * min_rows + 1
    padded = np.pad(v, min_rows, mode="edge")
    median = np.median(np.lib.stride_tricks.sliding_window_view(padded, w), axis=1)
    return np.clip(v, median - CLIP_SIGMA * sigma, median + CLIP_SIGMA * sigma)


def _best_split(v: np.ndarray, min_rows: int) -> tuple[int | None, float]:
    """Return the split of ``v`` that removes the most squared deviation, and how much."""
    n = v.size
    if n < 2 * min_rows:
        return None, 0.0
    k = np.arange(min_rows, n - min_rows + 1)
    c = np.cumsum(v)
    m1 = c[k - 1] / k
    m2 = (c[-1] - c[k - 1]) / (n - k)
    gain = k * (n - k) / n * (m1 - m2) ** 2
    best = int(np.argmax(gain))
    return int(k[best]), float(gain[best])
