"""The zero drift left in the lengths, as the zero readings and the points' residual tell it."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from wirecal.app.coverage import simulated_calibration, with_gauge
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import robot_from_dict
from wirecal.formats.truth import random_errors
from wirecal.solver.accuracy import workspace
from wirecal.solver.budget import ComplianceTerms, budget, drift_posterior, sources
from wirecal.solver.kinematics import tool_jacobian
from wirecal.solver.scale import ARM_PPM_PER_K, Drift
from wirecal.solver.simulate import Unmodelled

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PAYLOAD_VIPER = Path(__file__).resolve().parent / "data" / "payload_viper_s650"
SIGMA_MM = 0.01
N, M = 60, 4
T_S = np.linspace(20.0, 600.0, N)  # the points' times
T_REF_S = 250.0  # the zeros' mean time, every length read from it
SIGMA_Z = 0.5 / 3600  # the zeros' fit: σ_b 0.5 mm/h, in mm/s


def _src(drift: Drift):
    """Sources with reading noise and the drift alone (an exact scale, no warming, no zeros)."""
    return sources(SIGMA_MM, np.zeros(N), 0.0, True, ARM_PPM_PER_K, T_S, drift, T_REF_S,
                   np.zeros(N), np.zeros(N))  # fmt: skip


def _case(rng: np.random.Generator, drift_mm_per_s: float):
    """A fit without the drift: J (N, M), one unidentified compliance's column, the residual."""
    J, wire = rng.normal(size=(N, M)), rng.normal(size=(N, 1))
    d = J @ rng.normal(size=M) + drift_mm_per_s * (T_S - T_REF_S) + rng.normal(0, SIGMA_MM, N)
    residual = J @ np.linalg.lstsq(J, d, rcond=None)[0] - d  # model − measured
    terms = ComplianceTerms(np.zeros(M), ("c4",), wire, np.array([[0.0], [8e-6]]),
                            np.zeros(1), residual)  # fmt: skip
    return J, terms


def _by_hand(J: np.ndarray, terms: ComplianceTerms, prior: tuple[float, float]):
    """The posterior computed here: the drift's coefficient of [J, w, t − t_ref] fitted to −r
    (numpy's least squares), σ²·[(AᵀA)⁻¹]_bb its variance, times the zeros' N(prior)."""
    A = np.hstack([J, terms.wire, (T_S - T_REF_S)[:, None]])
    read = np.linalg.lstsq(A, -terms.residual_mm, rcond=None)[0][-1]
    var = SIGMA_MM**2 * np.linalg.inv(A.T @ A)[-1, -1]
    precision = 1 / prior[1] ** 2 + 1 / var
    return (prior[0] / prior[1] ** 2 + read / var) / precision, precision**-0.5


@pytest.mark.parametrize("removed", [False, True])
def test_the_residual_narrows_the_drift_left_in(removed):
    """Left in, the zeros say N(b̂, σ_b²); removed, what remains (b − b̂) is N(0, σ_b²); the
    residual reads the drift the geometry cannot take up; the posterior is their product."""
    rng = np.random.default_rng(7)
    J, terms = _case(rng, 0.3 / 3600)
    zeros = Drift(0.4 / 3600, SIGMA_Z, T_REF_S, 12, removed)
    mean, sd = drift_posterior(J, terms, _src(zeros))
    want_mean, want_sd = _by_hand(J, terms, (0.0 if removed else zeros.rate_mm_per_s, SIGMA_Z))
    assert mean == pytest.approx(want_mean, rel=1e-6)
    assert sd == pytest.approx(want_sd, rel=1e-6)
    assert sd < 0.8 * SIGMA_Z  # the points do tell the drift here


def test_the_drift_posterior_is_honest():
    """Over 1,500 simulated fits with a true drift of 0.8 mm/h (1.6 σ_b), the zeros' b̂ drawn
    about it: (posterior mean − truth) / posterior σ has mean 0 and σ 1 (to 0.08 and 6 %)."""
    rng = np.random.default_rng(3)
    truth = 0.8 / 3600
    z = []
    for _ in range(1500):
        J, terms = _case(rng, truth)
        zeros = Drift(truth + SIGMA_Z * rng.normal(), SIGMA_Z, T_REF_S, 12, False)
        mean, sd = drift_posterior(J, terms, _src(zeros))
        z.append((mean - truth) / sd)
    assert abs(np.mean(z)) < 0.08
    assert np.std(z) == pytest.approx(1.0, abs=0.06)


def test_the_compliance_budget_charges_the_posterior_not_the_zeros_alone():
    """The joint budget's drift term with compliances: √(μ² + σ_c²)·mean_q ‖J_p(q)·M·(t −
    t_ref)‖, the posterior's second moment (computed here by hand), not the zeros' alone,
    √(b̂² + σ_b²)·… (the old charge): 0.037 times it here, where the geometry's random columns
    take up little of the drift and the points tell it far better than the zeros."""
    data = tomllib.loads((EXAMPLES / "ur5e" / "robot.toml").read_text())
    robot = robot_from_dict(data, "ur5e.toml")
    q = workspace(robot, 30)
    names = ("a2", "a3", "d4", "th2")
    rng = np.random.default_rng(11)
    J, terms = _case(rng, 0.0)
    zeros = Drift(0.6 / 3600, SIGMA_Z, T_REF_S, 12, False)
    got = budget(robot.nominal, names, J, None, _src(zeros), q, terms).terms["drift"]
    mean, sd = _by_hand(J, terms, (zeros.rate_mm_per_s, SIGMA_Z))
    Jp = tool_jacobian(robot.nominal, q, names)[1]
    reach = np.linalg.norm(Jp @ (np.linalg.pinv(J) @ (T_S - T_REF_S)), axis=1).mean()
    assert got == pytest.approx(np.hypot(mean, sd) * reach, rel=1e-6)
    zeros_alone = np.hypot(zeros.rate_mm_per_s, SIGMA_Z) * reach
    assert got / zeros_alone == pytest.approx(0.037, abs=0.002)


@pytest.mark.slow
def test_the_identified_compliances_sigma_carries_the_drift_left_in():
    """A rigid Viper with a gauge on its payload plan, the zero drifting 1 mm/h (left in the
    lengths in 39 of 40 runs): the identified c2, c3's |ĉ − c|/σ against the simulation's
    truth has about the half-normal's median (0.67) and ±1.96 σ covers about 95 % of them.
    Before the joint estimate's covariance carried the drift: median 1.15, 78 %."""
    data = tomllib.loads((PAYLOAD_VIPER / "robot.toml").read_text())
    data["calibration"].update(compliances=["c2", "c3", "c4", "c5"], repeatability_mm=0.02)
    robot = with_gauge(robot_from_dict(data, "robot.toml"))
    plan = load_plan(PAYLOAD_VIPER / "plan.toml", robot)
    z = []
    for seed in range(1, 41):
        truth = random_errors(robot, 1.0, np.random.default_rng([seed, 1]))
        truth.update({n: -robot.nominal_value(n) for n in robot.compliances})  # rigid
        result, _ = simulated_calibration(
            robot, plan, truth, seed, unmodelled=Unmodelled(None, 0.0), drift_mm_per_h=1.0
        )
        if result.drift is None or result.drift.removed:
            continue
        joint = result.estimates["joint"]
        std, got = joint.std_by_name(), joint.as_dict()
        z += [abs(got[n] - truth[n]) / std[n] for n in ("c2", "c3")]
    assert len(z) >= 70
    assert 0.55 < np.median(z) < 0.8
    assert np.mean(np.array(z) <= 1.96) >= 0.9
