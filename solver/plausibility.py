"""The plausibility gate: whether an identification can be trusted enough to act on.

A log that passes every format check can still be nonsense for the model: an encoder that
never counted (wrong channel or belt mode), a robot file in metres, points that cannot
identify the parameters. Least squares returns numbers for all of them. The gate stands
between identification and every output a user acts on (patch, SPEC table, report, demo,
controller comparison) and refuses, with what to check, when:

* **lengths** — the measured wire lengths span less than half or more than twice what the
  robot file's geometry gives at the measured points (every count equal: the encoder did
  not count; twice as much: lengths in the robot file in another unit, or mm_per_count);
* **residual** — the joint fit's residual σ exceeds what the noise model allows: with
  reading noise σ_r (``noise_mm``) and quantisation q = |mm_per_count| (uniform, q²/12),
  σ_model² = σ_r² + q²/12, and the residual sum of squares of ν = N − m degrees of freedom
  is refused beyond σ_model²·χ²_ν(1 − α), α = :data:`FALSE_ALARM` (the chance that a sound
  log of that noise is refused);
* **identifiability** — the distance Jacobian at the *measured* configurations is rank
  deficient (the unobservable parameters and combinations are named), or the noise model
  leaves a parameter's σ at :data:`POORLY_IDENTIFIED` deg or mm or more (the typical size
  of the errors being calibrated, paper §2.2: the data cannot tell its sign);
* **drift** — the zero readings drift faster than
  :data:`~wirecal.solver.scale.DRIFT_TOLERANCE_MM_PER_H` even less three of the fit's σ
  (|b| − 3σ_b > tolerance: a sound log is not refused for its noise) — a wire creeping,
  the stand moving, a temperature far from steady: lengths read at different times no
  longer compare;
* **bound** — an estimate lies on or beyond its bound Ω (the stepwise estimate pinned at
  Ω, the joint estimate beyond it) or beyond :data:`PLAUSIBLE_DEG` / :data:`PLAUSIBLE_MM`
  (a manufactured arm is not that far from its data sheet: the robot file, the mastering or
  the log is wrong).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import gammainccinv

from wirecal.solver import params as P
from wirecal.solver.distance import wire_lengths
from wirecal.solver.errors import Implausible
from wirecal.solver.identifiability import Identifiability, analyse_jacobian, covariance
from wirecal.solver.identify import DEFAULT_OMEGA
from wirecal.solver.robot import LIVE_CHECK
from wirecal.solver.scale import DRIFT_TOLERANCE_MM_PER_H
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.solve import SolveResult, omega_vector

FALSE_ALARM = 1e-6
"""α of the residual test: a log whose noise matches the model is refused once in 10⁶."""


def chi2_quantile(alpha: float, dof: int) -> float:
    """Return χ²_ν(1 − α), the upper-α quantile of the χ² law with ν = ``dof``.

    χ²_ν(1 − α) = 2·Q⁻¹(ν/2, α), Q the regularised upper incomplete gamma function: the
    same number as ``scipy.stats.chi2.isf``, without importing ``scipy.stats`` (which
    doubled the start-up of ``wirecal solve``).
    """
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

LENGTH_SPAN_RATIO = 2.0
"""The measured lengths' span may differ from the model's by this factor either way."""

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


CHECK_HINT = (
    "check the encoder (channel, interface, belt_mode in the robot file; the counter must "
    "move when the wire is pulled), the robot file's units (mm and deg), and that the plan "
    "identifies its parameters (wirecal observe)"
)


HEADLINE = {
    "lengths": "implausible wire lengths",
    "residual": "residual far above the noise model",
    "identifiability": "the points do not identify every parameter",
    "bound": "estimates on their bound or beyond a plausible size",
    "drift": "the zero readings drift beyond the tolerance",
}


@dataclass(frozen=True)
class Finding:
    """One failed plausibility check."""

    check: str  # "lengths", "residual", "identifiability", "bound" or "drift"
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


def assess(
    result: SolveResult,
    method: str,
    *,
    noise_mm: float = READING_NOISE_MM,
    omega_default: float = DEFAULT_OMEGA,
) -> Plausibility:
    """Run every check of the gate on ``result``'s estimate by ``method``."""
    robot, m = result.robot, result.measurements
    est = result.estimates[method]
    names = est.names
    present = m.present
    q_deg = m.joints_deg[present]
    base = robot.nominal
    J = sensitivity(base, q_deg, m.theta0_deg, names).psi  # boundary units
    ident = analyse_jacobian(J, names)
    findings: list[Finding] = []

    measured = m.distance_mm[present]
    model = wire_lengths(base, np.radians(q_deg), np.radians(m.theta0_deg))
    findings += _lengths(measured, model, m.source, LIVE_CHECK[robot.controller.language])

    sigma_model = float(np.hypot(noise_mm, abs(m.mm_per_count) / np.sqrt(12)))
    dof = len(measured) - len(names)
    limit = residual_limit_mm(sigma_model, dof)
    if dof > 0 and not result.sigma_mm <= limit:
        findings.append(
            Finding(
                "residual",
                f"the residual is far above the noise: σ {result.sigma_mm:.4g} mm from the "
                f"joint fit; reading noise {noise_mm:g} mm and quantisation "
                f"{abs(m.mm_per_count):g} mm allow at most {limit:.4f} mm (χ² bound, "
                f"{dof} degrees of freedom, false alarm {FALSE_ALARM:g}): the lengths do "
                "not fit this robot model (a noisier set-up: state its noise with --noise-mm; "
                "gross outliers: --robust)",
            )
        )

    _, identified = covariance(J, 1.0)
    unidentified = tuple(n for n, ok in zip(names, identified, strict=True) if not ok)
    findings += _identifiability(ident, J, sigma_model)
    findings += _bounds(result, method, omega_default)
    findings += _drift(result)
    return Plausibility(
        method=method,
        findings=tuple(findings),
        noise_model_mm=sigma_model,
        residual_limit_mm=float(limit),
        residual_sigma_mm=result.sigma_mm,
        identifiability=ident,
        unidentified=unidentified,
    )


def _lengths(measured: np.ndarray, model: np.ndarray, source: str, check: str) -> list[Finding]:
    """Return the span of the measured lengths against the robot model's at the same points."""
    span_measured = float(np.ptp(measured)) if measured.size else 0.0
    span_model = float(np.ptp(model)) if model.size else 0.0
    if span_model <= 0:
        return []  # every point at one distance: the identifiability check speaks
    ratio = span_measured / span_model
    if ratio < 1 / LENGTH_SPAN_RATIO:
        why = (
            "every count is the same: the encoder did not count"
            if span_measured == 0
            else "the encoder counted far less than the wire moved"
        )
        return [
            Finding(
                "lengths",
                f"implausible wire lengths: {source}'s span {span_measured:.3f} mm where the "
                f"robot file's geometry gives {span_model:.1f} mm at the same points; {why} "
                "(wrong channel, interface, belt_mode or pulse_inputs, or the wire is not "
                f"attached); check it with {check} before measuring again",
            )
        ]
    if ratio > LENGTH_SPAN_RATIO:
        return [
            Finding(
                "lengths",
                f"implausible wire lengths: {source}'s span {span_measured:.1f} mm where the "
                f"robot file's geometry gives {span_model:.3g} mm at the same points "
                f"({ratio:.3g} times as much): are the robot file's lengths in mm (not m)? "
                "is encoder.mm_per_count right?",
            )
        ]
    return []


def _identifiability(ident: Identifiability, J: np.ndarray, sigma_model: float) -> list[Finding]:
    """Rank deficiency (named) and parameters the noise model leaves unidentified."""
    findings = []
    if ident.rank < len(ident.names):
        detail = " ".join(ident.describe()[1:-1])
        findings.append(
            Finding(
                "identifiability",
                f"the measured points do not identify the parameters: the distance Jacobian "
                f"has rank {ident.rank} of {len(ident.names)}. {detail} Use a plan whose "
                "points identify every parameter (wirecal observe ROBOT PLAN; wirecal plan)",
            )
        )
        return findings
    cov, _ = covariance(J, sigma_model**2)
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    weak = [f"{n} ±{s:.3g}" for n, s in zip(ident.names, sd, strict=True) if s >= POORLY_IDENTIFIED]
    if weak:
        findings.append(
            Finding(
                "identifiability",
                "the measured points barely identify "
                + ", ".join(weak)
                + f" (1σ from reading noise alone; {POORLY_IDENTIFIED:g} deg or mm is the "
                "size of the errors calibrated): the Jacobian is badly conditioned "
                f"(O2 = {ident.indices['O2']:.2g}); use a plan whose points move these "
                "parameters (wirecal observe, wirecal plan)",
            )
        )
    return findings


def implausible(names: Sequence[str], values: np.ndarray) -> list[str]:
    """Return ``"name value"`` of each estimate beyond :data:`PLAUSIBLE_DEG` / :data:`PLAUSIBLE_MM`.

    Angles (θ, α) in deg, lengths in mm, boundary units.
    """
    plausible = {"deg": PLAUSIBLE_DEG, "mm": PLAUSIBLE_MM}
    return [
        f"{n} {v:+.4g}"
        for n, v in zip(names, values, strict=True)
        if abs(v) > plausible[P.unit_of(n)]
    ]


def _bounds(result: SolveResult, method: str, omega_default: float) -> list[Finding]:
    """Estimates on or beyond their Ω, or beyond a physically plausible size."""
    est = result.estimates[method]
    names = est.names
    robot = result.robot
    omega = omega_vector(names, robot.n_joints, result.plan, omega_default)
    omega = robot.errors(names).to_boundary(omega)
    on_bound = [
        f"{n} {v:+.4g}"
        for n, v, w in zip(names, est.values, omega, strict=True)
        if abs(v) >= w * (1 - 1e-9)
    ]
    findings = []
    if on_bound:
        findings.append(
            Finding(
                "bound",
                f"estimates on or beyond their bound Ω ({method}): "
                + ", ".join(on_bound)
                + " deg/mm; a real offset is well inside Ω: the data does not fit the robot "
                "file",
            )
        )
    huge = implausible(names, est.values)
    if huge:
        findings.append(
            Finding(
                "bound",
                "estimates beyond a physically plausible size "
                f"({PLAUSIBLE_DEG:g} deg, {PLAUSIBLE_MM:g} mm; {method}): "
                + ", ".join(huge)
                + ": the robot file, the mastering or the log is wrong",
            )
        )
    return findings


def _drift(result: SolveResult) -> list[Finding]:
    """Return a drift of the zero readings beyond :data:`DRIFT_TOLERANCE_MM_PER_H` by 3σ."""
    dr = result.drift
    if dr is None or abs(dr.rate_mm_per_h) - 3 * dr.std_mm_per_h <= DRIFT_TOLERANCE_MM_PER_H:
        return []
    return [
        Finding(
            "drift",
            f"the zero readings at θ0 drift by {dr.rate_mm_per_h:+.3f} mm/h (± "
            f"{dr.std_mm_per_h:.3f}, {dr.zeros} readings), beyond the tolerance "
            f"{DRIFT_TOLERANCE_MM_PER_H:g} mm/h by more than 3σ: fix the encoder's stand and "
            "the wire's attachment, let the cell reach a steady temperature, and measure again",
        )
    ]


def gate(
    result: SolveResult,
    method: str,
    *,
    accept: bool = False,
    noise_mm: float = READING_NOISE_MM,
    omega_default: float = DEFAULT_OMEGA,
) -> Plausibility:
    """Assess an identification and refuse it unless it passed or is accepted.

    :func:`assess`, raising :class:`Implausible` (exit status 3) unless it passed or
    ``accept`` (the user's explicit override, which the patch then records).
    """
    verdict = assess(result, method, noise_mm=noise_mm, omega_default=omega_default)
    if verdict.passed or accept:
        return verdict
    raise Implausible(
        [
            *(f"{result.measurements.source}: {f.message}" for f in verdict.findings),
            f"nothing was written: this identification is not plausible; {CHECK_HINT}. "
            "To see the estimates anyway pass --accept-implausible (a patch written with it "
            "records the override)",
        ]
    )
