"""The error budget of a calibration: what the tool point's error is made of.

Each identification method is, linearised, a linear map M of the measured wire lengths to
the parameters (the joint method: M = J⁺, the least-squares pseudo-inverse; the stepwise
method: the map A of :func:`~wirecal.solver.accuracy.stepwise_map`). An error δd of the
lengths becomes δe = M·δd and the tool-point error J_p(q)·δe at a configuration q. Each
term is a parameter error with a stated distribution (:class:`~wirecal.solver.bound.ErrorModel`);
its figure is the mean over the workspace of the RMS tool-point error under that
distribution, from its second moment (:func:`~wirecal.solver.accuracy.rms_tool_error`):

* **noise** — the reading noise σ (from the joint residual): σ²·(JᵀJ)⁺, the Cramér–Rao
  bound, for the joint method; σ²·A·Aᵀ for the stepwise one; and the error of the zero
  reference every length is read from (the mean of the steps' zero readings, σ/√zeros),
  common to all lengths: δd = z·1, so δe = z·M·1; and the zero readings' length where the
  arm really stops at θ0, ‖δp‖ ≥ 0 whatever the direction, uniform between none and
  :data:`CHI3_MEAN`·σ, every length as much too short;
* **scale** — every length is off by the same factor: δd = ε·d, so δe = ε·M·d. ε is the
  reference's σ when the log has reference rows (Gaussian), else uniform within the
  datasheet's ``scale_tolerance_ppm`` (a tolerance is a limit, not a standard deviation:
  the GUM's rectangular distribution, JCGM 100:2008 §4.3.7);
* **drift** — the zero drift's uncertainty σ_b (and the fitted drift itself when it was
  left in): δd_i = b·(t_i − t_ref); with the robot file's ``compliances``, the drift left
  in the lengths as the zero readings and the joint fit's residual tell it together
  (:func:`drift_posterior`); and the temperature: the drum's expansion relative to
  the arm's, (α_drum − α_arm)·ΔT over an assumed change of
  :data:`ASSUMED_TEMPERATURE_RISE_K` across the run, of either sign equally likely: a scale
  that changes from the reference's time (the start; without a reference, the run's
  middle): δd_i = α·ΔT·d_i·(t_i − t_ref)/T. Untimed (version 1) logs: no drift term, said
  so;
* **exit** — the wire's wrap on an eyelet's exit edge, which the model leaves out
  (:func:`~wirecal.solver.plan.exit.unmodelled_exit_mm`, per point at the nominal
  model): a deterministic δd_i, so δe = M·δd; zero for a point exit and for a guide
  pulley (the model carries its arc);
* **sag** — joints 2 and 3 bending under gravity, which no kinematic parameter models: the
  robot file's ``gravity_sag_deg_per_m`` (:func:`~wirecal.solver.simulate.sag_lengths_mm`),
  uniform between none and it. The parameters absorb part of it, a bias the residual
  cannot show;
* **compliance** — with the robot file's ``compliances``, those the points do not identify
  (with a torque): their posterior (:func:`compliance_errors`), the prior uniform over the
  stated range :data:`~wirecal.solver.compliance.COMPLIANCE_RANGE_URAD_PER_NM` times what
  the readings say of them, N(ĉ, S) (:func:`compliance_likelihood`): a Gaussian restricted
  to the range, the uniform where they say nothing; the identified ones are parameters,
  their σ in the noise.

* **prior** — a fit with a prior where the readings are weak (a plan from a pool,
  :mod:`~wirecal.solver.wire_prior`): its map is M = P·Jᵀ/σ² with P the posterior
  covariance, the noise term σ²·M·Mᵀ, and the prior's share (M·J − I)·Λ⁻¹·(M·J − I)ᵀ —
  the arm's own error along what the readings see weakly, which the fit shrinks toward the
  data sheet (:class:`PriorTerms`).

The total is the second moment of all the terms together (independent sources): the
expected (RMS) error, a mean, not a bound. The **bound** is the error a calibration stays
below with 95 % probability (:mod:`wirecal.solver.bound`), from the same error models.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.accuracy import rms_tool_error, stepwise_map
from wirecal.solver.bound import ErrorModel, bound_mm, joined, truncated_model
from wirecal.solver.box_gaussian import BoxGaussian
from wirecal.solver.compliance import COMPLIANCE_RANGE_URAD_PER_NM
from wirecal.solver.errors import WirecalError
from wirecal.solver.identifiability import RANK_RTOL, covariance
from wirecal.solver.kinematics import Model, tool_jacobian
from wirecal.solver.memo import Kept, digest
from wirecal.solver.params import ErrorSet
from wirecal.solver.scale import ARM_PPM_PER_K, PPM, Drift

ASSUMED_TEMPERATURE_RISE_K = 0.5
"""Temperature change over a run the budget assumes (K): the simulated realistic run's rise;
its sign is taken as unknown."""

CHI3_MEAN = 2 * np.sqrt(2 / np.pi)
"""E‖δp‖ / σ for a 3-D Gaussian δp of σ per axis (the mean of a χ with 3 degrees of freedom).

At θ0 the wire is as short as it gets (the model's zero length): where the arm really
stops, δp off, it is ‖δp‖ long, never shorter, whatever the direction. Every zero reading
therefore reads long by up to that, 1.6 σ when the residual's σ is all the arm's
repeatability, none when it is all the encoder's reading noise: uniform between."""

TERMS = ("noise", "scale", "drift", "exit", "sag")

COMPLIANCE_NOTE = (
    "sag: the identified compliances (no assumed sag); the 95 % bound is the patch's as the "
    "controller applies it, the sag left in it; bound95_compensated_mm that of targets "
    "compensated offline"
)


@dataclass(frozen=True)
class Budget:
    """One method's expected mean tool-point error (mm) per source, in total, its 95 % bound."""

    terms: dict[str, float]  # mean over the workspace of each source's RMS error
    total: float
    worst: float  # the total's worst configuration
    notes: tuple[str, ...]
    bound: float  # 95 % bound of the mean over the workspace (:mod:`wirecal.solver.bound`)
    bound_compensated: float | None = None  # the same for targets compensated offline
    # the unidentified compliances' posterior (value, σ; µrad/(N·m)), as the bound takes them
    posterior: dict[str, tuple[float, float]] | None = None
    # the zero drift left in the lengths as the budget charged it (mean, σ; mm/s;
    # :func:`drift_posterior`): the joint estimate's covariance carries it too
    drift_left_mm_per_s: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        """Refuse a figure that is not a number: never a NaN budget with exit status 0."""
        figures = {**{f"{k} term": v for k, v in self.terms.items()}, "total": self.total}
        figures.update(worst=self.worst, bound=self.bound)
        if self.bound_compensated is not None:
            figures["compensated bound"] = self.bound_compensated
        bad = [f"{k} {v}" for k, v in figures.items() if not np.isfinite(v)]
        if bad:
            raise WirecalError(
                f"the error budget has no value ({', '.join(bad)}): a figure of the model is "
                "not a number; nothing is reported (please report this with the robot file "
                "and the plan)"
            )

    def as_json(self) -> dict:
        """Return the budget as a JSON-ready dict."""
        out = {
            "terms_mm": dict(self.terms),
            "total_mm": self.total,
            "worst_mm": self.worst,
            "bound95_mm": self.bound,
            "notes": list(self.notes),
        }
        if self.bound_compensated is not None:
            out["bound95_compensated_mm"] = self.bound_compensated
        if self.posterior:
            out["compliances_not_identified_urad_per_nm"] = {
                n: {"value": v, "std": sd} for n, (v, sd) in self.posterior.items()
            }
        return out


@dataclass(frozen=True)
class ComplianceTerms:
    """The compliances in the joint method's budget (internal units, rad/(N·m)).

    ``left`` (m,) is what the controller leaves of the estimated parameters: the value of
    each identified compliance (nominal + offset; the controller takes none), 0 for the
    geometry. ``names`` are the compliances the points do not identify (with a torque),
    ``wire`` (N, k) their wire-length Jacobian, ``prior`` (2, k) the range of each, as
    offsets from the robot file's value, ``nominal`` (k,) the file's; ``residual_mm`` (N,)
    the joint fit's residuals (model − measured), what the readings say of them.
    """

    left: np.ndarray
    names: tuple[str, ...]
    wire: np.ndarray
    prior: np.ndarray
    nominal: np.ndarray
    residual_mm: np.ndarray


@dataclass(frozen=True)
class Sources:
    """What the budget is computed from, shared by the methods."""

    sigma_mm: float  # reading noise σ
    lengths_mm: np.ndarray  # (N,) the lengths solved from
    scale_std: float  # ε: σ of the scale (reference) or the tolerance (dimensionless)
    measured_scale: bool  # ε is the reference's σ
    t_s: np.ndarray | None  # (N,) the points' times, None for an untimed log
    t_scale_ref_s: float  # when the scale was right (the reference's time or mid-run)
    run_s: float  # the run's duration
    drift: Drift | None
    t_zero_ref_s: float  # mean time of the zeros the lengths are read from
    thermal_ppm_per_k: float  # α_drum − α_arm
    exit_mm: np.ndarray  # (N,) the wire length the model leaves out at each point
    sag_mm: np.ndarray  # (N,) the length the robot file's gravity sag adds at each point
    sigma_zero_mm: float = 0.0  # σ of the zero reference every length is read from
    zero_bias_mm: float = 0.0  # the most the zero reference may read long (:data:`CHI3_MEAN`)
    # the drift left in the lengths, (mean, σ) in mm/s (:func:`drift_posterior`); None: the
    # zero readings' fit alone
    drift_left_mm_per_s: tuple[float, float] | None = None


@dataclass(frozen=True)
class PriorTerms:
    """A fit with a prior, linearised (:class:`~wirecal.solver.wire_prior.Posterior`'s rows).

    ``map`` (m, N) moves the m parameters by M·δd for a length error δd; ``noise`` (m, m) is
    the readings' share of the posterior, ``share`` (m, m) the prior's (internal units).
    """

    map: np.ndarray
    noise: np.ndarray
    share: np.ndarray


def sources(
    sigma_mm: float,
    lengths_mm: np.ndarray,
    scale_std: float,
    measured_scale: bool,
    drum_ppm_per_k: float,
    t_s: np.ndarray | None,
    drift: Drift | None,
    t_zero_ref_s: float | None,
    exit_mm: np.ndarray,
    sag_mm: np.ndarray,
    zeros: int = 0,
    *,
    zero_corrected: bool = False,
) -> Sources:
    """Gather the budget's inputs (see :class:`Sources`).

    ``scale_std`` is the reference's σ of the scale when ``measured_scale``, else the
    tolerance (dimensionless); the times are None for an untimed log. ``zeros``: the zero
    readings whose mean every length is read from (0: none), each with the reading noise.
    ``zero_corrected``: the lengths already carry what the zeros read long (a declared
    repeatability, :mod:`~wirecal.solver.zero_reading`), so no bias is budgeted for it.
    """
    timed = t_s is not None and t_zero_ref_s is not None and np.all(np.isfinite(t_s))
    t = np.asarray(t_s, dtype=float) if timed else None
    run_s = float(np.max(t)) if t is not None and t.size else 0.0
    return Sources(
        sigma_mm=sigma_mm,
        lengths_mm=np.asarray(lengths_mm, dtype=float),
        scale_std=scale_std,
        measured_scale=measured_scale,
        t_s=t,
        t_scale_ref_s=0.0 if measured_scale else run_s / 2,
        run_s=run_s,
        drift=drift,
        t_zero_ref_s=float(t_zero_ref_s) if timed and t_zero_ref_s is not None else 0.0,
        thermal_ppm_per_k=drum_ppm_per_k - ARM_PPM_PER_K,
        exit_mm=np.asarray(exit_mm, dtype=float),
        sag_mm=np.asarray(sag_mm, dtype=float),
        sigma_zero_mm=sigma_mm / np.sqrt(zeros) if zeros > 0 else 0.0,
        zero_bias_mm=CHI3_MEAN * sigma_mm if zeros > 0 and not zero_corrected else 0.0,
    )


def least_squares_map(J: np.ndarray) -> np.ndarray:
    """Return J⁺ over the directions the data sees (the rank rule of ``covariance``)."""
    return np.linalg.pinv(J, rcond=RANK_RTOL)


def budget(
    model: Model,
    names: tuple[str, ...],
    J: np.ndarray,
    step: np.ndarray | None,
    src: Sources,
    q_ws: np.ndarray,
    compliance: ComplianceTerms | None = None,
    prior: PriorTerms | None = None,
) -> Budget:
    """Return the error budget of a method (module docstring).

    ``J`` (N, m) is the wire-length Jacobian at the measured points in internal units;
    ``step`` the points' steps for the stepwise method, None for the joint method.
    ``compliance``: the joint method's compliances; the bound is then the patch's as the
    controller applies it (the sag left in it) and ``bound_compensated`` the bound of
    targets compensated offline with the identified compliances, and the drift is the one
    the residual narrows (:func:`drift_posterior`). ``prior``: a fit with a prior (its map
    and shares replace J's; ``J`` and ``step`` unused), its share a term of its own.
    """
    if compliance is not None:
        src = replace(src, drift_left_mm_per_s=drift_posterior(J, compliance, src))
    if prior is not None:
        M, noise = prior.map, prior.noise
    elif step is None:
        M = least_squares_map(J)
        noise = covariance(J, src.sigma_mm**2)[0]
    else:
        M = stepwise_map(J, step)
        noise = src.sigma_mm**2 * M @ M.T
    parts = _term_errors(M, noise, src)
    if prior is not None:
        parts["prior"] = ErrorModel(prior.share, np.zeros(len(M)), np.zeros((0, len(M))))
    errors = joined(list(parts.values()))
    Jp = _workspace_jacobian(model, q_ws, names)
    errs = {k: rms_tool_error(Jp, e.second_moment()).mean_mm for k, e in parts.items()}
    if compliance is None:
        total = rms_tool_error(Jp, errors.second_moment())
        return Budget(errs, total.mean_mm, total.max_mm, _notes(src), bound_mm(Jp, errors))
    return _with_compliance(model, q_ws, (Jp, J, M), compliance, src, errors, errs)


_WORKSPACE: Kept[np.ndarray] = Kept(8)
"""The last tool-point Jacobians over a workspace (Q, 3, m; read-only)."""


def _workspace_jacobian(model: Model, q_ws: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """Return ∂p/∂e (Q, 3, m) of ``names`` over the workspace ``q_ws``, kept by its inputs.

    The two methods' budgets of a solve without compliances take the same one, and so do
    the budgets of the same log solved again (:mod:`~wirecal.solver.memo`).
    """

    def computed() -> np.ndarray:
        Jp = tool_jacobian(model, q_ws, names)[1]
        Jp.setflags(write=False)
        return Jp

    return _WORKSPACE.get(digest(model, q_ws, tuple(names)), computed)


def _term_errors(M: np.ndarray, noise: np.ndarray, src: Sources) -> dict[str, ErrorModel]:
    """Return each term's parameter error with its distribution (module docstring).

    Gaussian: the noise, a measured scale, the zero drift; uniform within its limits: the
    scale known by its tolerance, the sag (between none and the declared one: bias and
    edge half of it); the assumed size of either sign: the temperature's scale change; a
    known bias: the exit.
    """
    m = len(M)
    none, zero = np.zeros((0, m)), np.zeros(m)
    b_zero = src.sigma_zero_mm * M.sum(axis=1)  # the zero reference's error, in every length
    long_zero = -src.zero_bias_mm / 2 * M.sum(axis=1)  # a zero read long: every length short
    b_scale = M @ src.lengths_mm
    b_sag = M @ src.sag_mm / 2
    drift, drift_bias, thermal = _drift(M, src)
    if src.measured_scale:
        scale = ErrorModel(src.scale_std**2 * np.outer(b_scale, b_scale), zero, none)
    else:
        scale = ErrorModel(np.zeros((m, m)), zero, src.scale_std * b_scale[None, :])
    return {
        "noise": ErrorModel(noise + np.outer(b_zero, b_zero), long_zero, long_zero[None, :]),
        "scale": scale,
        "drift": ErrorModel(drift, drift_bias, none, thermal[None, :]),
        "exit": ErrorModel(np.zeros((m, m)), M @ src.exit_mm, none),
        "sag": ErrorModel(np.zeros((m, m)), b_sag, b_sag[None, :]),
    }


def _with_compliance(
    model: Model,
    q_ws: np.ndarray,
    maps: tuple[np.ndarray, np.ndarray, np.ndarray],
    c: ComplianceTerms,
    src: Sources,
    errors: ErrorModel,
    errs: dict[str, float],
) -> Budget:
    """Return the joint budget with the compliances (:func:`compliance_errors`).

    ``maps``: the tool-point Jacobian over the workspace, the wire-length Jacobian and the
    least-squares map. The term ``compliance`` and the total gain the unidentified
    compliances; the identified ones are parameters, their σ in the noise term. ``bound``
    is the patch's (the controller takes no compliance: the identified values and the
    others' file values are left, −``left`` and −``nominal``), ``bound_compensated`` that
    of compensated targets.
    """
    Jx, unseen = compliance_errors(model, q_ws, maps, c, src)
    terms = {**errs, "compliance": rms_tool_error(Jx, unseen.second_moment()).mean_mm}
    extended = joined([errors.padded(len(unseen.bias)), unseen])
    total = rms_tool_error(Jx, extended.second_moment())
    left = -np.concatenate([c.left, c.nominal])
    notes = _notes(src)
    posterior = _posterior(model, c, unseen)
    said = ", ".join(f"{n} {v:.2g} ± {sd:.2g}" for n, (v, sd) in posterior.items())
    return Budget(
        terms,
        total.mean_mm,
        total.max_mm,
        (*notes[:2], COMPLIANCE_NOTE, *notes[3:])
        + ((f"{POSTERIOR_NOTE}: {said} µrad/(N·m)",) if posterior else ())
        + _drift_note(src),
        bound_mm(Jx, replace(extended, bias=extended.bias + left)),
        bound_mm(Jx, extended),
        posterior,
        src.drift_left_mm_per_s,
    )


POSTERIOR_NOTE = (
    "compliance: those not identified as the bound takes them, their range ({:g}–{:g} "
    "µrad/(N·m)) narrowed by what the readings say".format(*COMPLIANCE_RANGE_URAD_PER_NM)
)


def _posterior(model: Model, c: ComplianceTerms, unseen: ErrorModel) -> dict:
    """Return each unidentified compliance's posterior value and σ (µrad/(N·m))."""
    if unseen.truncated is None or not c.names:
        return {}
    units = ErrorSet(c.names, model.n_joints)
    mean, cov = unseen.truncated.moments
    value = units.to_boundary(c.nominal + mean)
    sd = units.to_boundary(np.sqrt(np.clip(np.diag(cov), 0.0, None)))
    return {n: (float(v), float(s)) for n, v, s in zip(c.names, value, sd, strict=True)}


def compliance_errors(
    model: Model,
    q_ws: np.ndarray,
    maps: tuple[np.ndarray, np.ndarray, np.ndarray],
    c: ComplianceTerms,
    src: Sources,
) -> tuple[np.ndarray, ErrorModel]:
    """Return the tool-point Jacobian (Q, 3, m) extended by the unidentified compliances.

    And those compliances' error model over the m + k (the one rule of the budget's
    compliance term and of both bounds). ``maps``: the tool-point Jacobian, the wire-length
    Jacobian J and the least-squares map M (:func:`_with_compliance`).

    The offsets of such compliances from the robot file's values are their posterior: the
    prior, each uniform over the stated range ``prior``
    (:data:`~wirecal.solver.compliance.COMPLIANCE_RANGE_URAD_PER_NM`), times what the
    readings say of them together, N(ĉ, S) (:func:`compliance_likelihood`): that Gaussian
    restricted to the box (:class:`~wirecal.solver.box_gaussian.BoxGaussian`), the uniform
    where the readings say nothing. The geometry's estimates absorb them (M·J_u·c_u) and
    they move the tool (−c_u): the error is [M·J_u; −I]·c_u. The geometry's own noise is
    independent of ĉ (M·J_u⁺ = 0 on the residual), so the posterior joins the budget's
    other terms as an independent source.
    """
    Jp, J, M = maps
    k = len(c.names)
    Ju = _workspace_jacobian(model, q_ws, c.names)
    V = np.vstack([M @ c.wire, -np.eye(k)])  # (m + k, k)
    return np.concatenate([Jp, Ju], axis=2), truncated_model(V.T, compliance_likelihood(J, c, src))


def compliance_likelihood(J: np.ndarray, c: ComplianceTerms, src: Sources) -> BoxGaussian:
    """Return the posterior of the unidentified compliances' offsets (internal units).

    What the readings say: ĉ, their least-squares estimate with the geometry ``J`` (N, m)
    from the joint fit's residual (the geometry's share of it is zero at the fit): the rows
    B of [J, J_u]⁺ for them (columns scaled to unit norm for the rank rule of
    :func:`~wirecal.solver.identifiability.covariance`), ĉ = −B·r. Every budget term moves
    ĉ through B as it moves the geometry through M (:func:`_term_errors`): their known
    biases are taken off ĉ, S is the rest's covariance. A compliance the points do not
    separate from the geometry is left out of the estimate: flat, its prior alone.
    """
    seen = _estimator(J, c.wire)[1]
    B = np.zeros((len(seen), len(J)))
    B[seen] = _estimator(J, c.wire[:, seen])[0]
    said = joined(list(_term_errors(B, src.sigma_mm**2 * B @ B.T, src).values()))
    cov = said.second_moment() - np.outer(said.bias, said.bias)
    return BoxGaussian(-B @ c.residual_mm - said.bias, cov, ~seen, c.prior[0], c.prior[1])


def _estimator(J: np.ndarray, wire: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows of [J, wire]⁺ for ``wire``'s coefficients (k, N) and which it tells.

    The columns scaled to unit norm, so the rank rule of
    :func:`~wirecal.solver.identifiability.covariance` compares shapes, not units.
    """
    full = np.hstack([J, wire])
    norms = np.linalg.norm(full, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    cov, identified = covariance(full / norms, 1.0)
    m = J.shape[1]
    return (cov @ (full / norms).T)[m:] / norms[m:, None], identified[m:]


def _drift_note(src: Sources) -> tuple[str, ...]:
    """Return the note of the drift the residual narrowed (:func:`drift_posterior`), if any."""
    if src.drift_left_mm_per_s is None or src.drift is None:
        return ()
    mean, sd = (3.6e6 * v for v in src.drift_left_mm_per_s)  # mm/s -> µm/h
    return (
        f"drift: left in the lengths {mean:+.0f} ± {sd:.0f} µm/h as the zero readings "
        f"(± {src.drift.std_mm_per_h * 1000:.0f}) and the points' residual tell it together",
    )


def _notes(src: Sources) -> tuple[str, ...]:
    """Return what the budget's terms were taken from."""
    notes = [
        "scale: measured with the reference gauge"
        if src.measured_scale
        else f"scale: the datasheet tolerance ±{src.scale_std / PPM:g} ppm, no reference "
        "measured: measure the reference (reference_length_mm) to remove most of it",
        f"exit: the eyelet's edge wrap the model leaves out, up to "
        f"{float(np.max(src.exit_mm)):.3f} mm at a point"
        if np.any(src.exit_mm)
        else "exit: none unmodelled (a point exit, or a guide pulley the model carries)",
        f"sag: joints 2 and 3 under gravity (gravity_sag_deg_per_m; assumed, not measured), "
        f"up to {float(np.max(np.abs(src.sag_mm), initial=0.0)):.3f} mm of wire at a point",
    ]
    if src.t_s is None:
        notes.append("drift: the log has no times (version 1): no drift term")
    return tuple(notes)


def _drift(M: np.ndarray, src: Sources) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the zero drift's parameter covariance and bias, and the temperature's error.

    The drift left in the lengths, b·(t − t_ref) moving the parameters by b·M·(t − t_ref):
    its posterior N(mean, σ²) when the residual was read for it (:func:`drift_posterior`);
    else from the zero readings' fit alone, random: its σ, and the fitted rate b̂ when it
    was left in (the second moment b̂² + σ² of the flat prior's posterior N(b̂, σ²)). The
    temperature's scale change is a bounded error of unknown sign: its edge, α·ΔT over the
    assumed rise (zero for an untimed log).
    """
    m = M.shape[0]
    cov, bias, edge = np.zeros((m, m)), np.zeros(m), np.zeros(m)
    if src.t_s is None:
        return cov, bias, edge
    g = M @ (src.t_s - src.t_zero_ref_s)
    if src.drift_left_mm_per_s is not None:
        mean, sd = src.drift_left_mm_per_s
        cov, bias = sd**2 * np.outer(g, g), mean * g
    elif src.drift is not None:
        left = 0.0 if src.drift.removed else src.drift.rate_mm_per_s**2
        cov += (src.drift.std_mm_per_s**2 + left) * np.outer(g, g)
    if src.run_s > 0:
        rate = src.thermal_ppm_per_k * PPM * ASSUMED_TEMPERATURE_RISE_K / src.run_s
        edge = rate * (M @ (src.lengths_mm * (src.t_s - src.t_scale_ref_s)))
    return cov, bias, edge


def drift_posterior(J: np.ndarray, c: ComplianceTerms, src: Sources) -> tuple[float, float] | None:
    """Return the posterior (mean, σ; mm/s) of the zero drift left in the lengths.

    Two independent readings of it. The zero readings' fit
    (:func:`~wirecal.solver.scale.fit_drift`): N(b̂, σ_b²) when the drift was left in,
    N(0, σ_b²) once b̂ was removed (b − b̂ remains). And the joint fit's residual
    ``c.residual_mm``: what of b·(t − t_ref) the geometry ``J`` (N, m) and the
    unidentified compliances ``c.wire`` cannot take up stays in it, read by w, the
    drift's row of [J, J_u, t − t_ref]⁺ (:func:`_estimator`), as −w·r; every other budget
    term moves that reading through w as it moves the geometry through M
    (:func:`_term_errors`): their known biases are taken off it, the rest is its variance
    (as :func:`compliance_likelihood` reads the compliances). With a flat prior the
    posterior is the two Gaussians' product. None for an untimed log or without a drift
    fit; the zeros' alone where the points do not tell the drift from the parameters.
    """
    d = src.drift
    if src.t_s is None or d is None:
        return None
    prior_mean, prior_var = (0.0 if d.removed else d.rate_mm_per_s), d.std_mm_per_s**2
    w, seen = _estimator(np.hstack([J, c.wire]), (src.t_s - src.t_zero_ref_s)[:, None])
    if not seen[0]:
        return prior_mean, d.std_mm_per_s
    others = replace(src, drift=None)  # every term but the drift itself
    said = joined(list(_term_errors(w, src.sigma_mm**2 * w @ w.T, others).values()))
    var = float(said.second_moment()[0, 0] - said.bias[0] ** 2)
    read = float(-w[0] @ c.residual_mm - said.bias[0])
    precision = 1.0 / prior_var + 1.0 / var
    return (prior_mean / prior_var + read / var) / precision, precision**-0.5
