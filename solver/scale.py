"""The draw-wire encoder's scale and drift, from the log's reference and zero readings.

**Scale.** The counts become millimetres through ``mm_per_count``, known only to the
datasheet's ``scale_tolerance_ppm``. Wire lengths alone cannot tell the scale: scaling every
length of the robot and ``mm_per_count`` together leaves every reading unchanged (the null
direction of the wire-length Jacobian with the scale as a column, whose column is the
measured lengths themselves, ∂d̃/∂s = −d̃). A reference gauge fixes it: the operator seats
the wire tip in nest A, then nest B, ``reference_repeats`` times; each pair's difference
ℓ̃_i (mm at the nominal scale) reads the certified length L. With true mm per count
= nominal × k, ℓ̃_i = L/k + noise, so

    k̂ = L / mean(ℓ̃),   σ_k² = (σ_ℓ²/n + u_L²) / L²

with σ_ℓ the scatter of the pairs (the reading noise model when there is one pair) and
u_L the gauge's certified uncertainty. Every wire length is then k̂·d̃.

**Drift.** The zero readings at θ0 (one per step and the closing one) all read the same
wire length; a linear fit of them against the controller's time ``t_s`` measures a drift of
the readings (the encoder's stand, the wire creeping, temperature). A drift beyond its 3σ is
removed from every length (the length at time t less the fitted drift since the zeros'
mean time); a smaller one is reported and left (removing it would add only its fit's noise).
Its σ is judged with the points' noise once it is removed (left in, the drift inflates
that noise 1.2–2.1 times at the paper's speed and 1 mm/h, and hides itself). A slip is a
step change of the zeros, not a slope: :func:`find_slips` tells them apart.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wirecal.solver.identifiability import covariance
from wirecal.solver.verdict import chi2_quantile

PPM = 1e-6

ARM_PPM_PER_K = 12.0
"""The arm's linear expansion (ppm/K) the simulation and the budget assume: steel's, and
between steel and the aluminium of cast arms; the true arm's is unknown to wirecal."""

DRIFT_SIGNIFICANCE = 3.0
"""A fitted drift is removed from the lengths when beyond this many of its σ."""

DRIFT_TOLERANCE_MM_PER_H = 0.5
"""Largest drift of the zero readings accepted (mm/h): a draw-wire encoder's reading at one
pose does not move that much in an hour unless the wire slipped, the stand moved or the
temperature is far from steady (0.5 mm/h is 20 K/h on a 1 m aluminium stand)."""

DRIFT_REMOVABLE_MM_PER_H = 5.0
"""Largest drift removed rather than refused (mm/h): ten times the tolerance is no longer
a stand settling or a cell warming but a wire creeping or a loose mount."""

LINEARITY_FALSE_ALARM = 1e-3
"""α of the test that the zero readings lie on the drift's line within their noise."""

MIN_DRIFT_ZEROS = 4
"""Zero readings needed for a drift fit (two parameters and a scatter)."""


@dataclass(frozen=True)
class ScaleEstimate:
    """The encoder's scale from the reference rows: true mm per count = nominal × factor."""

    factor: float  # k̂
    std: float  # σ of k̂ (dimensionless)
    pairs: int
    reference_length_mm: float
    measured_mm: np.ndarray  # each pair's B − A at the nominal scale

    @property
    def ppm(self) -> float:
        """Return (k̂ − 1) in ppm."""
        return (self.factor - 1) / PPM

    @property
    def std_ppm(self) -> float:
        """Return σ of k̂ in ppm."""
        return self.std / PPM


def estimate_scale(
    measured_mm: np.ndarray, length_mm: float, uncertainty_mm: float, sigma_reading_mm: float
) -> ScaleEstimate:
    """Return the scale from each pair's nest B − nest A length (module docstring).

    ``sigma_reading_mm`` is the noise of one reading (σ of a difference is √2 times it),
    used when there is a single pair; from two pairs on, their own scatter is used, but
    never less than the noise model allows.
    """
    ell = np.asarray(measured_mm, dtype=float)
    n = len(ell)
    model = math.sqrt(2) * sigma_reading_mm
    scatter = float(np.std(ell, ddof=1)) if n > 1 else model
    sigma_ell = max(scatter, model)
    factor = length_mm / float(ell.mean())
    std = math.sqrt(sigma_ell**2 / n + uncertainty_mm**2) / length_mm
    return ScaleEstimate(factor, std, n, length_mm, ell)


SEATING_TOLERANCE_MM = 0.05
"""How far (mm) a pair's B − A may read from the certified length beyond the scale's own
tolerance: 3.5σ of the difference of two readings of 0.01 mm noise each; a tip seated on
a burr or dirt, or not pushed home, reads further off."""

UNMOVED_FRACTION = 0.05
"""A pair whose |B − A| is below this fraction of the gauge's length: the tip stayed in
one nest (or the encoder did not count)."""


def reference_problems(
    measured_mm: np.ndarray, lines: list[tuple[int, int]], length_mm: float, tolerance_ppm: float
) -> list[str]:
    """Name what went wrong in the reference step, one ``line: problem`` per cause.

    ``measured_mm`` is each pair's B − A at the nominal scale, ``lines`` each pair's
    (nest A, nest B) line. A pair near 0 is an unmoved tip, one near −L swapped nests;
    the others must read L within the scale's tolerance plus
    :data:`SEATING_TOLERANCE_MM`: one pair off is a bad seating, every pair off by the
    same amount a wrong certified length (or mm_per_count).
    """
    ell = np.asarray(measured_mm, dtype=float)
    allowed = length_mm * tolerance_ppm * PPM + SEATING_TOLERANCE_MM
    out: list[str] = []
    off: list[int] = []
    for k, (x, (a, b)) in enumerate(zip(ell, lines, strict=True)):
        where = f"{a}-{b}: reference pair {k + 1} reads B − A = {x:+.3f} mm"
        if abs(x) < UNMOVED_FRACTION * length_mm:
            out.append(
                f"{where} of a {length_mm:g} mm gauge ([encoder] reference_length_mm): "
                "the tip did not move from nest A to nest B (or the encoder did not "
                "count); seat it in each nest in turn and repeat the reference step"
            )
        elif abs(x + length_mm) < UNMOVED_FRACTION * length_mm:
            out.append(
                f"{where}, minus the gauge's length: nests A and B were swapped; seat the "
                "tip in nest A (the one nearer the encoder) first"
            )
        elif abs(x - length_mm) > allowed:
            off.append(k)
    if off:
        out += _off_pairs(ell, lines, off, length_mm, allowed)
    return out


def _off_pairs(
    ell: np.ndarray, lines: list[tuple[int, int]], off: list[int], length_mm: float, allowed: float
) -> list[str]:
    """Name the pairs that read the gauge beyond ``allowed``: bad seatings or a wrong length."""
    spread = float(np.ptp(ell[off]))
    if len(off) == len(ell) and (len(off) > 1 and spread <= 2 * SEATING_TOLERANCE_MM):
        return [
            f"{lines[0][0]}: every reference pair reads {float(ell.mean()):.3f} mm against "
            f"[encoder] reference_length_mm = {length_mm:g} (± {allowed:.3f} mm): check "
            "the gauge's certified length and mm_per_count in the robot file"
        ]
    return [
        f"{lines[k][0]}-{lines[k][1]}: reference pair {k + 1} reads B − A = {ell[k]:.3f} mm, "
        f"{ell[k] - length_mm:+.3f} mm from the gauge's {length_mm:g} mm (allowed ± "
        f"{allowed:.3f}): a bad seating of the tip; clean the nests and repeat the "
        "reference step"
        for k in off
    ]


@dataclass(frozen=True)
class Drift:
    """A linear drift of the zero readings over the run's time."""

    rate_mm_per_s: float
    std_mm_per_s: float
    t_mean_s: float  # the zeros' mean time
    zeros: int
    removed: bool  # beyond DRIFT_SIGNIFICANCE σ: removed from the lengths
    linear: bool = True  # the zeros scatter about the line within their noise (χ² test)

    @property
    def rate_mm_per_h(self) -> float:
        """Return the drift in mm/h."""
        return self.rate_mm_per_s * 3600

    @property
    def std_mm_per_h(self) -> float:
        """Return σ of the drift in mm/h."""
        return self.std_mm_per_s * 3600

    def correction_mm(self, t_s: np.ndarray, t_ref_s: float) -> np.ndarray:
        """Return what to subtract from lengths read at ``t_s`` (zero when not removed).

        The lengths are measured from a zero reference taken at (mean) time ``t_ref_s``.
        """
        if not self.removed:
            return np.zeros_like(np.asarray(t_s, dtype=float))
        return self.rate_mm_per_s * (np.asarray(t_s, dtype=float) - t_ref_s)

    @property
    def correctable(self) -> bool:
        """Whether removing it corrects the lengths: linear, known to the tolerance, not huge.

        Known to the tolerance: twice its σ (95 %) within :data:`DRIFT_TOLERANCE_MM_PER_H`;
        what is left after removal is in the error budget (:mod:`wirecal.solver.budget`).
        Not huge: within :data:`DRIFT_REMOVABLE_MM_PER_H`.
        """
        known = 2 * self.std_mm_per_h <= DRIFT_TOLERANCE_MM_PER_H
        small = abs(self.rate_mm_per_h) <= DRIFT_REMOVABLE_MM_PER_H
        return self.removed and self.linear and known and small

    @property
    def warning(self) -> str | None:
        """Return what to say of a drift beyond the tolerance that was removed; else None."""
        beyond = abs(self.rate_mm_per_h) - DRIFT_SIGNIFICANCE * self.std_mm_per_h
        if not self.correctable or beyond <= DRIFT_TOLERANCE_MM_PER_H:
            return None
        return (
            f"the zero readings drift by {self.rate_mm_per_h:+.3f} ± {self.std_mm_per_h:.3f} "
            f"mm/h, beyond the tolerance {DRIFT_TOLERANCE_MM_PER_H:g} mm/h; the drift is "
            "linear and well measured, so it was removed from the lengths. Before the next "
            "run, fix the encoder's stand and the wire's attachment and let the cell reach a "
            "steady temperature"
        )

    def text(self) -> str:
        """Describe the drift in words for ``wirecal solve``."""
        verdict = (
            "removed from the lengths"
            if self.removed
            else f"within {DRIFT_SIGNIFICANCE:g}σ of none: left in"
        )
        return (
            f"zero drift {self.rate_mm_per_h * 1000:+.1f} ± {self.std_mm_per_h * 1000:.1f} "
            f"µm/h over {self.zeros} zero readings ({verdict})"
        )


def fit_drift(t_s: np.ndarray, zero_mm: np.ndarray, sigma_reading_mm: float) -> Drift | None:
    """Fit zero_mm = c + b·(t − t̄) by least squares; None with too few zero readings.

    σ_b from the fit's own scatter (n − 2 degrees of freedom), never below what the noise
    model ``sigma_reading_mm`` allows.
    """
    t = np.asarray(t_s, dtype=float)
    z = np.asarray(zero_mm, dtype=float)
    n = len(t)
    if n < MIN_DRIFT_ZEROS or np.ptp(t) <= 0:
        return None
    t_mean = float(t.mean())
    dt = t - t_mean
    sxx = float(dt @ dt)
    b = float(dt @ (z - z.mean())) / sxx
    r = z - z.mean() - b * dt
    scatter = math.sqrt(float(r @ r) / (n - 2))
    sigma = max(scatter, sigma_reading_mm)
    std = sigma / math.sqrt(sxx)
    chi2_limit = chi2_quantile(LINEARITY_FALSE_ALARM, n - 2)  # χ²_(n−2)(1 − α)
    linear = bool(scatter**2 * (n - 2) <= sigma_reading_mm**2 * chi2_limit)
    return Drift(b, std, t_mean, n, abs(b) > DRIFT_SIGNIFICANCE * std, linear)


def find_slips(
    t_s: np.ndarray, zero_mm: np.ndarray, tol_mm: float
) -> list[tuple[int, float]] | None:
    """Tell slips from a drift in the zero readings: a slip is a step, a drift a slope.

    Fits zero_mm = c + b·t + Σ J_k·[i ≥ k], adding the step k that best explains the
    readings as long as its jump |J_k| exceeds ``tol_mm``. Returns (index of the first
    zero after the slip, J_k) per slip; None without usable times (fewer than
    :data:`MIN_DRIFT_ZEROS` zeros, or times missing or not increasing).
    """
    t = np.asarray(t_s, dtype=float)
    z = np.asarray(zero_mm, dtype=float)
    n = len(t)
    if n < MIN_DRIFT_ZEROS or not np.all(np.diff(t) > 0):  # NaN compares False too
        return None
    columns = [np.ones(n), t - t[0]]
    slips: list[tuple[int, float]] = []
    while len(columns) + 1 < n:
        k, jump = _best_step(columns, z, {k for k, _ in slips})
        if abs(jump) <= tol_mm:
            break
        slips.append((k, jump))
        columns.append((np.arange(n) >= k).astype(float))
    return sorted(slips)


def _best_step(columns: list[np.ndarray], z: np.ndarray, taken: set[int]) -> tuple[int, float]:
    """Return the step (index, jump) that, added to ``columns``, leaves the least residual."""
    n = len(z)
    best = (math.inf, 0, 0.0)
    for k in set(range(1, n)) - taken:
        X = np.column_stack([*columns, np.arange(n) >= k])
        coef, *_ = np.linalg.lstsq(X, z, rcond=None)
        r = z - X @ coef
        best = min(best, (float(r @ r), k, float(coef[-1])))
    return best[1], best[2]


@dataclass(frozen=True)
class ScaleObservability:
    """How well the wire lengths alone tell the encoder's scale, for ``wirecal observe``."""

    std_ppm: float  # σ of the scale from the lengths alone (inf: not at all)
    fixed_lengths: tuple[str, ...]  # the non-zero lengths not among the parameters

    def describe(self, sigma_mm: float, tolerance_ppm: float) -> list[str]:
        """Name the scale–length combination in words."""
        lines = [
            "Encoder scale: scaling every length of the robot (a, d, the tool point) and "
            "mm_per_count together leaves every wire length unchanged (the null direction "
            "s·(all lengths, mm_per_count))."
        ]
        if not math.isfinite(self.std_ppm):
            lines.append(
                "  Every non-zero length is a parameter here: the scale is not observable "
                "at all; it goes into the lengths."
            )
        else:
            lines.append(
                f"  Only the lengths held at nominal ({', '.join(self.fixed_lengths)}) tell it,"
                f" and only as well as they are exact: ±{self.std_ppm:.0f} ppm if they were "
                f"(1σ at {sigma_mm:g} mm reading noise), against a tolerance of "
                f"±{tolerance_ppm:g} ppm; a scale error goes into the lengths."
            )
        lines.append(
            "  The reference step resolves it: give reference_length_mm in [encoder] "
            "(a gauge with two nests a certified distance apart)."
        )
        return lines


def scale_observability(
    psi: np.ndarray,
    lengths_mm: np.ndarray,
    names: tuple[str, ...],
    nominal_lengths: dict[str, float],
    sigma_mm: float,
) -> ScaleObservability:
    """Return σ of the scale from the lengths alone: Ψ (boundary units) with a column −d.

    ``nominal_lengths`` are the robot's non-zero lengths by parameter name (a*, d*, tool
    coordinates); those not in ``names`` break the null direction.
    """
    fixed = tuple(n for n in nominal_lengths if n not in names)
    J = np.column_stack([psi, -np.asarray(lengths_mm) * PPM])  # scale column per ppm
    cov, identified = covariance(J, sigma_mm**2)
    std = float(np.sqrt(cov[-1, -1])) if identified[-1] and fixed else math.inf
    return ScaleObservability(std, fixed)
