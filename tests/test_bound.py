"""The error budget's 95 % bound (solver/bound.py), its gravity-sag term, the robot-file key,
and the bound where a user reads it: ``solve``'s text and JSON, the report's top."""

from __future__ import annotations

import copy
import json
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given
from hypothesis import strategies as st
from scipy.special import ndtri
from scipy.stats import binom, truncnorm

from wirecal.app.coverage import trial, wilson
from wirecal.app.report import render_report
from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.robot_file import robot_file_text, robot_from_dict
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.accuracy import error_vs_truth_mm, workspace
from wirecal.solver.bound import (
    BOUND_PROBABILITY,
    DRAWS,
    SEED,
    ErrorModel,
    bound_mm,
    joined,
    low_discrepancy,
    mean_tool_error,
    truncated_model,
)
from wirecal.solver.box_gaussian import BoxGaussian
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.scale import ARM_PPM_PER_K
from wirecal.solver.simulate import Unmodelled, sag_lengths_mm
from wirecal.solver.solve import solve

from .conftest import VIPER

Z95 = 1.959964  # the normal's 97.5 % point: the half-normal's 95 % point


def _one_parameter_jacobian(size_mm: float, q: int = 5) -> np.ndarray:
    """J_p (q, 3, 1): one parameter moving the tool point ``size_mm`` per unit along x."""
    Jp = np.zeros((q, 3, 1))
    Jp[:, 0, 0] = size_mm
    return Jp


def test_mean_tool_error_is_the_mean_of_the_norms():
    # two configurations: the error (3, 4, 0)·δe and (0, 0, 2)·δe, δe = 2: norms 10 and 4
    Jp = np.array([[[3.0], [4.0], [0.0]], [[0.0], [0.0], [2.0]]])
    assert mean_tool_error(Jp, np.array([[2.0]]))[0] == pytest.approx(7.0, rel=1e-15)


def test_gaussian_alone_gives_the_half_normal_quantile():
    """E = 3 mm·|x|, x ~ N(0, 0.01²): the 95 % point is 1.96·0.03 mm, the median 0.6745·0.03
    mm (the quasi-random draws: within 1 %)."""
    model = ErrorModel(np.array([[1e-4]]), np.zeros(1), np.zeros((0, 1)))
    got = bound_mm(_one_parameter_jacobian(3.0), model)
    assert got == pytest.approx(Z95 * 0.03, rel=0.01)
    assert bound_mm(_one_parameter_jacobian(3.0), model) == got  # deterministic
    assert bound_mm(_one_parameter_jacobian(3.0), model, probability=0.5) == pytest.approx(
        0.6745 * 0.03, rel=0.01
    )


def test_a_singular_covariance_is_bounded_along_its_direction():
    """Σ = v·vᵀ, v = (0.01, 0.01); J_p sees only the first parameter, 2 mm per unit."""
    Jp = np.zeros((4, 3, 2))
    Jp[:, 1, 0] = 2.0
    model = ErrorModel(np.outer([0.01, 0.01], [0.01, 0.01]), np.zeros(2), np.zeros((0, 2)))
    assert bound_mm(Jp, model) == pytest.approx(Z95 * 0.02, rel=0.01)


def test_a_term_known_by_its_limits_is_uniform_within_them():
    """No Gaussian: E = 3 mm·|ε|·0.1, ε ~ U(−1, 1), so |ε| ~ U(0, 1) and the 95 % point is
    0.95·0.3 mm; a one-sided term between 0 and b (bias b/2, edge b/2) gives 0.95·b·3 mm
    (the quasi-random draws: within 1 %)."""
    Jp = _one_parameter_jacobian(3.0)
    model = ErrorModel(np.zeros((1, 1)), np.zeros(1), np.array([[0.1]]))
    assert bound_mm(Jp, model) == pytest.approx(0.95 * 0.3, rel=0.01)
    one_sided = ErrorModel(np.zeros((1, 1)), np.array([-0.04]), np.array([[-0.04]]))
    assert bound_mm(Jp, one_sided) == pytest.approx(0.95 * 0.08 * 3.0, rel=0.01)


@pytest.mark.parametrize(
    ("mean", "std"),
    [(1.0, 1.3), (-0.5, 0.4), (9.0, 0.3), (4.0, 30.0), (-30.0, 0.5), (4.0, 1.0)],
)
def test_one_box_restricted_gaussian_is_scipys_truncnorm(mean, std):
    """N(μ, σ²) restricted to [0, 8], one coordinate: the draws are truncnorm's quantiles
    at the probabilities, equally weighted; the moments truncnorm's (a fine grid of
    probabilities: to 1e-5). A flat coordinate is the uniform over the range."""
    post = BoxGaussian(np.array([mean]), np.array([[std**2]]), np.array([False]),
                       np.zeros(1), np.full(1, 8.0))  # fmt: skip
    ref = truncnorm(-mean / std, (8 - mean) / std, loc=mean, scale=std)
    u = np.array([[0.01], [0.3], [0.5], [0.95], [0.999]])
    t, w = post.sample(u)
    np.testing.assert_allclose(t[:, 0], ref.ppf(u[:, 0]), rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(w, 0.2, rtol=1e-12)
    grid = ((np.arange(100_000) + 0.5) / 100_000)[:, None]
    e, v = post.moments(grid)
    assert e[0] == pytest.approx(ref.mean(), rel=1e-5, abs=1e-7)
    assert v[0, 0] == pytest.approx(ref.var(), rel=1e-3, abs=1e-7)
    flat = replace(post, flat=np.array([True]))
    np.testing.assert_allclose(flat.sample(u)[0][:, 0], 8 * u[:, 0], rtol=1e-12)


def test_two_correlated_coordinates_in_a_box_against_a_grid():
    """N(μ, S) with correlation −0.9 restricted to [0, 8]²: the GHK draws' weighted mean and
    covariance against the density summed over a 1000 × 1000 grid of the box (to 2 %)."""
    mean, S = np.array([3.0, 9.0]), np.array([[4.0, -5.4], [-5.4, 9.0]])
    post = BoxGaussian(mean, S, np.array([False, False]), np.zeros(2), np.full(2, 8.0))
    e, cov = post.moments(low_discrepancy(2, DRAWS, SEED))
    x = (np.arange(1000) + 0.5) * 8 / 1000
    X = np.stack(np.meshgrid(x, x, indexing="ij"), axis=-1).reshape(-1, 2) - mean
    density = np.exp(-0.5 * np.einsum("ni,ij,nj->n", X, np.linalg.inv(S), X))
    density /= density.sum()
    ref_mean = density @ (X + mean)
    D = X + mean - ref_mean
    ref_cov = (D.T * density) @ D
    np.testing.assert_allclose(e, ref_mean, rtol=0.02)
    np.testing.assert_allclose(cov, ref_cov, rtol=0.02, atol=0.02 * np.max(np.diag(ref_cov)))


def test_a_box_restricted_term_gives_its_quantile_and_moments():
    """E = 2 mm·|t|, t ~ N(1, 1.3²) on [0, 8] (t ≥ 0): the bound is 2·its 95 % point (the
    quasi-random draws within 1 %); the second moment 4·E[t²]; joined with a Gaussian the
    terms stay independent (their second moments add); padding adds no error."""
    Jp = _one_parameter_jacobian(2.0)
    post = BoxGaussian(
        np.ones(1), np.array([[1.69]]), np.zeros(1, bool), np.zeros(1), np.full(1, 8.0)
    )
    model = truncated_model(np.ones((1, 1)), post)
    ref = truncnorm(-1 / 1.3, 7 / 1.3, loc=1.0, scale=1.3)
    assert bound_mm(Jp, model) == pytest.approx(2.0 * ref.ppf(0.95), rel=0.01)
    second = ref.var() + ref.mean() ** 2  # from the bound's 4,096 draws: to 0.5 %
    assert model.second_moment()[0, 0] == pytest.approx(second, rel=0.005)
    both = joined([model, ErrorModel(np.array([[0.04]]), np.zeros(1), np.zeros((0, 1)))])
    assert both.second_moment()[0, 0] == pytest.approx(model.second_moment()[0, 0] + 0.04)
    assert both.padded(3).second_moment()[:1, :1] == pytest.approx(both.second_moment())
    assert not np.any(both.padded(3).second_moment()[1:])


def test_two_uniform_terms_combine_not_at_their_corner():
    """E = ‖(0.3·ε1, 0.4·ε2)‖ with independent uniform ε: the 95 % point from a fine grid over
    the square (0.428 mm), below the corner's 0.5 mm."""
    Jp = np.zeros((2, 3, 2))
    Jp[:, 0, 0] = 1.0  # parameter 1 moves the tool point along x, parameter 2 along y
    Jp[:, 1, 1] = 1.0
    model = ErrorModel(np.zeros((2, 2)), np.zeros(2), np.array([[0.3, 0.0], [0.0, 0.4]]))
    e = (np.arange(2000) + 0.5) / 1000.0 - 1.0  # midpoints of a 2000 × 2000 grid
    expected = np.quantile(np.hypot(0.3 * e[:, None], 0.4 * e[None, :]), 0.95)
    assert expected == pytest.approx(0.4276, abs=1e-4)
    assert bound_mm(Jp, model) == pytest.approx(expected, rel=0.01)


def test_gaussian_and_uniform_terms_are_drawn_jointly():
    """E = |x + ε·a| mm, x ~ N(0, 0.02²), a = 0.05: P(E ≤ t) = mean over ε of
    Φ((t − aε)/σ) − Φ((−t − aε)/σ); its 95 % point by bisection (scipy's normal)."""
    from scipy.stats import norm

    Jp = _one_parameter_jacobian(1.0)
    model = ErrorModel(np.array([[0.02**2]]), np.zeros(1), np.array([[0.05]]))
    eps = (np.arange(4000) + 0.5) / 2000.0 - 1.0
    lo, hi = 0.0, 0.2
    for _ in range(60):
        t = (lo + hi) / 2
        p = np.mean(norm.cdf((t - 0.05 * eps) / 0.02) - norm.cdf((-t - 0.05 * eps) / 0.02))
        lo, hi = (t, hi) if p < 0.95 else (lo, t)
    assert bound_mm(Jp, model) == pytest.approx(lo, rel=0.015)  # 2-D draws: 1.2 % here


def test_second_moment_by_hand():
    """cov + b·bᵀ + the uniform's variance 1/3 per edge: diag(0.3²/3, 0.4²/3) here."""
    b = np.array([0.1, -0.2])
    model = ErrorModel(np.eye(2) * 0.01, b, np.array([[0.3, 0.0], [0.0, 0.4]]))
    expected = np.array([[0.01 + 0.01 + 0.03, -0.02], [-0.02, 0.01 + 0.04 + 0.16 / 3]])
    np.testing.assert_allclose(model.second_moment(), expected, rtol=1e-12)


def test_bound_is_the_draws_quantile_by_brute_force():
    """The blocked single-precision evaluation against every norm taken in double precision
    at once (all draws × configurations, no blocks), over the same draws (Gaussian
    coordinates first, then 2u − 1 for the two uniform terms): 60 configurations."""
    rng = np.random.default_rng(3)
    q, m = 60, 4
    Jp = rng.normal(size=(q, 3, m))
    root = rng.normal(size=(m, m)) * 0.1
    edges = rng.normal(size=(2, m)) * 0.2
    bias = -edges.sum(axis=0)
    model = ErrorModel(root @ root.T, bias, edges)
    w, U = np.linalg.eigh(model.cov)
    u = low_discrepancy(m + 2, DRAWS, SEED)
    de = ndtri(u[:, :m]) @ (U * np.sqrt(np.clip(w, 0, None))).T + bias + (2 * u[:, m:] - 1) @ edges
    E = np.linalg.norm(np.einsum("kim,dm->dki", Jp, de), axis=2).mean(axis=1)
    assert bound_mm(Jp, model) == pytest.approx(np.quantile(E, BOUND_PROBABILITY), rel=1e-5)


@pytest.fixture(scope="module")
def still(viper):
    """The Viper with an ideal encoder file (no tolerance, drum as the arm), sagging as declared."""
    return replace(
        viper,
        encoder=replace(
            viper.encoder, scale_tolerance_ppm=0.0, temperature_coefficient_ppm_per_k=ARM_PPM_PER_K
        ),
    )


def test_sag_lengths_vanish_without_sag_and_scale_with_it(still, paper_plan):
    assert not np.any(sag_lengths_mm(replace(still, gravity_sag_deg_per_m=0.0), paper_plan))
    once = sag_lengths_mm(still, paper_plan)
    twice = sag_lengths_mm(replace(still, gravity_sag_deg_per_m=0.02), paper_plan)
    # 0.01 deg/m at the Viper's reach (≈ 0.6 m): some hundredths of a mm of wire
    assert 0.02 < np.max(np.abs(once)) < 0.1
    np.testing.assert_allclose(twice, 2 * once, rtol=1e-3, atol=1e-6)


def test_the_sag_term_predicts_what_the_sag_alone_does(still, paper_plan):
    """No noise, an ideal encoder, the twin's sag (0.01 deg/m) alone: the joint estimate's
    tool-point error is the budget's sag at the declared sag (the term is the RMS of the
    uniform between none and it: 1/√3 of that), ±30 % (0.062 and 0.073 mm against 0.057:
    the linearisation at the nominal arm), and below the bound. The sag turns the joints the
    way gravity pulls (its sign changes where the wrist crosses the joint's vertical), so
    the parameters absorb less of it than of a sag of one sign: the residual's σ sees the
    rest (0.09 mm), also when the file declares no sag."""
    sagging = Unmodelled(repeatability_mm=0.0, compliance_deg_per_m=0.01)
    q = workspace(still)
    for seed in (1, 2):
        truth = random_errors(still, 1.0, np.random.default_rng([seed, 1]))
        text = simulate_log(still, paper_plan, truth, seed=seed, noise_mm=0.0, unmodelled=sagging)
        m = check_log(parse_log(text, "sag.csv"), paper_plan, still)
        result = solve(still, paper_plan, m)
        err = error_vs_truth_mm(still, truth, result.estimates["joint"].as_dict(), q)
        b = result.budgets["joint"]
        assert err == pytest.approx(np.sqrt(3) * b.terms["sag"], rel=0.3)
        assert err <= b.bound
        blind = solve(replace(still, gravity_sag_deg_per_m=0.0), paper_plan, m).budgets["joint"]
        assert blind.terms["sag"] == 0
        assert err <= blind.bound


BASE = tomllib.loads((VIPER / "robot.toml").read_text())


@pytest.mark.parametrize(
    ("value", "problem"),
    [
        (-0.001, "give a number between 0 and 1 deg/m"),
        (1.5, "give a number between 0 and 1 deg/m"),
        ("0.01", "give a number between 0 and 1 deg/m"),
    ],
)
def test_gravity_sag_key_is_checked(value, problem):
    data = copy.deepcopy(BASE)
    data["calibration"]["gravity_sag_deg_per_m"] = value
    with pytest.raises(WirecalError) as info:
        robot_from_dict(data, "r.toml")
    assert any(
        p.startswith("r.toml: calibration.gravity_sag_deg_per_m:") and problem in p
        for p in info.value.problems
    ), info.value.problems


@pytest.mark.parametrize(("value", "written"), [(0.01, False), (0.0, True), (0.05, True)])
def test_gravity_sag_key_reads_and_writes_back(value, written):
    """Default 0.01 deg/m (the twin's); another value is written back, the default is not."""
    data = copy.deepcopy(BASE)
    data["calibration"]["gravity_sag_deg_per_m"] = value
    robot = robot_from_dict(data, "r.toml")
    assert robot.gravity_sag_deg_per_m == value
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    assert ("gravity_sag_deg_per_m" in text) is written
    assert robot_from_dict(tomllib.loads(text), "again.toml").gravity_sag_deg_per_m == value
    assert robot_from_dict(BASE, "r.toml").gravity_sag_deg_per_m == 0.01


def test_solve_prints_the_bound_beside_the_mean(tmp_path):
    robot, plan = str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")
    runner = CliRunner()
    log = tmp_path / "run.csv"
    assert (
        runner.invoke(main, ["simulate", robot, plan, "-o", str(log), "--seed", "2"]).exit_code == 0
    )
    text = runner.invoke(main, ["solve", robot, plan, str(log)])
    assert text.exit_code == 0, text.output
    rows = {line[:15].strip(): line[15:39].split() for line in text.output.splitlines()}
    bounds = np.array(rows["95 % bound"], dtype=float)  # stepwise, joint
    assert np.all(bounds > np.array(rows["total"], dtype=float))
    assert float(rows["gravity sag"][1]) > 0
    data = json.loads(runner.invoke(main, ["solve", robot, plan, str(log), "--json"]).output)
    joint = data["encoder"]["budget"]["joint"]
    assert joint["bound95_mm"] == pytest.approx(bounds[1], abs=5e-5)
    assert joint["terms_mm"]["sag"] == pytest.approx(float(rows["gravity sag"][1]), abs=5e-5)


@pytest.fixture(scope="module")
def seeded_result(viper, paper_plan):
    """The Viper's paper plan simulated with random errors (seed 5) and solved, once."""
    truth = random_errors(viper, 1.0, np.random.default_rng(5))
    text = simulate_log(viper, paper_plan, truth, seed=5)
    return solve(viper, paper_plan, check_log(parse_log(text, "s.csv"), paper_plan, viper))


def test_report_opens_with_the_verdict_and_the_bound(seeded_result):
    result = seeded_result
    html = render_report(result, plausibility="passed (residual fine)")
    best = result.budgets[result.recommended]
    top = html[: html.index("<h2>Identified parameters</h2>")]
    assert "<h2>Verdict</h2>" in top
    assert "Plausibility gate: <b>passed (residual fine)</b>" in top
    assert f"below\n{best.bound:.3f} mm with 95 % probability" in top
    assert html.index("<h2>Verdict</h2>") < html.index("<h2>Error budget</h2>")


def test_wilson_interval_by_hand():
    # 285/300, z = 1.96: centre (0.95 + 1.96²/600)/(1 + 1.96²/300) = 0.94431,
    # half-width 1.96·√(0.95·0.05/300 + 1.96²/360000)/(1 + 1.96²/300) = 0.02516
    lo, hi = wilson(285, 300)
    assert lo == pytest.approx(0.91915, abs=1e-4)
    assert hi == pytest.approx(0.96947, abs=1e-4)
    assert wilson(300, 300)[1] == pytest.approx(1.0, abs=1e-12)


@pytest.mark.slow
def test_the_bound_covers_simulated_calibrations_with_unmodelled_errors(viper, paper_plan):
    """30 realistic calibrations with a gauge, the twin's repeatability and sag on (the
    bench's hardest case, 300 of 300 covered): at least 28 covered. Were the coverage 80 %,
    28 or more of 30 would happen with probability 4.4 %; with the sag left out of the budget
    13 of 20 were covered. (The seeds are fixed: the test is deterministic.)"""
    gauge = replace(
        viper,
        encoder=replace(
            viper.encoder,
            reference_length_mm=500.0,
            reference_uncertainty_mm=0.002,
            reference_repeats=3,
        ),
    )
    runs = [trial(gauge, paper_plan, seed, Unmodelled()) for seed in range(1, 31)]
    assert binom.sf(27, 30, 0.8) == pytest.approx(0.044, abs=0.001)
    assert sum(r.error_mm <= r.bound_mm for r in runs) >= 28
    assert all(r.bound_mm > r.mean_mm for r in runs)


@pytest.mark.parametrize(
    ("ratio", "best"), [(0.9, "joint"), (1 / 1.36 + 1e-6, "joint"), (0.7, "stepwise")]
)
def test_a_near_tie_goes_to_the_joint_method(seeded_result, ratio, best):
    """The stepwise budget falls short by up to 1.36× (bench_encoder): the stepwise method is
    recommended only when its predicted mean is below the joint's / 1.36 (the UR5 demo's
    0.2880 against 0.2891 mm, both the scale at its edge, is a tie)."""
    result = seeded_result
    predicted = {"joint": {"mean": 0.3, "max": 0.5}, "stepwise": {"mean": 0.3 * ratio, "max": 0.5}}
    assert replace(result, predicted=predicted).recommended == best


@given(st.floats(min_value=0.0, max_value=1.0, allow_nan=False))
def test_gravity_sag_key_round_trips_any_valid_value(value):
    """Read back within the writer's TIDY, 1e-11 (it writes the shortest decimal within it)."""
    data = copy.deepcopy(BASE)
    data["calibration"]["gravity_sag_deg_per_m"] = value
    robot = robot_from_dict(data, "r.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    again = robot_from_dict(tomllib.loads(text), "again.toml").gravity_sag_deg_per_m
    assert abs(again - value) <= 1e-11
