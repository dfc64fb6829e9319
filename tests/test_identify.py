"""Identification: the step-by-step solver is the paper's algorithm; the joint method
recovers truth from exact data and reaches the Cramér–Rao bound under noise."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from wirecal.solver import montecarlo
from wirecal.solver.accuracy import crb, noise_covariance
from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.identify import Problem, joint, omega_vector, run_stepwise, stepwise
from wirecal.solver.kinematics import with_errors
from wirecal.solver.params import ErrorSet
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.simulate import measured_lengths

from .conftest import TABLE5


def make_problem(robot, plan, d):
    q, step, _ = plan.all_points()
    return Problem(robot.nominal, plan.order, np.radians(q), np.radians(plan.theta0_deg), d, step)


def exact_lengths(robot, plan, truth_internal):
    q, _, _ = plan.all_points()
    model = with_errors(robot.nominal, plan.order, truth_internal)
    return wire_lengths(model, np.radians(q), np.radians(plan.theta0_deg))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_joint_recovers_truth_from_exact_lengths(viper, paper_plan, seed):
    errors = ErrorSet(paper_plan.order, 6)
    truth = errors.to_internal(np.random.default_rng(seed).uniform(-1, 1, 10))
    problem = make_problem(viper, paper_plan, exact_lengths(viper, paper_plan, truth))
    x0, _ = stepwise(problem, omega_vector(paper_plan.order, 6, paper_plan))
    est = joint(problem, x0)
    np.testing.assert_allclose(est.values, errors.to_boundary(truth), atol=1e-9)
    assert est.residual_rms_mm < 1e-9


def test_quantisation_only_within_its_own_bound(viper, paper_plan):
    """Counts quantised at 0.025488 mm, no other noise: the joint errors stay within
    4σ of the bound that quantisation alone implies (≈1e-2 for a1/a3: the count is
    coarse, so 1e-3 is out of reach on 69 points)."""
    errors = ErrorSet(paper_plan.order, 6)
    truth = errors.to_internal([TABLE5[n] for n in paper_plan.order])
    rng = np.random.default_rng(3)
    mpc = viper.encoder.mm_per_count
    d = measured_lengths(
        with_errors(viper.nominal, paper_plan.order, truth), paper_plan, mpc, 0.0, rng
    )
    problem = make_problem(viper, paper_plan, d)
    x0, _ = stepwise(problem, omega_vector(paper_plan.order, 6, paper_plan))
    est = joint(problem, x0)
    J = wire_jacobian(
        with_errors(viper.nominal, paper_plan.order, truth),
        problem.q,
        problem.q0,
        paper_plan.order,
    )[1]
    sq = mpc / np.sqrt(12)
    sd = errors.to_boundary(np.sqrt(np.diag(crb(J, noise_covariance(69, sq, sq / np.sqrt(10))))))
    err = est.values - errors.to_boundary(truth)
    assert np.all(np.abs(err) <= 4 * sd), (err, sd)
    assert np.all(sd < 0.012)


def test_each_step_is_the_papers_bounded_scalar_minimisation(viper, paper_plan):
    """Step j minimises Σ_{S_j}(d_i − d̃_i)² over δe_j ∈ Ω_j with earlier parameters at
    their estimates and later ones at nominal: checked against scipy's bounded Brent."""
    errors = ErrorSet(paper_plan.order, 6)
    truth = errors.to_internal([TABLE5[n] for n in paper_plan.order])
    rng = np.random.default_rng(8)
    d = measured_lengths(
        with_errors(viper.nominal, paper_plan.order, truth),
        paper_plan,
        viper.encoder.mm_per_count,
        0.01,
        rng,
    )
    problem = make_problem(viper, paper_plan, d)
    omega = omega_vector(paper_plan.order, 6, paper_plan)
    x, _ = stepwise(problem, omega)
    for j in range(10):
        sel = problem.step == j + 1

        def cost(v, j=j, sel=sel):
            e = np.concatenate([x[:j], [v], np.zeros(9 - j)])  # later ones at nominal
            dist = wire_lengths(
                with_errors(problem.base, problem.names, e), problem.q[sel], problem.q0
            )
            return float(np.sum((dist - d[sel]) ** 2))

        ref = minimize_scalar(
            cost, bounds=(-omega[j], omega[j]), method="bounded", options={"xatol": 1e-12}
        )
        assert abs(x[j] - ref.x) < 1e-7, paper_plan.order[j]
        assert cost(x[j]) <= ref.fun * (1 + 1e-9) + 1e-15


def test_order_respected_later_data_cannot_change_earlier_steps(viper, paper_plan):
    errors = ErrorSet(paper_plan.order, 6)
    truth = errors.to_internal([TABLE5[n] for n in paper_plan.order])
    d = exact_lengths(viper, paper_plan, truth)
    problem = make_problem(viper, paper_plan, d)
    omega = omega_vector(paper_plan.order, 6, paper_plan)
    x, _ = stepwise(problem, omega)
    later = problem.step >= 6
    d2 = d.copy()
    d2[later] += np.random.default_rng(0).normal(0, 0.5, later.sum())
    x2, _ = stepwise(make_problem(viper, paper_plan, d2), omega)
    np.testing.assert_array_equal(x[:5], x2[:5])
    assert np.all(x[5:] != x2[5:])


def test_each_steps_cost_depends_on_its_parameter_only_at_isolating_points(viper, paper_plan):
    """On the corrected plan, every later parameter's Ψ at a step's points is tiny next to
    the step's own: perturbing a later parameter barely moves the step's cost minimum,
    exactly as the leak coefficient predicts."""
    q, step, _ = paper_plan.all_points()
    psi = sensitivity(viper.nominal, q, paper_plan.theta0_deg, paper_plan.order).psi
    for j in range(9):
        sel = step == j + 1
        own = np.sum(psi[sel, j] ** 2)
        for t in range(j + 1, 10):
            assert abs(psi[sel, j] @ psi[sel, t]) / own < 0.1


def test_bound_hit_is_reported(viper, paper_plan):
    errors = ErrorSet(paper_plan.order, 6)
    truth = errors.to_internal([TABLE5[n] for n in paper_plan.order])  # th6 = −1.215 deg
    problem = make_problem(viper, paper_plan, exact_lengths(viper, paper_plan, truth))
    omega = omega_vector(paper_plan.order, 6, paper_plan, default=0.5)
    psi = sensitivity(
        viper.nominal, np.degrees(problem.q), paper_plan.theta0_deg, paper_plan.order
    ).psi
    est = run_stepwise(problem, omega, psi)
    th6 = est.steps[0]
    assert th6.parameter == "th6"
    assert th6.on_bound
    assert th6.estimate == pytest.approx(-0.5)
    assert th6.omega == pytest.approx(0.5)
    assert est.steps[2].on_bound
    assert est.steps[2].estimate == pytest.approx(-0.5)
    assert not est.steps[3].on_bound  # th4 = 0.245 lies inside Ω


def test_batched_equals_one_at_a_time(viper, paper_plan):
    errors = ErrorSet(paper_plan.order, 6)
    rng = np.random.default_rng(4)
    truths = errors.to_internal(rng.uniform(-1, 1, (5, 10)))
    d = measured_lengths(
        with_errors(viper.nominal, paper_plan.order, truths),
        paper_plan,
        viper.encoder.mm_per_count,
        0.01,
        rng,
    )
    omega = omega_vector(paper_plan.order, 6, paper_plan)
    batch, _ = stepwise(make_problem(viper, paper_plan, d), omega)
    for t in range(5):
        single, _ = stepwise(make_problem(viper, paper_plan, d[t]), omega)
        np.testing.assert_allclose(batch[t], single, atol=1e-12)


def test_joint_reaches_the_cramer_rao_bound(viper, paper_plan):
    """σ = 0.01 mm on the corrected paper plan: the joint method's mean tool-point error
    is within 1.5× of the bound's (measured ≈1.04× in bench/bench_identification.py)."""
    truths = np.tile([TABLE5[n] for n in paper_plan.order], (60, 1))
    mc = montecarlo.run(viper, paper_plan, truths, noise_mm=0.01, seed=11, n_workspace=300)
    ratio = mc.methods["joint"].tool_mean_mm / mc.crb.tool_mean_mm
    assert ratio <= 1.5, ratio
    assert mc.methods["stepwise"].tool_mean_mm > 3 * mc.methods["joint"].tool_mean_mm


def test_stepwise_diagnostics_per_step_and_data_set(viper, paper_plan):
    """Per step: its point count, iterations, and a residual RMS that the step's own
    estimate lowers in every data set (the cost never increases)."""
    truth = ErrorSet(paper_plan.order, 6).to_internal([TABLE5[n] for n in paper_plan.order])
    d = exact_lengths(viper, paper_plan, truth)
    noisy = d + np.random.default_rng(3).normal(0, 0.01, (4, d.size))
    _, info = stepwise(
        make_problem(viper, paper_plan, noisy), omega_vector(paper_plan.order, 6, paper_plan)
    )
    _, step, _ = paper_plan.all_points()
    assert [s.n_points for s in info] == [int(np.sum(step == j + 1)) for j in range(10)]
    for s in info:
        assert s.rms_before_mm.shape == s.rms_after_mm.shape == (4,)
        assert np.all(s.rms_after_mm <= s.rms_before_mm)
        assert 1 <= s.iterations <= 50
