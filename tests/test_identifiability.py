"""Identifiability: θ1 and the base row never observable, the tool point redundant with
th6/d6, the paper's 10 parameters identifiable from its plan; O1–O5 by their formulas."""

from __future__ import annotations

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.identifiability import (
    TALL_ROWS,
    analyse,
    observability_indices,
    right_svd,
    select_columns,
)


def test_th1_unobservable_from_any_points(viper):
    rng = np.random.default_rng(7)
    q = rng.uniform(viper.joint_min_deg, viper.joint_max_deg, (40, 6))
    result = analyse(viper.nominal, q, q[0] + 5.0, ["th1", "th2", "a2"])
    assert result.unobservable == ("th1",)
    assert result.rank == 2


def test_full_analysis_names_every_redundancy(viper, paper_plan):
    q, _, _ = paper_plan.all_points()
    names = P.all_names(6, with_tool=True)
    result = analyse(viper.nominal, q, paper_plan.theta0_deg, names)
    assert set(result.unobservable) == {"al0", "a0", "th1", "d1"}
    combos = {frozenset(n for n, _ in c): dict(c) for c in result.combinations}
    assert frozenset({"d2", "d3"}) in combos  # joints 2 and 3 are parallel
    assert frozenset({"d6", "tool_z"}) in combos
    th6_ty = combos[frozenset({"th6", "tool_y"})]
    # ∂p/∂th6 = z6 × R6·t = R6·(−t_y, t_x, 0) = −60·R6·e_y per rad: 1 deg ≡ −1.047 mm of t_y
    assert abs(th6_ty["tool_y"] / th6_ty["th6"] - np.pi / 180 * 60) < 1e-6
    assert result.rank == len(names) - 7
    text = "\n".join(result.describe())
    assert "th1 is unobservable: it moves every calibration point and the encoder" in text


def test_paper_parameters_identifiable(viper, paper_plan):
    q, _, _ = paper_plan.all_points()
    result = analyse(viper.nominal, q, paper_plan.theta0_deg, viper.parameters)
    assert result.rank == 10
    assert not result.unobservable
    assert not result.combinations
    assert result.indices["O3"] > 0.5
    assert "Every parameter is identifiable" in "\n".join(result.describe())


def test_point_set_that_cannot_see_a_parameter(viper):
    q = np.array([[0, -90, 210, -90, 26, a] for a in (-10, 0, 10, 20)], dtype=float)
    result = analyse(viper.nominal, q, np.array([0, -90, 210, -90, 0, -90.0]), ["th6", "a2"])
    assert result.unobservable == ("a2",)
    assert "a2 is unobservable: no wire length of these points depends on it" in "\n".join(
        result.describe()
    )


def test_observability_indices_formulas():
    s = np.array([4.0, 2.0, 1.0])
    o = observability_indices(s, 9)
    assert np.isclose(o["O1"], 2.0 / 3.0)  # (4·2·1)^(1/3) / √9
    assert np.isclose(o["O2"], 0.25)
    assert np.isclose(o["O3"], 1.0)
    assert np.isclose(o["O4"], 0.25)
    assert np.isclose(o["O5"], 1 / 1.75)
    assert observability_indices(np.array([3.0, 0.0]), 5)["O1"] == 0.0


def test_select_columns_drops_a_column_zero_to_round_off():
    """A column of round-off (1e-17 of the others: θ6 with the tool on its axis) is zero,
    not a unit column of any direction: it is left out as degenerate, by name, and the
    columns after it are chosen as without it."""
    rng = np.random.default_rng(0)
    J = rng.normal(size=(40, 4))
    J[:, 2] = 1e-17 * rng.normal(size=40)
    names = ("a", "b", "th6", "d")
    sel = select_columns(J, names, 1)
    assert sel.kept == (0, 1, 3)
    assert [n for n, _ in sel.dropped] == ["th6"]
    assert sel.dropped[0][1] == "degenerate: +1·th6 changes no length"
    with_noise = select_columns(J, names, 1, sigma_mm=0.01, max_std=10.0)
    assert with_noise.kept == (0, 1, 3)


def test_select_columns_refuses_a_column_the_covariance_does_not_identify():
    """A column 1e-5 of another plus 1e-10 of a third direction: of unit length, its
    direction differs by 1e-5 (the rank test passes), but JᵀJ sees it 1e-10 below the
    largest, under RANK_RTOL: the covariance does not identify it, so it is left out
    even with no σ limit (its restricted σ would be finite, not the truth)."""
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=30), rng.normal(size=30)
    J = np.column_stack([a, 1e-5 * a + 1e-10 * b])
    sel = select_columns(J, ("p", "q"), 1, sigma_mm=0.01)
    assert sel.kept == (0,)
    assert sel.dropped[0][0] == "q"
    assert sel.dropped[0][1].startswith("not identified: nearly ")


def test_a_tall_jacobians_svd_through_its_r_is_the_direct_one_bit_for_bit():
    """right_svd of a tall J goes through J = QR: LAPACK's own first step for it, so the
    singular values and right vectors are those of the SVD of J itself, bit for bit (the
    covariances and null spaces of long fits unchanged by it)."""
    rng = np.random.default_rng(4)
    for rows, cols in ((TALL_ROWS, 23), (5000, 30), (3000, 7)):
        J = rng.normal(size=(rows, cols)) * rng.uniform(0.01, 100.0, cols)
        J[:, -1] = J[:, -2]  # a null direction too
        s, vt = right_svd(J)
        _, s_direct, vt_direct = np.linalg.svd(J, full_matrices=False)
        assert np.array_equal(s, s_direct)
        assert np.array_equal(vt, vt_direct)
