"""Offset jumps of the cable length between sessions: change points of a row sequence.

A sensor re-mounted between sessions reads every later length with another offset. Ordered
by row, the lengths less the model without offsets are then piecewise constant plus noise.
Binary segmentation finds the jumps: a segment [a, b) splits at k where the drop of its sum
of squares about the mean,

    G(k) = n₁n₂/(n₁ + n₂)·(m₁ − m₂)²/σ²,

is largest, if G exceeds the penalty β = :data:`PENALTY_PER_LN_N`·ln N (a BIC-like penalty
in units of the noise σ, three times BIC's 2·ln N: at 4·ln N chance runs of a dozen rows in
a few dozen cut sessions from pure noise; at 6·ln N a jump of 1.5σ between sessions of 20
rows in 1000 is still found), and each part has at least :data:`MIN_SESSION_ROWS` rows; the
parts are split again until no split pays. Binary segmentation can cut between two jumps
first and leave short stubs beside the true ones; so the change point whose split pays
least is then removed while it pays less than the penalty by a capped cost (each row's
squared deviation from its segment's median, capped at (CLIP_SIGMA·σ)²: an outlier beside
a jump cannot hold a stub), and each moved to its best place between its neighbours,
until none is removed or moved.

σ is the scatter of successive differences, which a jump does not inflate: the larger of
their median absolute deviation's σ and their RMS less the largest :data:`TRIM` share
(corrected for the trimmed normal tail) — the first alone, on a few dozen rows, comes out
low often enough to cut sessions from noise. Lone outliers inflate it (each makes two large
differences), so σ is estimated again on the values with them clipped (below) and that
estimate taken when it is well below the first (:func:`noise_sigma`).

Last, :func:`place` puts each boundary where it costs least between its neighbours' levels
(their medians), each row costing its squared deviation capped at (CLIP_SIGMA·σ)²: a lone
outlier at a boundary then cannot pull it, whatever side it is on.

Outliers (a snagged or mistyped row) must not cut a session: before the search every row
farther than :data:`CLIP_SIGMA` σ from the band between the medians of the
:data:`MIN_SESSION_ROWS` rows before it and the as many after it is moved onto the band's
nearer edge. At a jump the band spans both levels, so a step is left as it is; a lone row
far from both sides is pulled in.
"""

from __future__ import annotations

import warnings

import numpy as np

PENALTY_PER_LN_N = 6.0
MIN_SESSION_ROWS = 5
CLIP_SIGMA = 3.0
TRIM = 0.1
TRIMMED_NORMAL_RMS = 0.789
"""RMS of a unit normal's values within its central 90 %: √(1 − 2·1.645·φ(1.645)/0.9)."""
MAD_TO_SIGMA = 1.4826
"""σ of normal noise per median absolute deviation."""
INFLATED = 1.5
"""σ is taken as inflated by lone outliers when it is this many times its estimate with them
clipped (:func:`noise_sigma`). Clipping pure noise lowers it by 10–15 % (its own tails):
taking that lower σ cut twice as many sessions from noise."""


def robust_sigma(values: np.ndarray) -> float:
    """Return σ from the median absolute deviation (normal noise), robust to outliers."""
    v = np.asarray(values, dtype=float)
    return float(MAD_TO_SIGMA * np.median(np.abs(v - np.median(v)))) if v.size else 0.0


def difference_sigma(values: np.ndarray) -> float:
    """Return the noise σ of a piecewise-constant sequence from its successive differences."""
    d = np.abs(np.diff(np.asarray(values, dtype=float)))
    if d.size == 0:
        return 0.0
    kept = np.sort(d)[: max(1, int(np.ceil((1 - TRIM) * d.size)))]
    trimmed = float(np.sqrt(np.mean(kept**2))) / TRIMMED_NORMAL_RMS
    return max(robust_sigma(d * np.sign(np.diff(values))), trimmed) / np.sqrt(2)


def noise_sigma(values: np.ndarray, min_rows: int = MIN_SESSION_ROWS) -> float:
    """Return the noise σ of a piecewise-constant sequence with lone outliers (docstring).

    :func:`difference_sigma`, and again on the values with their lone outliers clipped at
    that σ (:func:`_clipped`); the second when the first exceeds it :data:`INFLATED` times
    over. Two snags in 24 rows make four of 23 differences large, the trimmed RMS keeps two,
    and σ came out eleven times the noise's, hiding an 8σ jump.
    """
    v = np.asarray(values, dtype=float)
    s = difference_sigma(v)
    again = difference_sigma(_clipped(v, s, min_rows)) if s > 0 else s
    return again if INFLATED * again < s else s


def change_points(
    values: np.ndarray, sigma: float | None = None, min_rows: int = MIN_SESSION_ROWS
) -> list[int]:
    """Return the sorted indices where a new level of ``values`` starts (module docstring)."""
    v = np.asarray(values, dtype=float)
    n = v.size
    if n < 2 * min_rows:
        return []
    s = noise_sigma(v, min_rows) if sigma is None else sigma
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
    return _refine(v, sorted(found), s, min_rows)


def _refine(v: np.ndarray, points: list[int], sigma: float, min_rows: int) -> list[int]:
    """Return the change points once none is dropped or moved (module docstring).

    The point whose split pays least is dropped while it pays less than the penalty by the
    capped cost (:func:`_capped`); then each moves to its best place between its neighbours.
    That point's penalty takes the larger of ``sigma`` and the scatter within the sessions
    without it (:func:`_within_sigma`, σ where it is no change point), raised by at most two
    standard errors of ``sigma`` (1 + 2/√(2(N − 1))): the difference σ of a few dozen rows
    comes out 20 % low now and then, and a cut from pure noise then paid (52 rows, two
    snags, 1 in 300 draws); of a thousand rows it is within 5 %, so sessions' jumps that
    remain unfound cannot raise it further and hide the others.
    """
    cap = (CLIP_SIGMA * sigma) ** 2
    for _ in range(100 * (len(points) + 1)):
        bounds = [0, *points, v.size]
        best: list[int] = []
        gains: list[float] = []
        for a, b in zip(bounds[:-2], bounds[2:], strict=True):
            k, _ = _best_split(v[a:b], min_rows)
            best.append(bounds[len(best) + 1] if k is None else a + k)
            gains.append(
                -np.inf
                if k is None
                else _capped(v[a:b], cap) - _capped(v[a : a + k], cap) - _capped(v[a + k : b], cap)
            )
        if gains:
            weakest = int(np.argmin(gains))
            within = _within_sigma(v, points[:weakest] + points[weakest + 1 :])
            s = min(max(sigma, within), sigma * (1 + 2 / np.sqrt(2 * (v.size - 1))))
            if gains[weakest] <= PENALTY_PER_LN_N * np.log(v.size) * s**2:
                del points[weakest]
                continue
        if best != points:
            points = sorted(set(best))
        else:
            return points
    return points


def _within_sigma(v: np.ndarray, points: list[int]) -> float:
    """Return the pooled σ of ``v`` about each session's mean, the sessions cut at ``points``."""
    parts = np.split(v, points)
    dof = v.size - len(parts)
    return float(np.sqrt(sum(float(np.sum((p - p.mean()) ** 2)) for p in parts) / dof))


def _capped(v: np.ndarray, cap: float) -> float:
    """Return Σ min((v − median)², cap): a segment's cost that one outlier moves by ≤ cap."""
    return float(np.sum(np.minimum((v - np.median(v)) ** 2, cap))) if v.size else 0.0


def _window_medians(w: np.ndarray) -> np.ndarray:
    """Return each row's median of ``w`` (N, m), NaN ignored (all NaN: NaN).

    Only the windows at the ends hold NaN (the padding): the others take ``np.median``,
    six times faster than ``np.nanmedian`` over every row (100,000 rows: 7 against 42 ms).
    """
    med = np.median(w, axis=1)
    edge = np.isnan(med)
    med[edge] = np.nanmedian(w[edge], axis=1)
    return med


def _clipped(v: np.ndarray, sigma: float, min_rows: int) -> np.ndarray:
    """Return ``v`` with rows far from their neighbours' band moved onto it (docstring).

    Near the first and last rows one side has fewer than a majority of ``min_rows`` values
    (its median would follow one outlier): the other side's median serves for both.
    """
    padded = np.pad(v, min_rows, constant_values=np.nan)
    windows = np.lib.stride_tricks.sliding_window_view(padded, min_rows)
    enough = min_rows // 2 + 1
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an empty side: all NaN
        sides = []
        for w in (windows[: v.size], windows[min_rows + 1 :]):
            med = _window_medians(w)
            sides.append(np.where(np.sum(~np.isnan(w), axis=1) >= enough, med, np.nan))
    before, after = sides
    before = np.where(np.isnan(before), after, before)
    after = np.where(np.isnan(after), before, after)
    lo, hi = np.minimum(before, after), np.maximum(before, after)
    far = (v < lo - CLIP_SIGMA * sigma) | (v > hi + CLIP_SIGMA * sigma)
    return np.where(far, np.clip(v, lo, hi), v)


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
