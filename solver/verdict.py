"""The plausibility gate's verdict and the rules every gate shares (``solve``'s and ``fit``'s).

The verdict (:class:`Plausibility`, its :class:`Finding` list), the residual bound
σ_model·√(χ²_ν(1 − α)/ν) (:func:`residual_limit_mm`), the sizes beyond which an estimate
is implausible (:func:`implausible`) or a parameter unidentified (:data:`POORLY_IDENTIFIED`),
and how a patch says the gate was overridden (:func:`override_warning`). The checks of an
identification are :mod:`~wirecal.solver.plausibility`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.identifiability import Identifiability

FALSE_ALARM = 1e-6
"""α of the residual test: a log whose noise matches the model is refused once in 10⁶."""


def chi2_quantile(alpha: float, dof: int) -> float:
    """Return χ²_ν(1 − α), the upper-α quantile of the χ² law with ν = ``dof``.

    χ²_ν(1 − α) = 2·Q⁻¹(ν/2, α), Q the regularised upper incomplete gamma function: the
    same number as ``scipy.stats.chi2.isf``, without importing ``scipy.stats`` (which
    doubled the start-up of ``wirecal solve``).
    """
    # imported here: scipy.special costs 0.17 s of CPU at import, and ``wirecal plan``
    # needs only this module's reading noise
    from scipy.special import gammainccinv

    return 2.0 * float(gammainccinv(dof / 2.0, alpha))


def residual_limit_mm(sigma_model_mm: float, dof: int) -> float:
    """Return the largest residual σ the gate accepts (NaN when ``dof`` ≤ 0: none to judge).

    σ_model·√(χ²_ν(1 − α)/ν), α the :data:`FALSE_ALARM`, ν = ``dof``.
    """
    if dof <= 0:
        return float("nan")
    return sigma_model_mm * float(np.sqrt(chi2_quantile(FALSE_ALARM, dof) / dof))


READING_NOISE_MM = 0.02
"""Default σ of one reading before quantisation: the paper's arm repeats to ±0.02 mm."""


POORLY_IDENTIFIED = 1.0
"""σ (deg or mm) from the noise model at or beyond which a parameter counts as unidentified."""


PLAUSIBLE_DEG = 10.0
PLAUSIBLE_MM = 10.0
"""Largest believable offset of an angle (deg) or a length (mm) from the data sheet."""

PLAUSIBLE_URAD_PER_NM = 100.0
"""Largest believable compliance offset (µrad/(N·m)): wirecal's bound, ten times the
largest of issue 30's 2–8 µrad/(N·m); light arms' drives may reach tens."""


OVERRIDDEN = "overridden: "
"""How a patch's ``plausibility`` field starts when the user overrode the gate."""


def override_warning(plausibility: str) -> str | None:
    """Return the warning every artefact made from an overridden patch carries.

    From the patch's ``plausibility`` field; None when the gate passed (or the patch
    predates it).
    """
    if not plausibility.startswith(OVERRIDDEN):
        return None
    return (
        "wirecal's plausibility gate refused this result and the refusal was overridden "
        f"(--accept-implausible): {plausibility[len(OVERRIDDEN) :]}"
    )


HEADLINE = {
    "lengths": "implausible wire lengths",
    "residual": "residual far above the noise model",
    "identifiability": "the points do not identify every parameter",
    "bound": "estimates on their bound or beyond a plausible size",
    "drift": "the zero readings drift beyond the tolerance",
    "holdout": "held-out rows far above the quantisation floor",
    "budget": "the error budget is not below the correction",
}


@dataclass(frozen=True)
class Finding:
    """One failed plausibility check."""

    check: str  # a key of HEADLINE
    message: str


@dataclass(frozen=True)
class Plausibility:
    """The gate's verdict on one method's estimate; ``findings`` empty means it passed."""

    method: str
    findings: tuple[Finding, ...]
    noise_model_mm: float  # σ_model of one reading
    residual_limit_mm: float  # largest residual σ the χ² bound allows (NaN: no dof)
    residual_sigma_mm: float
    identifiability: Identifiability
    unidentified: tuple[str, ...]  # parameters whose σ the data leaves unbounded

    @property
    def passed(self) -> bool:
        """Return whether no check failed."""
        return not self.findings

    def summary(self) -> str:
        """One line for a patch: 'passed (…)', or 'failed: ' and the checks that failed."""
        if self.passed:
            return (
                f"passed (residual σ {self.residual_sigma_mm:.4f} mm ≤ "
                f"{self.residual_limit_mm:.4f} mm, rank {self.identifiability.rank} of "
                f"{len(self.identifiability.names)}, no estimate on its bound)"
            )
        return "failed: " + "; ".join(dict.fromkeys(HEADLINE[f.check] for f in self.findings))

    def patch_field(self) -> str:
        """Return the patch's ``plausibility`` value: the verdict, or that it was overridden."""
        return self.summary() if self.passed else OVERRIDDEN + self.summary()

    def as_json(self) -> dict:
        """Return the verdict as a JSON-ready dict."""
        return {
            "passed": self.passed,
            "findings": [{"check": f.check, "message": f.message} for f in self.findings],
            "noise_model_mm": self.noise_model_mm,
            "residual_sigma_mm": _num(self.residual_sigma_mm),
            "residual_limit_mm": _num(self.residual_limit_mm),
            "rank": self.identifiability.rank,
            "unidentified": list(self.unidentified),
        }


def _num(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def implausible(names: Sequence[str], values: np.ndarray) -> list[str]:
    """Return ``"name value"`` of each estimate beyond :data:`PLAUSIBLE_DEG` / :data:`PLAUSIBLE_MM`.

    Angles (θ, α) in deg, lengths in mm, compliances in µrad/(N·m)
    (:data:`PLAUSIBLE_URAD_PER_NM`), boundary units.
    """
    plausible = {"deg": PLAUSIBLE_DEG, "mm": PLAUSIBLE_MM, "urad/Nm": PLAUSIBLE_URAD_PER_NM}
    return [
        f"{n} {v:+.4g}"
        for n, v in zip(names, values, strict=True)
        if abs(v) > plausible[P.unit_of(n)]
    ]
