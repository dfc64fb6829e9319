"""The plausibility gate: whether an identification can be trusted enough to act on.

A log that passes every format check can still be nonsense for the model: an encoder that
never counted (wrong channel or belt mode), a robot file in metres, points that cannot
identify the parameters. Least squares returns numbers for all of them. The gate stands
between identification and every output a user acts on (patch, SPEC table, report, demo,
controller comparison) and refuses, with what to check, when:

* **lengths** — the measured wire lengths span less than half or more than twice what the
  robot file's geometry gives at the measured points (every count equal: the encoder did
  not count; |mm_per_count| times as much, within 10 %: the log's counts are millimetres;
  twice as much: lengths in the robot file in another unit, or mm_per_count);
* **residual** — the joint fit's residual σ exceeds what the noise model allows: with
  reading noise σ_r (``noise_mm``), quantisation q = |mm_per_count| (uniform, q²/12) and,
  when the robot file declares ``[calibration] repeatability_mm``, what the arm's landing
  adds to the lengths, σ_a (:func:`~wirecal.solver.zero_reading.length_sigma_mm`, the rule
  of the twin's arm and the zero readings), σ_model² = σ_r² + q²/12 + σ_a² (like the
  reading noise's, the zero reference's own error, common to every length, is not in it),
  and the residual sum of squares of ν = N − m degrees of freedom
  is refused beyond σ_model²·χ²_ν(1 − α), α = :data:`FALSE_ALARM` (the chance that a sound
  log of that noise is refused);
* **identifiability** — the distance Jacobian at the *measured* configurations is rank
  deficient (the unobservable parameters and combinations are named), or the reading
  noise's model (σ_r² + q²/12) leaves a parameter's σ at :data:`POORLY_IDENTIFIED` deg
  or mm or more (the typical size of the errors being calibrated, paper §2.2: the data
  cannot tell its sign). A fit with a prior (a plan from a pool,
  :mod:`~wirecal.solver.solve_pool`) is judged on its posterior: the readings' Jacobian
  with the prior's rows must have full rank (a direction neither holds: the attachment
  unseen); a direction the readings see weakly is the prior's, its share of the tool
  point's error in the budget, not a finding. Its residual's degrees of freedom are N
  less the parameters the readings carry;
* **drift** — the zero readings drift faster than
  :data:`~wirecal.solver.scale.DRIFT_TOLERANCE_MM_PER_H` even less three of the fit's σ
  (|b| − 3σ_b > tolerance: a sound log is not refused for its noise) — a wire creeping,
  the stand moving, a temperature far from steady: lengths read at different times no
  longer compare. Unless removing it corrects them (``Drift.correctable``: linear, known
  to the tolerance, at most :data:`~wirecal.solver.scale.DRIFT_REMOVABLE_MM_PER_H`): then
  it was removed from the lengths and ``wirecal solve`` warns instead;
* **bound** — an estimate lies on or beyond its bound Ω (the stepwise estimate pinned at
  Ω, the joint estimate beyond it) or beyond :data:`PLAUSIBLE_DEG` / :data:`PLAUSIBLE_MM`
  (a manufactured arm is not that far from its data sheet: the robot file, the mastering or
  the log is wrong).
"""

from __future__ import annotations

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.compliance import SIGMA_LIMIT_URAD_PER_NM
from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.errors import Implausible
from wirecal.solver.identifiability import Identifiability, analyse_jacobian, covariance
from wirecal.solver.identify import DEFAULT_OMEGA, at_points
from wirecal.solver.kinematics import Model, with_errors
from wirecal.solver.params import ErrorSet
from wirecal.solver.scale import DRIFT_REMOVABLE_MM_PER_H, DRIFT_TOLERANCE_MM_PER_H, PPM
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.solve import SolveResult, omega_vector
from wirecal.solver.verdict import (
    FALSE_ALARM,
    PLAUSIBLE_DEG,
    PLAUSIBLE_MM,
    POORLY_IDENTIFIED,
    READING_NOISE_MM,
    Finding,
    Plausibility,
    implausible,
    residual_limit_mm,
)
from wirecal.solver.zero_reading import length_sigma_mm

LENGTH_SPAN_RATIO = 2.0
"""The measured lengths' span may differ from the model's by this factor either way."""
COUNTS_IN_MM_TOLERANCE = 0.1
"""A span ratio within this fraction of |mm_per_count| means the log's counts are in mm: the
arm's errors and the encoder's scale change the span by a few per cent at most."""


LIVE_CHECK = "the live-count program 'wirecal gen' writes"
"""What the findings call the live-check program when the caller does not name it."""

CHECK_HINT = (
    "check the encoder (channel, interface, belt_mode in the robot file; the counter must "
    "move when the wire is pulled), the robot file's units (mm and deg), and that the plan "
    "identifies its parameters (wirecal observe)"
)


def assess(
    result: SolveResult,
    method: str,
    *,
    noise_mm: float = READING_NOISE_MM,
    omega_default: float = DEFAULT_OMEGA,
    live_check: str = LIVE_CHECK,
) -> Plausibility:
    """Run every check of the gate on ``result``'s estimate by ``method``.

    ``live_check``: the controller program that shows the live counts, which the findings
    name (the robot's language's, :attr:`wirecal.lang.base.Language.live_check`).
    """
    robot, m = result.robot, result.measurements
    est = result.estimates[method]
    names = est.names
    present = m.present
    q_deg = m.joints_deg[present]
    base = at_points(robot.nominal, result.plan, present)  # a payload step's mass on
    sigma_model = float(np.hypot(noise_mm, abs(m.mm_per_count) / np.sqrt(12)))
    J, ident = _jacobian(result, method, base, sigma_model)
    findings: list[Finding] = []

    measured = m.distance_mm[present]
    model = wire_lengths(base, np.radians(q_deg), np.radians(m.theta0_deg))
    findings += _lengths(measured, model, m.mm_per_count, m.source, live_check)

    landing = _landing_sigma_mm(result, base)
    sigma_length = float(np.hypot(sigma_model, landing))  # one reading of a length
    fitted = len(names) if result.prior is None else result.prior.effective
    dof = int(len(measured) - fitted)
    limit = residual_limit_mm(sigma_length, dof)
    if dof > 0 and not result.sigma_mm <= limit:
        arm = f", the arm's repeatability {landing:.3g} mm (σ)" if landing else ""
        findings.append(
            Finding(
                "residual",
                f"the residual is far above the noise: σ {result.sigma_mm:.4g} mm from the "
                f"joint fit; reading noise {noise_mm:g} mm and quantisation "
                f"{abs(m.mm_per_count):g} mm{arm} allow at most {limit:.4f} mm (χ² bound, "
                f"{dof} degrees of freedom, false alarm {FALSE_ALARM:g}): the lengths do "
                "not fit this robot model (a noisier set-up: state its noise with --noise-mm; "
                f"gross outliers: --robust{_scale_hint(result, limit)}",
            )
        )

    _, identified = covariance(J, 1.0)
    unidentified = tuple(n for n, ok in zip(names, identified, strict=True) if not ok)
    findings += _identifiability(ident, J, sigma_model, each=result.prior is None)
    findings += _bounds(result, method, omega_default)
    findings += _drift(result)
    return Plausibility(
        method=method,
        findings=tuple(findings),
        noise_model_mm=sigma_length,
        residual_limit_mm=float(limit),
        residual_sigma_mm=result.sigma_mm,
        identifiability=ident,
        unidentified=unidentified,
    )


def _jacobian(
    result: SolveResult, method: str, base: Model, sigma_model: float
) -> tuple[np.ndarray, Identifiability]:
    """Return the Jacobian the gate judges the estimate's parameters by, and its analysis.

    The distance Jacobian Ψ at the measured points (boundary units); for a fit with a prior
    (a plan from a pool) the readings' Jacobian of that fit over ``sigma_model`` with the
    prior's rows 1/σ_k below it: what the readings do not carry, the prior does, so the
    rank is the posterior's (a parameter without a prior, the attachment, must be seen).
    """
    m, names = result.measurements, result.estimates[method].names
    if result.prior is None:
        J = sensitivity(base, m.joints_deg[m.present], m.theta0_deg, names).psi
        return J, analyse_jacobian(J, names)
    rows = 1.0 / np.array([result.prior.prior_sd[n] for n in names])
    J = np.vstack([result.prior.jacobian / sigma_model, np.diag(rows)])
    return J, analyse_jacobian(J, names)


def _landing_sigma_mm(result: SolveResult, base: Model) -> float:
    """Return σ_a, what the declared repeatability adds to a length (0 without the key)."""
    m, r = result.measurements, result.robot.repeatability_mm
    if r is None:
        return 0.0
    q = np.radians(m.joints_deg[m.present])
    return length_sigma_mm(base, q, np.radians(m.theta0_deg), r)


def _scale_hint(result: SolveResult, limit_mm: float) -> str:
    """Return the residual finding's end: the encoder's scale, when the log has no gauge."""
    if len(result.measurements.reference_mm):
        return ")"
    return _scale_explains(result, limit_mm) or (
        "; an encoder scale off beyond [encoder] scale_tolerance_ppm: check mm_per_count, or "
        "measure a reference gauge (reference_length_mm), as this log has no reference step)"
    )


def _scale_explains(result: SolveResult, limit_mm: float) -> str:
    """Return the residual finding's diagnosis of an encoder scale error ('' if none).

    The joint fit linearised at its estimate with the scale s as one more unknown (the
    lengths read (1 + s)·d̃, column −d̃, :func:`~wirecal.solver.identify.joint`'s): when
    its residual σ is within ``limit_mm`` and s beyond the robot file's tolerance, the
    scale explains the misfit. Without a gauge s leans on the lengths the plan holds at
    nominal (:mod:`~wirecal.solver.scale`), so a wrong one of those looks the same.
    """
    est, m, robot = result.estimates.get("joint"), result.measurements, result.robot
    if est is None:
        return ""
    errors = ErrorSet(est.names, robot.n_joints)
    q, q0 = np.radians(m.joints_deg[m.present]), np.radians(m.theta0_deg)
    model = with_errors(robot.nominal, est.names, errors.to_internal(est.values))
    d, J = wire_jacobian(at_points(model, result.plan, m.present), q, q0, est.names)
    measured = m.distance_mm[m.present]
    A = np.column_stack([J, -measured])
    dof = len(measured) - A.shape[1]
    if dof <= 0:
        return ""
    step, *_ = np.linalg.lstsq(A, measured - d, rcond=None)
    left = measured - d - A @ step
    sigma = float(np.sqrt(left @ left / dof))
    s_ppm, tolerance = float(step[-1]) / PPM, robot.encoder.scale_tolerance_ppm
    if not (sigma <= limit_mm and abs(s_ppm) > tolerance):
        return ""
    return (
        f"); the encoder's scale explains it: the lengths read {abs(s_ppm):.0f} ppm "
        f"{'longer' if s_ppm > 0 else 'shorter'} fit to σ {sigma:.4f} mm, a scale off "
        f"beyond [encoder] scale_tolerance_ppm {tolerance:g}: mm_per_count {m.mm_per_count:g} "
        f"would be about {m.mm_per_count * (1 + s_ppm * PPM):.6g}; check it against the "
        "encoder's data sheet or measure a reference gauge (reference_length_mm), as this "
        "log has no reference step; unless a length the plan leaves at the robot file's "
        "value is wrong by as much"
    )


def _lengths(
    measured: np.ndarray, model: np.ndarray, mm_per_count: float, source: str, check: str
) -> list[Finding]:
    """Return the span of the measured lengths against the robot model's at the same points.

    A span ``mm_per_count`` times the model's is counts that were already millimetres.
    """
    span_measured = float(np.ptp(measured)) if measured.size else 0.0
    span_model = float(np.ptp(model)) if model.size else 0.0
    if span_model <= 0:
        return []  # every point at one distance: the identifiability check speaks
    ratio = span_measured / span_model
    if (
        ratio < 1 / LENGTH_SPAN_RATIO
        and abs(ratio / abs(mm_per_count) - 1) < COUNTS_IN_MM_TOLERANCE
    ):
        return [
            Finding(
                "lengths",
                f"implausible wire lengths: {source}'s span {span_measured:.3f} mm where the "
                f"robot file's geometry gives {span_model:.1f} mm at the same points, "
                f"{ratio:.4g} times as much: the log's counts column looks like millimetres "
                f"(its span is mm_per_count {abs(mm_per_count):g} × the expected one), as a "
                "program that logged the wire's length writes; log the raw count (as the "
                "programs 'wirecal gen' writes do) and measure again",
            )
        ]
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


def _identifiability(
    ident: Identifiability, J: np.ndarray, sigma_model: float, *, each: bool = True
) -> list[Finding]:
    """Rank deficiency (named) and, with ``each``, the parameters the noise leaves unidentified."""
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
    if not each:
        return findings
    cov, _ = covariance(J, sigma_model**2)
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    # a compliance: twice the σ it was chosen by (wirecal.solver.compliance), in µrad/(N·m)
    limit = [
        2 * SIGMA_LIMIT_URAD_PER_NM if P.unit_of(n) == "urad/Nm" else POORLY_IDENTIFIED
        for n in ident.names
    ]
    weak = [f"{n} ±{s:.3g}" for n, s, w in zip(ident.names, sd, limit, strict=True) if s >= w]
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


def _bounds(result: SolveResult, method: str, omega_default: float) -> list[Finding]:
    """Estimates on or beyond their Ω, or beyond a physically plausible size.

    Compliances have no Ω (no step bounds them): only their plausible size.
    """
    est = result.estimates[method]
    names = est.names
    robot = result.robot
    omega = omega_vector(names, robot.n_joints, result.plan, omega_default)
    omega = robot.errors(names).to_boundary(omega)
    on_bound = [
        f"{n} {v:+.4g}"
        for n, v, w in zip(names, est.values, omega, strict=True)
        if abs(v) >= w * (1 - 1e-9) and P.unit_of(n) != "urad/Nm"
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
    if dr.correctable:
        return []  # removed from the lengths, with a warning (Drift.warning)
    why = (
        "not removed from the lengths"
        if not dr.removed
        else "not linear (the zero readings scatter about a line beyond their noise), so "
        "removing it cannot correct the lengths"
        if not dr.linear
        else f"beyond {DRIFT_REMOVABLE_MM_PER_H:g} mm/h, more than removing it can correct"
        if abs(dr.rate_mm_per_h) > DRIFT_REMOVABLE_MM_PER_H
        else "not measured well enough to be removed (2σ beyond the tolerance)"
    )
    return [
        Finding(
            "drift",
            f"the zero readings at θ0 drift by {dr.rate_mm_per_h:+.3f} mm/h (± "
            f"{dr.std_mm_per_h:.3f}, {dr.zeros} readings), beyond the tolerance "
            f"{DRIFT_TOLERANCE_MM_PER_H:g} mm/h by more than 3σ and {why}: fix the encoder's "
            "stand and the wire's attachment, let the cell reach a steady temperature, and "
            "measure again",
        )
    ]


def gate(
    result: SolveResult,
    method: str,
    *,
    accept: bool = False,
    noise_mm: float = READING_NOISE_MM,
    omega_default: float = DEFAULT_OMEGA,
    live_check: str = LIVE_CHECK,
) -> Plausibility:
    """Assess an identification and refuse it unless it passed or is accepted.

    :func:`assess`, raising :class:`Implausible` (exit status 3) unless it passed or
    ``accept`` (the user's explicit override, which the patch then records).
    """
    verdict = assess(
        result, method, noise_mm=noise_mm, omega_default=omega_default, live_check=live_check
    )
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
