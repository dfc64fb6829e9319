"""Offset jumps of the cable length between sessions: change points of a row sequence.

A sensor re-mounted between sessions reads every later length with another offset. Ordered
by row, the lengths less the model without offsets are then piecewise constant plus noise.
Binary segmentation finds the jumps: a segment [a, b) splits at k where the drop of its sum
of squares about the mean,

    G(k) = n₁n₂/(n₁ + n₂)·(m₁ − m₂)²/σ²,

is largest, if G exceeds the penalty β = :data:`PENALTY_PER_LN_N`·ln N (a BIC-like penalty
in units of the noise σ, stricter than BIC's 2·ln N so that the quantisation noise's
tails do not cut a session), and each part has at least :data:`MIN_SESSION_ROWS` rows; the
parts are split again until no split pays. Binary segmentation can cut between two jumps
first and leave short stubs beside the true ones; so each change point is then moved to
its best place between its neighbours, or removed when that split no longer pays, until
none moves (each move lowers the total cost, so this ends). σ is the scatter of successive
differences (robust, median absolute deviation), which a jump does not inflate.

Last, :func:`place` puts each boundary where it costs least between its neighbours' levels
(their medians), each row costing its squared deviation capped at (CLIP_SIGMA·σ)²: a lone
outlier at a boundary then cannot pull it, whatever side it is on.

Outliers (a snagged or mistyped row) must not cut a session: before the search every value
is clipped to within :data:`CLIP_SIGMA` σ of the band between the medians of the
:data:`MIN_SESSION_ROWS` rows before it and the as many after it. At a jump the band spans
both levels, so a step is left as it is; a lone row far from both sides is pulled in.
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
    return _refine(v, sorted(found), penalty * s**2, min_rows)


def _refine(v: np.ndarray, points: list[int], penalty: float, min_rows: int) -> list[int]:
    """Move each change point to its best place between its neighbours, or drop it."""
    for _ in range(100 * (len(points) + 1)):
        bounds = [0, *points, v.size]
        for i in range(1, len(bounds) - 1):
            k, gain = _best_split(v[bounds[i - 1] : bounds[i + 1]], min_rows)
            if k is None or gain <= penalty:
                del points[i - 1]
                break
            if bounds[i - 1] + k != bounds[i]:
                points[i - 1] = bounds[i - 1] + k
                break
        else:
            return points
    return points


def _clipped(v: np.ndarray, sigma: float, min_rows: int) -> np.ndarray:
    """Return ``v`` clipped to the band of its neighbours' medians ± CLIP_SIGMA·σ (docstring)."""
    padded = np.pad(v, min_rows, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, min_rows)
    before = np.median(windows[: v.size], axis=1)
    after = np.median(windows[min_rows + 1 :], axis=1)
    lo, hi = np.minimum(before, after), np.maximum(before, after)
    return np.clip(v, lo - CLIP_SIGMA * sigma, hi + CLIP_SIGMA * sigma)


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


def place(values: np.ndarray, starts: tuple[int, ...], sigma: float) -> tuple[int, ...]:
    """Return ``starts`` with each boundary moved to its least robust cost (module docstring)."""
    v = np.asarray(values, dtype=float)
    out = list(starts)
    cap = (CLIP_SIGMA * sigma) ** 2
    for i in range(1, len(out)):
        a, b = out[i - 1], out[i + 1] if i + 1 < len(out) else v.size
        m1, m2 = np.median(v[a : out[i]]), np.median(v[out[i] : b])
        seg = v[a:b]
        left = np.concatenate([[0.0], np.cumsum(np.minimum((seg - m1) ** 2, cap))])
        right = np.concatenate([np.cumsum(np.minimum((seg - m2) ** 2, cap)[::-1])[::-1], [0.0]])
        k = np.arange(1, seg.size)  # at least one row on each side
        out[i] = a + int(k[np.argmin(left[k] + right[k])])
    return tuple(out)
