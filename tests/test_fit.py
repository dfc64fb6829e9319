"""``wirecal fit``: the cable model with the anchor anywhere, sessions, outliers, held-out
validation — on simulated tables whose truth the generator knows."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from tests.conftest import ROOT
from wirecal.formats.robot_file import load_robot
from wirecal.solver.accuracy import workspace
from wirecal.solver.fit.calibrate import Data, candidates, choose, point_model
from wirecal.solver.fit.model import (
    Layout,
    length_joint_gradient,
    lengths_and_jacobian,
    model_of,
    quantisation_floor,
)
from wirecal.solver.fit.result import FitOptions, fit_table
from wirecal.solver.fit.sessions import change_points, noise_sigma, place
from wirecal.solver.fit.synth import synthetic_table, take_rows
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.memo import Kept

ARMS = ("viper_s650", "abb_irb120", "ur5e")


def _robot(arm):
    return load_robot(ROOT / "examples" / arm / "robot.toml")


def _truth(syn, robot, name):
    """The generator's value of a fitted parameter (boundary units)."""
    axis = "xyz".index(name[-1]) if name[-2:] in ("_x", "_y", "_z") else None
    if name.startswith("tool_"):
        return syn.attachment_mm[axis] - robot.tool_point[axis]
    if name.startswith("anchor_"):
        return syn.anchor_mm[axis]
    if name.startswith("offset_"):
        return syn.offsets_mm[int(name.split("_")[1]) - 1]
    return syn.errors.get(name, 0.0)


def _check_recovery(robot, syn, result):
    core = result.main.core
    floor = result.main.floor_mm
    # sessions: as many as simulated, each start within ±2 rows
    assert len(core.starts) == len(syn.starts)
    assert np.all(np.abs(np.array(core.starts) - np.array(syn.starts)) <= 2)
    # outliers: every row whose snag or typo moves the length by more than 10 floors is
    # rejected; nothing else is, but a row beside a session's start
    rejected = set(np.flatnonzero(~core.inliers).tolist())
    gross = {r for r, e in syn.bad_mm.items() if abs(e) > 10 * floor}
    assert gross <= rejected
    near_start = {s + d for s in syn.starts[1:] for d in range(-2, 3)}
    assert rejected <= set(syn.bad_mm) | near_start
    # every fitted anchor and offset within 4σ of the truth
    per = core.layout.boundary_per_internal
    for name, value, std in zip(core.layout.names, core.x * per, core.std * per, strict=True):
        if name.startswith(("anchor_", "offset_")):
            truth = _truth(syn, robot, name)
            assert abs(value - truth) <= 4 * std, (name, value, truth, std)
    # the DH errors and the attachment as a model: its tool points over the workspace within
    # 0.15 mm of the truth's on average (per DH error 4σ no longer holds: a DH error BIC
    # fixes at 0, e.g. th2 = 0.012° at |z| 2.6, moves its correlated partner th3 by 7 of
    # its σ, and the tool point by microns)
    fitted = model_of(point_model(robot), core.layout, core.x)
    true = Model(robot.model(syn.errors).dh, syn.attachment_mm)
    q = workspace(robot)
    error = np.linalg.norm(tool_position(fitted, q) - tool_position(true, q), axis=1)
    assert error.mean() <= 0.15, error.mean()


@pytest.mark.parametrize("arm", ["viper_s650", "abb_irb120"])
def test_fit_recovers_sessions_outliers_and_the_truth(arm):
    robot = _robot(arm)
    syn = synthetic_table(robot, 400, seed=3)
    result = fit_table(robot, syn.table, FitOptions(holdout="random:0.2", repeats=3))
    _check_recovery(robot, syn, result)
    # every truth parameter was fitted (the generator perturbs identifiable ones only), or
    # left at 0 by BIC when its truth is small (under 0.15 deg or mm, σ's of 0.02–0.05)
    core = result.main.core
    bic = {name for name, why in core.dropped if "(BIC)" in why}
    for name, truth in syn.errors.items():
        assert name in core.layout.geometry or (name in bic and abs(truth) < 0.15), name


@pytest.mark.slow
@pytest.mark.parametrize("arm", ARMS)
@pytest.mark.parametrize("seed", [0, 1])
def test_fit_1000_rows_recovers_truth_and_reaches_the_floor(arm, seed):
    robot = _robot(arm)
    syn = synthetic_table(robot, 1000, seed=seed)
    result = fit_table(robot, syn.table, FitOptions(holdout="random:0.2", repeats=5))
    _check_recovery(robot, syn, result)
    assert result.main.holdout.ratio <= 1.2
    half = fit_table(robot, syn.table, FitOptions(holdout="half"))
    assert half.main.holdout.ratio <= 1.2


def test_held_out_rms_within_1_2_floors_and_the_half_split():
    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 400, seed=5)
    for scheme in ("random:0.2", "half"):
        ho = fit_table(robot, syn.table, FitOptions(holdout=scheme, repeats=2)).main.holdout
        assert ho.rows > 0
        assert ho.floor_mm > 0.1  # 0.1° joints at arm's reach: tenths of a mm
        assert ho.rms_mm <= 1.2 * ho.floor_mm, scheme
        assert ho.mae_mm < ho.rms_mm < ho.max_mm


def test_single_session_fits_one_offset_and_lists_the_jumps():
    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 300, seed=2, sessions=2)
    result = fit_table(robot, syn.table, FitOptions(single_session=True, holdout="none"))
    core = result.main.core
    assert core.layout.n_sessions == 1
    assert len(core.ignored_jumps) == 1
    assert abs(core.ignored_jumps[0] - syn.starts[1]) <= 2


def test_a_boundary_that_alternates_between_two_rows_ends_the_session_search(monkeypatch):
    """A boundary found at row 450, then 452, then 450 … once ran out of refits ("did not
    settle"): a set of sessions found again ends the search, keeping the cycle's fit with
    the fewest outliers."""
    from wirecal.solver.fit import calibrate as F

    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 300, seed=2, sessions=2, snags=0, typos=0)
    true = syn.starts[1]
    seen: list[tuple[int, ...]] = []
    found = F._session_starts

    def alternate(ps, data, values=None):
        if values is not None:  # the final check for jumps left in the residual
            return found(ps, data, values)
        seen.append(tuple(int(s) for s in np.unique(data.session, return_index=True)[1]))
        return (0, true + 2 * (len(seen) % 2))  # true+2, true, true+2, …

    monkeypatch.setattr(F, "_session_starts", alternate)
    monkeypatch.setattr(F, "_FITS", Kept(F.KEPT_FITS))  # fitted here, kept for no other test
    core = fit_table(robot, syn.table, FitOptions(holdout="none")).main.core
    assert seen == [(0,), (0, true + 2), (0, true)]  # (0, true + 2) found again: a cycle
    assert core.starts == (0, true)  # the boundary where the lengths jump fits best


def test_one_session_and_no_snags_gives_one_offset_and_no_outliers():
    robot = _robot("ur5e")
    syn = synthetic_table(robot, 300, seed=4, sessions=1, snags=0, typos=0)
    core = fit_table(robot, syn.table, FitOptions(holdout="none")).main.core
    assert core.starts == (0,)
    assert core.inliers.all()


def test_refined_joints_beat_the_rounded_ones_and_xyz_flags_only_typos():
    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 400, seed=6)
    result = fit_table(robot, syn.table, FitOptions(refine_joints=True, repeats=2))
    assert result.refined is not None
    assert result.xyz is not None
    assert set(result.xyz.flagged) <= set(syn.typos)
    assert result.xyz.flagged  # seed 6 has a joint typo that moves the TCP
    assert not result.main.core.inliers[list(result.xyz.flagged)].any()  # left out of the fit
    # the controller's TCP (0, 0, 100) mm in the flange frame, recovered from x, y, z
    np.testing.assert_allclose(result.xyz.tcp_mm, [0, 0, 100], atol=0.05)
    assert result.refined.holdout.rms_mm < 0.5 * result.main.holdout.rms_mm
    assert result.refined.holdout.floor_mm < 0.5 * result.main.holdout.floor_mm


def test_budget_has_the_robot_files_gravity_sag():
    """The fit's budget carries the sag term: none without sag, proportional to it."""
    from dataclasses import replace

    from wirecal.solver.fit.gate import fit_budget

    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 200, seed=1, sessions=1, snags=0, typos=0)
    result = fit_table(robot, syn.table, FitOptions(holdout="none"))
    sag = {
        k: fit_budget(r := replace(result, robot=replace(robot, gravity_sag_deg_per_m=k)), r.main)
        for k in (0.0, 0.01, 0.02)
    }
    assert sag[0.0].terms["sag"] == 0.0
    assert sag[0.01].terms["sag"] > 1e-4  # 0.01 deg/m over a metre's lever: tens of µm
    assert sag[0.02].terms["sag"] == pytest.approx(2 * sag[0.01].terms["sag"], rel=0.01)
    assert sag[0.01].terms["noise"] == sag[0.0].terms["noise"]


def test_a_jump_left_in_the_residual_is_refused_naming_its_row():
    from dataclasses import replace

    from wirecal.solver.errors import WirecalError
    from wirecal.solver.fit.result import _refuse_ignored_jumps

    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 100, seed=1, sessions=1, snags=0, typos=0)
    core = fit_table(robot, syn.table, FitOptions(holdout="none")).main.core
    jumped = replace(core, ignored_jumps=(40,))
    with pytest.raises(WirecalError, match=r"still jumps at row 40 \(<synthetic>:42\)"):
        _refuse_ignored_jumps(syn.table, jumped, FitOptions())
    _refuse_ignored_jumps(syn.table, jumped, FitOptions(single_session=True))  # asked for


def test_too_few_rows_and_refine_without_xyz_are_refused():
    from dataclasses import replace

    from wirecal.solver.errors import WirecalError

    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 10, seed=0, sessions=1, snags=0, typos=0)
    with pytest.raises(WirecalError, match="at least"):
        fit_table(robot, syn.table)
    syn = synthetic_table(robot, 60, seed=0, sessions=1, snags=0, typos=0)
    table = replace(syn.table, xyz_mm=None, xyz_resolution_mm=None)
    with pytest.raises(WirecalError, match="--refine-joints needs x, y, z"):
        fit_table(robot, table, FitOptions(refine_joints=True, holdout="none"))


# --- the model: derivatives against finite differences -------------------------------


@settings(max_examples=15, deadline=None)
@given(
    st.sampled_from(ARMS),
    st.booleans(),
    st.integers(0, 2**31),
    st.lists(st.floats(-1500, 1500), min_size=3, max_size=3),
)
def test_length_jacobian_matches_finite_differences(arm, scale, seed, anchor):
    robot = _robot(arm)
    base = point_model(robot)
    rng = np.random.default_rng(seed)
    q = np.radians(rng.uniform(-170, 170, (7, 6)))
    layout = Layout(("tool_x", "tool_y", "tool_z", "th2", "a2", "d4", "al3"), 6, 2, scale)
    x = rng.normal(0, 0.01, len(layout.names))
    x[7:10] = anchor
    session = rng.integers(0, 2, 7)
    lengths, J = lengths_and_jacobian(base, layout, x, q, session)
    assume(np.min(lengths - x[-2:][session]) > 10.0)  # the wire's direction is defined
    h = 1e-6
    for k in range(len(x)):
        dx = np.zeros_like(x)
        dx[k] = h
        up, _ = lengths_and_jacobian(base, layout, x + dx, q, session)
        down, _ = lengths_and_jacobian(base, layout, x - dx, q, session)
        np.testing.assert_allclose(J[:, k], (up - down) / (2 * h), rtol=1e-5, atol=1e-5)


def test_quantisation_floor_matches_monte_carlo_rounding():
    """The floor's per-row σ against lengths recomputed from joints shifted by uniform
    rounding errors (forward kinematics only, not the floor's Jacobian)."""
    robot = _robot("ur5e")
    base = point_model(robot)
    rng = np.random.default_rng(1)
    q_deg = rng.uniform(-120, 120, (5, 6))
    anchor = np.array([600.0, 200.0, 300.0])
    layout = Layout((), 6, 1, False)
    x = np.array([*anchor, 0.0])
    floor = quantisation_floor(length_joint_gradient(base, layout, x, np.radians(q_deg)), 0.1, 0.0)
    trials = 4000
    err = rng.uniform(-0.05, 0.05, (trials, 5, 6))
    q = np.radians(q_deg[None] + err).reshape(-1, 6)
    lengths = np.linalg.norm(tool_position(base, q) - anchor, axis=1).reshape(trials, 5)
    np.testing.assert_allclose(lengths.std(axis=0), floor, rtol=0.06)


# --- identifiability on these rows ---------------------------------------------------


def test_choice_names_the_degenerate_combinations_and_scale_against_lengths():
    robot = _robot("viper_s650")
    base = point_model(robot)
    syn = synthetic_table(robot, 200, seed=0, sessions=1, snags=0, typos=0)
    q = np.radians(syn.table.q_deg)
    data = Data(q, syn.table.length_mm, np.zeros(200, dtype=int), 0.25)
    layout = Layout(("tool_x", "tool_y", "tool_z"), 6, 1, True)
    x = np.zeros(len(layout.names))
    x[3:6] = syn.anchor_mm
    chosen, _, dropped = choose(base, layout, x, data, np.arange(200), 0.25)
    why = dict(dropped)
    assert "tool_z" in why["d6"]
    assert "tool_y" in why["th6"]
    assert "d2" in why["d3"]  # parallel axes 2 and 3
    # with the scale fitted, scaling every length together is unseen: one length goes,
    # named with the scale in its combination
    scaled = [n for n, w in dropped if "scale" in w]
    assert len(scaled) == 1
    assert scaled[0][0] in "ad"
    assert set(chosen.geometry) | set(why) == {"tool_x", "tool_y", "tool_z", *candidates(base)}


def test_a_twist_fitted_to_noise_does_not_split_parallel_axes():
    """The cause of d2 = +2683 mm, d3 = −2683 mm (seed 0, 1000 rows, Viper): at a fitted
    α2 of −0.004° d3 looked separable from d2; the choice is made at the nominal DH."""
    robot = _robot("viper_s650")
    base = point_model(robot)
    syn = synthetic_table(robot, 200, seed=0, sessions=1, snags=0, typos=0)
    data = Data(np.radians(syn.table.q_deg), syn.table.length_mm, np.zeros(200, dtype=int), 0.25)
    layout = Layout(("tool_x", "tool_y", "tool_z", "al2"), 6, 1, False)
    x = np.zeros(len(layout.names))
    x[3] = np.radians(-0.004)
    x[4:7] = syn.anchor_mm
    chosen, carried, dropped = choose(base, layout, x, data, np.arange(200), 0.25)
    assert "d3" not in chosen.geometry
    assert "d2" in dict(dropped)["d3"]
    assert "al2" in chosen.geometry  # kept, and its fitted value carried over
    assert carried[chosen.names.index("al2")] == x[3]


def test_a_fit_whose_parameters_are_not_identified_is_refused(monkeypatch):
    """Should the choice ever keep a degenerate pair (d2, d3 of parallel axes): refused,
    neither reported with a small σ nor dropped by BIC as "not worth a parameter"."""
    from wirecal.solver.errors import WirecalError
    from wirecal.solver.fit import calibrate as F

    robot = _robot("viper_s650")
    syn = synthetic_table(robot, 100, seed=1, sessions=1, snags=0, typos=0)

    def degenerate(base, layout, x, data, rows, sigma_mm, compliances=()):
        both = replace(layout, geometry=(*layout.geometry[:3], "d2", "d3"))
        return both, F._carry(layout, x, both), ()

    monkeypatch.setattr(F, "choose", degenerate)
    monkeypatch.setattr(F, "_FITS", Kept(F.KEPT_FITS))  # fitted here, kept for no other test
    with pytest.raises(WirecalError, match=r"parameters d2, d3 are not identified"):
        fit_table(robot, syn.table, FitOptions(holdout="none"))


# --- change points -------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.integers(12, 80), min_size=1, max_size=4),
    st.lists(st.floats(8, 40), min_size=4, max_size=4),
    st.integers(0, 2**31),
)
@example([12, 12], [8.0] * 4, 0)  # two snags inflated σ elevenfold: the jump went unseen
@example([52], [8.0] * 4, 0)  # one session: the difference σ came out 22 % low, a cut paid
@example([22, 22], [8.0] * 4, 33)  # snags at rows 19, 20: the search cuts at 19, place at 22
def test_change_points_find_jumps_within_two_rows(lengths, jumps, seed):
    """The fit's session starts (the search, then each boundary placed robustly, as
    ``fit.calibrate._session_starts`` does) lie within two rows of the true jumps."""
    rng = np.random.default_rng(seed)
    level = np.cumsum([0.0] + [j * rng.choice([-1, 1]) for j in jumps[: len(lengths) - 1]])
    values = np.concatenate([np.full(n, lv) for n, lv in zip(lengths, level, strict=True)])
    values += rng.normal(0, 1.0, values.size)
    lone = rng.choice(values.size, 2, replace=False)
    values[lone] += 50.0  # snags: lone rows far off must not cut a session
    truth = np.cumsum(lengths)[:-1]
    found = change_points(values)
    assert len(found) == len(truth)
    starts = place(values, (0, *found), noise_sigma(values))[1:]
    assert np.all(np.abs(np.array(starts) - truth) <= 2)


def test_no_change_points_in_noise():
    rng = np.random.default_rng(7)
    for _ in range(20):
        assert change_points(rng.normal(0, 1.0, 500)) == []


# --- hostile tables (issue 31 item 4; docs/fit.md "What fit refuses") ---------------


def test_lengths_alone_match_the_lengths_of_the_jacobian_call():
    from wirecal.solver.fit.model import lengths

    robot = _robot("ur5e")
    base = point_model(robot)
    layout = Layout(("tool_x", "th2", "a2"), 6, 2, True)
    rng = np.random.default_rng(1)
    x = rng.normal(0, 1e-3, len(layout.names))
    x[4:7] = [300.0, -200.0, 100.0]
    q = np.radians(rng.uniform(-90, 90, (20, 6)))
    session = np.repeat([0, 1], 10)
    np.testing.assert_allclose(
        lengths(base, layout, x, q, session),
        lengths_and_jacobian(base, layout, x, q, session)[0],
        rtol=0,
        atol=1e-9,
    )


def test_ft30_covariance_and_identifiability_are_linear_in_the_rows():
    """FT30: 100,000 rows ended in a 74.5 GiB (N × N) allocation in the covariance's SVD.

    200,000 rows × 30 columns: an N × N matrix would need 320 GB; the right vectors alone
    are 30 × 30. (Timing is bench/bench_fit.py's, not this test's.)
    """
    from wirecal.solver.identifiability import analyse_jacobian, covariance

    rng = np.random.default_rng(0)
    J = rng.normal(size=(200_000, 30))
    J[:, 29] = J[:, 28]  # one degenerate pair: the null-space paths run too
    cov, identified = covariance(J, 1.0)
    assert cov.shape == (30, 30)
    assert identified[:28].all()
    assert not identified[28:].any()
    ident = analyse_jacobian(J, tuple(f"p{k}" for k in range(30)))
    assert ident.rank == 29
    assert len(ident.combinations) == 1


def _clean(robot, n, seed=0):
    return synthetic_table(robot, n, seed=seed, sessions=1, snags=0, typos=0)


@pytest.mark.parametrize(
    ("rows", "scheme", "trains"),
    [(400, "random:0.999", 0), (30, "random:0.9", 3), (30, "half", 15)],
)
def test_ft45_ft46_a_split_training_on_under_twice_the_parameters_is_refused(rows, scheme, trains):
    """FT45/FT46: random:0.999 (no training row) read RMS/floor 0.98, random:0.9 on 30 rows
    0.51 (below the floor), half on 30 rows trained 15 rows for 23 parameters unsaid."""
    from wirecal.solver.errors import WirecalError

    robot = _robot("viper_s650")
    with pytest.raises(WirecalError, match=rf"--holdout {scheme}: a split trains on {trains} "):
        fit_table(robot, _clean(robot, rows).table, FitOptions(holdout=scheme, repeats=2))


def test_ft45_the_refusal_says_what_share_would_do():
    from wirecal.solver.errors import WirecalError
    from wirecal.solver.fit.holdout import check_training

    with pytest.raises(WirecalError, match=r"at most a share 0\.77 "):
        check_training("random:0.9", 40, 200, 23)  # (200 − 46) / 200 = 0.77
    with pytest.raises(WirecalError, match="too few rows to hold any out"):
        check_training("half", 15, 30, 23)
    check_training("random:0.2", 46, 200, 23)  # exactly twice: accepted


def test_ft27_copied_rows_are_named_left_out_and_do_not_shrink_the_sigmas():
    """FT27: every row twice was not said; held-out rows were copies of training rows and
    the σ's came out √2 too small."""
    robot = _robot("viper_s650")
    table = _clean(robot, 120, seed=3).table
    doubled = take_rows(table, np.tile(np.arange(120), 2))
    once = fit_table(robot, table, FitOptions(holdout="none"))
    both = fit_table(robot, doubled, FitOptions(holdout="random:0.2", repeats=2))
    assert both.copies == tuple((120 + r, r) for r in range(120))
    assert not both.main.core.inliers[120:].any()
    np.testing.assert_allclose(both.main.core.std, once.main.core.std, rtol=1e-6)


def test_holdout_rule_a_held_out_row_never_trains(monkeypatch):
    """Rule (fit_holdout): a held-out row never trains, nor a row at its joints.

    Kills the mutation "fit's held-out split can train on its held-out rows" (issue 33)
    wherever it sits: the rows each refit trains on are recorded at the solver's call.
    """
    import wirecal.solver.fit.calibrate as fit_module

    robot = _robot("viper_s650")
    table = _clean(robot, 150, seed=2).table
    again = np.r_[np.arange(150), [3, 70, 140]]  # three repeated readings at old joints
    table = take_rows(table, again)
    table = replace(table, length_mm=table.length_mm + np.r_[np.zeros(150), [0.05, -0.05, 0.1]])
    seen: list[tuple[np.ndarray, np.ndarray]] = []
    real_splits, real_solve = fit_module.splits, fit_module.solve

    def record_splits(*args, **kwargs):
        out = real_splits(*args, **kwargs)
        seen.extend((None, test) for _, test in out)
        return out

    trained: list[np.ndarray] = []

    def record_solve(base, layout, x0, data, rows, **kwargs):
        if "free" in kwargs:  # the held-out refits pass which parameters are free
            trained.append(np.asarray(rows))
        return real_solve(base, layout, x0, data, rows, **kwargs)

    monkeypatch.setattr(fit_module, "splits", record_splits)
    monkeypatch.setattr(fit_module, "solve", record_solve)
    for scheme in ("random:0.3", "half"):
        seen.clear()
        trained.clear()
        fit_table(robot, table, FitOptions(holdout=scheme, repeats=3))
        assert len(trained) == len(seen) > 0
        for train, (_, test) in zip(trained, seen, strict=True):
            assert len(test) > 0
            assert not set(train) & set(test), scheme
            q = {tuple(v) for v in table.q_deg[test]}
            assert not any(tuple(v) in q for v in table.q_deg[train]), scheme


def test_bic_elimination_is_the_refit_with_the_dropped_columns_fixed():
    """fit_select: z² of each drop and the estimates after it, against least squares solved
    again without the dropped columns (exact for a linear model)."""
    from wirecal.solver.fit.select import bic_eliminated
    from wirecal.solver.identifiability import covariance

    rng = np.random.default_rng(4)
    n = 400
    J = rng.normal(size=(n, 6))
    truth = np.array([3.0, 0.0, 0.0, 2.0, 0.0, 1.0])  # noise σ 1: |z| of a zero ≈ 1
    y = J @ truth + rng.normal(size=n)
    x = np.linalg.lstsq(J, y, rcond=None)[0]
    sigma = float(np.sqrt(np.sum((y - J @ x) ** 2) / (n - 6)))
    out = bic_eliminated(covariance(J, sigma**2)[0], x, [1, 2, 3, 4, 5], n)
    assert {k for k, _ in out} == {1, 2, 4}  # the zeros; 0 is no candidate
    assert all(z < np.sqrt(np.log(n)) for _, z in out)
    # the |z| of the last drop, from a refit without the columns dropped before it
    before = [k for k, _ in out[:-1]]
    keep = [c for c in range(6) if c not in before]
    xs = np.linalg.lstsq(J[:, keep], y, rcond=None)[0]
    cov = sigma**2 * np.linalg.inv(J[:, keep].T @ J[:, keep])
    last = keep.index(out[-1][0])
    assert out[-1][1] == pytest.approx(abs(xs[last]) / np.sqrt(cov[last, last]), rel=1e-9)
