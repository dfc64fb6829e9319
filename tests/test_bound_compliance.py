"""The compliances in the error budget (one rule with the bound) and the sag in the report."""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import numpy as np
import pytest

from wirecal.app.coverage import with_gauge
from wirecal.app.report import render_report, sag_summary
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import robot_from_dict
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.accuracy import rms_tool_error, workspace
from wirecal.solver.bound import DRAWS, SEED, low_discrepancy
from wirecal.solver.budget import (
    ComplianceTerms,
    budget,
    compliance_errors,
    compliance_likelihood,
    sources,
)
from wirecal.solver.compliance import workspace_sag
from wirecal.solver.kinematics import tool_jacobian
from wirecal.solver.log.measurements import check_log
from wirecal.solver.simulate import Unmodelled, realistic_encoder
from wirecal.solver.solve import solve

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture(scope="module")
def ur5e():
    """The UR5e (UR's masses) asking for c2..c5: its plan identifies c2 and c3."""
    data = tomllib.loads((EXAMPLES / "ur5e" / "robot.toml").read_text())
    data = copy.deepcopy(data)
    data["calibration"]["compliances"] = ["c2", "c3", "c4", "c5"]
    return robot_from_dict(data, "ur5e.toml")


def _src(sigma_mm: float, n: int):
    """Sources with the reading noise alone (a measured, exact scale; no times, no zeros)."""
    return sources(sigma_mm, np.zeros(n), 0.0, True, 0.0, None, None, None,
                   np.zeros(n), np.zeros(n))  # fmt: skip


def test_a_compliance_the_readings_cannot_separate_keeps_its_prior(ur5e):
    """A compliance whose wire column is a combination of the geometry's says nothing: its
    posterior is the prior, U(0, p) beyond the file's value, E[c_u²] = p²/3, and the error
    over the parameters and the compliance is G·c_u, G = [M·J_u; −1]: second moment
    G·Gᵀ·p²/3 (the bound's 4,096 draws: to 0.5 %)."""
    rng = np.random.default_rng(1)
    q = workspace(ur5e, 20)
    m, n = 3, 12
    J = rng.normal(size=(n, m))
    M, wire = np.linalg.pinv(J), J @ np.array([[0.3], [-1.0], [2.0]])
    prior = 8e-6  # rad/(N·m)
    residual = rng.normal(0.0, 0.01, n)
    span = np.array([[0.0], [prior]])  # offsets 0 to p from the file's value
    terms = ComplianceTerms(np.zeros(m), ("c4",), wire, span, np.zeros(1), residual)
    Jp = tool_jacobian(ur5e.nominal, q, ("a2", "a3", "d4"))[1]
    Jx, unseen = compliance_errors(ur5e.nominal, q, (Jp, J, M), terms, _src(0.01, n))
    G = np.concatenate([M @ wire[:, 0], [-1.0]])
    np.testing.assert_allclose(unseen.second_moment(), np.outer(G, G) * prior**2 / 3, rtol=0.005)
    np.testing.assert_allclose(Jx[:, :, :m], Jp, rtol=0)
    np.testing.assert_allclose(Jx[:, :, m], tool_jacobian(ur5e.nominal, q, ("c4",))[1][:, :, 0])


def test_what_the_readings_say_of_an_unidentified_compliance(ur5e):
    """Lengths d = J·e + w·c + noise, fitted without c: the residual says ĉ = −B·r, B the
    compliance's row of [J, w]⁺, with σ²·[(AᵀA)⁻¹]_cc, A = [J, w] (computed here by
    numpy's inverse); noise-free, ĉ is the truth. Its posterior with a sharp likelihood
    inside the range is that Gaussian; at the range's edge a half-Gaussian (mean 0.798 σ
    above the edge)."""
    rng = np.random.default_rng(4)
    n, m = 40, 3
    J, w = rng.normal(size=(n, m)), rng.normal(size=(n, 1))
    A = np.hstack([J, w])
    for truth in (3e-6, 0.0):
        d = J @ rng.normal(size=m) + w[:, 0] * truth
        e_fit = np.linalg.lstsq(J, d, rcond=None)[0]
        residual = J @ e_fit - d  # model − measured, the compliance left out of the fit
        span = np.array([[0.0], [8e-6]])
        terms = ComplianceTerms(np.zeros(m), ("c4",), w, span, np.zeros(1), residual)
        post = compliance_likelihood(J, terms, _src(1e-7, n))
        sigma = 1e-7 * np.sqrt(np.linalg.inv(A.T @ A)[m, m])
        assert post.mean[0] == pytest.approx(truth, abs=1e-12)
        assert post.cov[0, 0] == pytest.approx(sigma**2, rel=1e-9)
        mean, _ = post.moments(low_discrepancy(1, DRAWS, SEED))
        expected = truth + (0.7979 * sigma if truth == 0 else 0.0)  # √(2/π)·σ at the edge
        assert mean[0] == pytest.approx(expected, abs=0.01 * sigma)
        assert not post.flat[0]


def test_workspace_sag_is_removed_by_compensating_every_compliance(ur5e):
    """c2 = c3 = 5 µrad/(N·m): a sag of tens of µm; compensated it vanishes (to 1e-9 mm);
    compensating c2 alone leaves c3's (to 2e-5 mm: c3's sag at the joints moved by c2's
    compensation, second order); the sag doubles with the compliance (to 1e-3)."""
    q = workspace(ur5e, 200)
    bent = ur5e.model({"c2": 5.0, "c3": 5.0})
    sag = workspace_sag(bent, [1, 2], q)
    assert 0.005 < sag.before_mm.mean() < 0.5
    assert sag.after_mm.max() < 1e-9
    partial = workspace_sag(bent, [1], q)
    alone = workspace_sag(ur5e.model({"c3": 5.0}), [], q)
    np.testing.assert_allclose(partial.after_mm, alone.before_mm, rtol=0, atol=2e-5)
    double = workspace_sag(ur5e.model({"c2": 10.0, "c3": 10.0}), [], q)
    np.testing.assert_allclose(double.before_mm, 2 * sag.before_mm, rtol=1e-3)


@pytest.mark.slow
def test_a_compliant_calibration_reports_its_sag_and_the_budget_its_compliances(ur5e):
    """A simulated compliant UR5e with a gauge: the budget lists the unidentified
    compliances' term, the report the sag before (tens of µm) and after (c4 and c5 at the
    file's 0: none left) and both bounds."""
    robot = with_gauge(ur5e)
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    truth = random_errors(robot, 1.0, np.random.default_rng([3, 1]))
    encoder = realistic_encoder(robot.encoder, np.random.default_rng([3, 4]))
    text = simulate_log(robot, plan, truth, seed=3, encoder=encoder, unmodelled=Unmodelled(0.02))
    result = solve(robot, plan, check_log(parse_log(text, "run"), plan, robot))
    joint = result.budgets["joint"]
    assert 0 < joint.terms["compliance"] < joint.total
    # c4, c5 not identified: their posterior lies in the stated 2–8 µrad/(N·m), no wider
    # than the uniform's σ 6/√12 = 1.73 (the readings can only narrow it).
    assert set(joint.posterior) == {"c4", "c5"}
    for value, sd in joint.posterior.values():
        assert 2.0 < value < 8.0
        assert 0.0 < sd < 1.74
    said = joint.as_json()["compliances_not_identified_urad_per_nm"]
    assert said["c4"]["value"] == joint.posterior["c4"][0]
    assert "compliance" not in result.budgets["stepwise"].terms
    sag = sag_summary(result)
    assert sag is not None
    assert 0.005 < sag["before_mean"] < sag["before_max"] < 1.0
    assert sag["after_max"] < 1e-9
    assert 0 < sag["sigma"] < sag["before_mean"]
    html = render_report(result)
    assert "Sag under gravity, before and after compensation" in html
    assert "compliances not identified" in html
    assert "95 % bound, targets compensated offline" in html


def test_the_zero_reference_enters_every_length(ur5e):
    """Every length is read from the mean of ``zeros`` zero readings: a common error of
    σ/√zeros, δe = z·M·1, and the zero read long by u ~ U(0, 1.5958·σ) (E‖δp‖ of a 3-D
    Gaussian: 2·√(2/π)·σ), every length as much short: the noise term's second moment gains
    (σ²/zeros + E[u²])·(M·1)(M·1)ᵀ, E[u²] = (1.5958·σ)²/3."""
    rng = np.random.default_rng(2)
    names = ("a2", "a3", "d4")
    J = rng.normal(size=(30, 3))
    q = workspace(ur5e, 50)

    def noise_mm(zeros: int) -> float:
        src = sources(0.01, np.zeros(30), 0.0, True, 0.0, None, None, None,
                      np.zeros(30), np.zeros(30), zeros)  # fmt: skip
        return budget(ur5e.nominal, names, J, None, src, q).terms["noise"]

    M = np.linalg.pinv(J)
    cov = 0.01**2 * np.linalg.inv(J.T @ J)
    ones = M.sum(axis=1)
    Jp = tool_jacobian(ur5e.nominal, q, names)[1]
    long_zero = (1.5957691 * 0.01) ** 2 / 3
    expected = rms_tool_error(Jp, cov + (0.01**2 / 4 + long_zero) * np.outer(ones, ones)).mean_mm
    assert noise_mm(4) == pytest.approx(expected, rel=1e-7)  # the constant to 8 digits
    assert noise_mm(0) == pytest.approx(rms_tool_error(Jp, cov).mean_mm, rel=1e-9)
