"""Which joint compliances one wire identifies with the geometry; offline compensation.

A compliance c_j (:mod:`~wirecal.solver.gravity`) moves the tool point as the joint offset
θ_j would, scaled by the gravity torque: ∂d/∂c_j = τ_j(q)·∂d/∂θ_j. One wire tells c_j
from θ_j only through the change of τ_j over the plan's points, so:

* c_j is **unobservable** when τ_j is zero at every point: gravity along joint j's axis
  (joint 1 of a floor-mounted arm), or nothing joint j carries lies off its axis (the
  flange joint without a payload);
* c_j is **inseparable** from the geometry when its column is a combination of the
  geometric parameters' over the points (τ_j constant: c_j·τ_j is a θ_j offset), named
  by the identifiability analysis (:func:`~wirecal.solver.identifiability.analyse_jacobian`);
* otherwise c_j is **identified** when its σ at the reading noise, estimated together with
  the geometry and the other identified compliances, is at most
  :data:`SIGMA_LIMIT_URAD_PER_NM`; the compliance with the largest σ is left out first.

Compensation (:func:`compensated_joints`): the joints to command so that the bent arm
holds the pose the rigid arm has at the wanted joints, the way absolute-accuracy options
use a compliance model offline.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.identifiability import analyse_jacobian, covariance
from wirecal.solver.kinematics import Model, bends, gravity_torques, rigid_frames, tool_position
from wirecal.solver.sensitivity import sensitivity

COMPLIANCE_RANGE_URAD_PER_NM = (2.0, 8.0)
"""The range (µrad/(N·m)) of a compliance's true value: the error budget's prior (uniform)
of one the points do not identify, and the range simulated arms draw theirs from
(:func:`~wirecal.formats.truth.random_errors`): issue 30's independent model of an arm like
the Viper s650, "joints 2–4 yielding 2–8 µrad/N·m under gravity" (not a vendor figure). A
stiffer arm is bounded conservatively: its sag is smaller than the range's."""

PRIOR_COMPLIANCE_URAD_PER_NM = COMPLIANCE_RANGE_URAD_PER_NM[1]
"""How far (µrad/(N·m)) a compliance may be: the top of :data:`COMPLIANCE_RANGE_URAD_PER_NM`
(the planner's prior size of a compliance, and the identification rule's range 0–8)."""

SIGMA_LIMIT_URAD_PER_NM = PRIOR_COMPLIANCE_URAD_PER_NM / 12**0.5
"""Largest σ (µrad/(N·m)) of an identified compliance at the reading noise: the σ of a
uniform over 0–8 µrad/(N·m) (2.31), so an identified compliance is known better than
anything from rigid to the range's top. (The budget's prior of one not identified is the
narrower :data:`COMPLIANCE_RANGE_URAD_PER_NM`, σ 1.73, narrowed further by the readings;
the rule stays as it was, so the patch carries the compliances it did.)"""

COMPENSATION_ITERATIONS = 4
"""Fixed-point steps of :func:`compensated_joints`: each shrinks the error by c·|∂τ/∂q|
(≈ 10⁻³), so four leave 10⁻¹² of the sag."""


@dataclass(frozen=True)
class ComplianceObservability:
    """The compliances a plan identifies with the geometry, their σ, and why not the others."""

    identified: tuple[str, ...]
    sigma_urad_per_nm: dict[str, float]  # every candidate's σ at its last evaluation
    reasons: dict[str, str]  # each candidate not identified: why
    no_torque: tuple[str, ...] = ()  # candidates gravity exerts no torque on: no effect

    def describe(self) -> list[str]:
        """Return the analysis in words, one sentence per line."""
        lines = []
        if self.identified:
            sig = ", ".join(f"{n} (σ {self.sigma_urad_per_nm[n]:.3g})" for n in self.identified)
            lines.append(f"Compliances identified with the geometry: {sig} µrad/(N·m).")
        else:
            lines.append("No compliance is identified by these points.")
        lines += [f"{name} is not identified: {why}." for name, why in self.reasons.items()]
        return lines

    def as_json(self) -> dict:
        """Return the analysis as a JSON-ready dict."""
        sig = {n: (s if np.isfinite(s) else None) for n, s in self.sigma_urad_per_nm.items()}
        return {
            "identified": list(self.identified),
            "sigma_urad_per_nm": sig,
            "not_identified": dict(self.reasons),
            "sigma_limit_urad_per_nm": SIGMA_LIMIT_URAD_PER_NM,
        }


def compliance_observability(
    model: Model,
    q_deg: np.ndarray,
    theta0_deg: np.ndarray,
    geometry: Sequence[str],
    candidates: Sequence[str],
    noise_mm: float,
) -> ComplianceObservability:
    """Return which ``candidates`` the points identify with ``geometry`` (module docstring)."""
    geometry, candidates = tuple(geometry), tuple(candidates)
    names = geometry + candidates
    psi = sensitivity(model, q_deg, theta0_deg, names).psi
    ident = analyse_jacobian(psi, names)
    reasons: dict[str, str] = {}
    no_torque = tuple(n for n in candidates if n in ident.unobservable)
    for name in no_torque:
        reasons[name] = (
            f"gravity has no torque about joint {name[1:]} at these points (its axis "
            "is vertical, or nothing it carries lies off its axis): no wire length moves"
        )
    for combo in ident.combinations:
        terms = " ".join(f"{c:+.4g}·{n}" for n, c in combo)
        for name, _ in combo:
            if name in candidates and name not in reasons:
                reasons[name] = (
                    f"{terms} leaves every wire length unchanged: its torque does not vary "
                    "enough over these points to tell it from the geometry"
                )
    keep = [n for n in candidates if n not in reasons]
    sigma = dict.fromkeys(candidates, float("inf"))
    while keep:
        cols = [names.index(n) for n in (*geometry, *keep)]
        cov, ok = covariance(psi[:, cols], noise_mm**2)
        sd = np.where(ok, np.sqrt(np.clip(np.diag(cov), 0.0, None)), np.inf)[len(geometry) :]
        sigma.update(zip(keep, (float(s) for s in sd), strict=True))
        worst = int(np.argmax(sd))
        if sd[worst] <= SIGMA_LIMIT_URAD_PER_NM:
            break
        name = keep.pop(worst)
        reasons[name] = (
            f"σ {sd[worst]:.3g} µrad/(N·m) at {noise_mm:g} mm of reading noise, above "
            f"{SIGMA_LIMIT_URAD_PER_NM:.3g}: the torque about joint {name[1:]} is too small or "
            "varies too little over these points"
        )
    order = {n: k for k, n in enumerate(candidates)}
    return ComplianceObservability(
        tuple(keep), sigma, dict(sorted(reasons.items(), key=lambda kv: order[kv[0]])), no_torque
    )


def compensated_joints(model: Model, q: np.ndarray) -> np.ndarray:
    """Return the joints (rad, (N, n)) to command so the bent ``model`` reaches q's pose.

    The pose the rigid arm has at the wanted joints ``q`` (N, n), e.g. from the inverse
    kinematics of the calibrated geometry for a wanted tool point. The bent arm at q_c
    turns its joints by c·τ(q_c), so q_c = q − c·τ(q_c): a fixed point, reached in
    :data:`COMPENSATION_ITERATIONS` steps (τ is evaluated at the commanded joints, as the
    model does). A model without masses or compliance returns q.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if not bends(model):
        return q
    c = model.compliance
    rigid = replace(model, compliance=None)
    command = q
    for _ in range(COMPENSATION_ITERATIONS):
        command = q - c * gravity_torques(rigid, rigid_frames(rigid, command))
    return command


@dataclass(frozen=True)
class Sag:
    """The tool point's sag under gravity at configurations (mm, (Q,)), before and after.

    ``before_mm``: the bent arm against the rigid one at the commanded joints (the patch as
    a controller applies it); ``after_mm``: at the joints :func:`compensated_joints` gives
    for the identified compliances (what the others leave).
    """

    before_mm: np.ndarray
    after_mm: np.ndarray


def workspace_sag(model: Model, identified: Sequence[int], q: np.ndarray) -> Sag:
    """Return ``model``'s sag over ``q`` (rad, (Q, n)) before and after compensation.

    ``model`` is the calibrated arm (the identified compliances' values, the file's for
    the others); the compensation takes only the compliances of joints ``identified``
    (0-based rows).
    """
    rigid = replace(model, compliance=None)
    p = tool_position(rigid, q)
    c = np.zeros(model.n_joints)
    if model.compliance is not None:
        c[list(identified)] = np.asarray(model.compliance)[list(identified)]
    command = compensated_joints(replace(model, compliance=c), q)
    return Sag(
        np.linalg.norm(tool_position(model, q) - p, axis=1),
        np.linalg.norm(tool_position(model, command) - p, axis=1),
    )
