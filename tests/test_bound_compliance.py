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
from wirecal.solver.budget import ComplianceTerms, budget, compliance_errors, sources
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


def test_an_unidentified_compliance_is_uniform_between_the_file_and_the_prior(ur5e):
    """c_u ~ U(0, p) beyond the file's value: E[c_u²] = p²/3, and the error over the
    parameters and the compliance is G·c_u, G = [M·J_u; −1]: second moment G·Gᵀ·p²/3."""
    rng = np.random.default_rng(1)
    q = workspace(ur5e, 20)
    m, n = 3, 12
    M, wire = rng.normal(size=(m, n)), rng.normal(size=(n, 1))
    prior = 8e-6  # rad/(N·m)
    terms = ComplianceTerms(np.zeros(m), ("c4",), wire, np.array([prior]), np.zeros(1))
    Jp = tool_jacobian(ur5e.nominal, q, ("a2", "a3", "d4"))[1]
    Jx, unseen = compliance_errors(ur5e.nominal, q, Jp, M, terms)
    G = np.concatenate([M @ wire[:, 0], [-1.0]])
    np.testing.assert_allclose(unseen.second_moment(), np.outer(G, G) * prior**2 / 3, rtol=1e-12)
    np.testing.assert_allclose(Jx[:, :, :m], Jp, rtol=0)
    np.testing.assert_allclose(Jx[:, :, m], tool_jacobian(ur5e.nominal, q, ("c4",))[1][:, :, 0])


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
