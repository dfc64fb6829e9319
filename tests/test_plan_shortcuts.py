"""The planner's exact shortcuts give the answers of the work they save.

The candidates' moves from θ0 are screened only where a choice asks (the order of §3.4,
a step's pool, the compliances' bound); the joint design ranks its candidates by gain
per second of robot time, working out the time only where a lower bound of it cannot
settle the ranking; and a capsule's box gap does not depend on which other
configurations are asked about with it (what lets the sweeps merge and split their
calls freely).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.candidates import Screened
from wirecal.solver.plan.design import _unidentifiable
from wirecal.solver.plan.joint import _Candidates
from wirecal.solver.plan.moves import move_clearance, reach_and_move_ok
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.steps import POOL_SIZE, isolating_each, most_informative, step_by_step
from wirecal.solver.plan.tour import visit_floor_s, visit_s
from wirecal.solver.run_parameters import DEFAULT_RUN, PAPER_RUN
from wirecal.solver.sensitivity import PSI_FLOOR, sensitivity

THETA0 = np.array([-72, -156, 235, 3, 64, 41], float)  # 'wirecal plan' --for stepwise's


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), paper=st.booleans())
def test_the_bound_of_a_visits_robot_time_is_never_above_it(viper, seed, paper):
    """For moves anywhere within the limits (and short ones, where the settle and the
    readings dominate), at the planner's run and the paper's: bound ≤ time, and the
    bound is at least the stop's fixed part (0.5 s ramp, 0.08 s settle, 0.18 s readings)."""
    rng = np.random.default_rng(seed)
    lo, hi = viper.limits_deg()
    start = rng.uniform(lo, hi)
    ends = rng.uniform(lo, hi, (20, 6))
    ends[:5] = start + rng.uniform(-2.0, 2.0, (5, 6))
    run = PAPER_RUN if paper else DEFAULT_RUN
    p0 = tool_position(viper.nominal, np.radians(start)[None])[0]
    floor = visit_floor_s(viper, run, start, ends)
    assert np.all(floor <= visit_s(viper, run, p0, start, ends))
    assert np.all(floor >= 0.5 + 0.08 + 0.18 - 1e-9)


@pytest.fixture(scope="module")
def joint_candidates(viper):
    """The joint design's candidates around the Viper's θ0, the planner's settings."""
    opt = PlanOptions()
    model = viper.nominal
    cands = Screened(viper, THETA0, opt)
    excluded = _unidentifiable(model, cands.q, THETA0, list(viper.parameters))
    names = [n for n in viper.parameters if n not in excluded]
    psi = sensitivity(model, cands.q, THETA0, names).psi
    pools = step_by_step(viper, THETA0, cands, psi, names, {}, opt, lambda f: None)
    return _Candidates(viper, THETA0, cands.q, cands.via, pools, opt)


@pytest.mark.slow
def test_screening_on_demand_makes_the_choices_of_screening_all(viper):
    """Around the Viper's θ0: the order of §3.4 and each step's pool (its POOL_SIZE most
    sensitive usable isolating candidates, in order) are those of every candidate
    screened first, while fewer than half the candidates are screened; and the first
    usable candidates of random rankings are those of the full screening."""
    opt = PlanOptions()
    lazy, full = Screened(viper, THETA0, opt), Screened(viper, THETA0, opt)
    usable = full.usable(np.ones(len(full.q), bool))
    assert 0.2 < usable.mean() < 0.8  # both kinds of candidates, many of each
    names = list(viper.parameters)
    col = {n: k for k, n in enumerate(names)}
    psi = sensitivity(viper.nominal, lazy.q, THETA0, names).psi
    remaining = list(names)
    while (want := most_informative(psi, col, remaining, opt, full.first_usable)) is not None:
        got = most_informative(psi, col, remaining, opt, lazy.first_usable)
        assert got is not None
        assert got[0] == want[0]
        iso = want[1][usable[want[1]]][:POOL_SIZE]  # the full screening's pool
        assert np.array_equal(lazy.first_usable([got[1]], [POOL_SIZE])[0], iso)
        remaining.remove(want[0])
    assert most_informative(psi, col, remaining, opt, lazy.first_usable) is None
    assert np.count_nonzero(lazy.state) < len(lazy.q) / 2
    screened = lazy.state > 0
    assert np.array_equal(lazy.state[screened] == 1, usable[screened])
    assert np.array_equal(lazy.via[screened], full.via[screened], equal_nan=True)
    rng = np.random.default_rng(2)
    for n in (1, 7, 300):
        order = rng.permutation(len(lazy.q))[:2000]
        assert np.array_equal(lazy.first_usable([order], [n])[0], order[usable[order]][:n])


def _ranking_by_times(c: _Candidates, gain: np.ndarray) -> np.ndarray:
    """Every allowed candidate ranked by gain per second, every time worked out (the
    planner's ranking before the bound): the least time from each configuration counted."""
    cost = np.full(len(c.cand), np.inf)
    for starts in c.starts:
        for a, members in starts:
            t = visit_s(c.robot, c.opt.run, c.p0, a, c.q[members])
            cost[members] = np.minimum(cost[members], t)
    ranked = np.flatnonzero(c.allowed)
    return ranked[np.argsort(-gain[ranked] / cost[ranked], kind="stable")]


@pytest.mark.slow
def test_the_ranking_by_bounds_is_the_ranking_by_times(joint_candidates):
    """The head of the ranking, 8 and 40 long, is that of every time worked out, ties
    (a tenth of the gains zero) in the order of the candidates; also after a step gained
    a point (its candidates counted from it too, some of their times worked out before)."""
    c = joint_candidates
    rng = np.random.default_rng(1)
    assert len(np.flatnonzero(c.allowed)) > 100
    for added in (False, True):
        if added:
            k = int(c.step[c.head(rng.exponential(1.0, len(c.cand)), 8)[0]])
            allowed = np.flatnonzero(c.allowed & (c.step == k))
            c.pools[k].picks.append(int(c.local[allowed[0]]))
            c.update(k, 1)
        for _ in range(3):
            gain = rng.exponential(1.0, len(c.cand))
            gain[rng.random(len(gain)) < 0.1] = 0.0
            full = _ranking_by_times(c, gain)
            for n in (8, 40):
                assert np.array_equal(c.head(gain, n), full[:n])


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_box_gap_does_not_depend_on_the_configurations_asked_with_it(viper, seed):
    """The Viper's base column: each configuration's gaps asked alone are the gaps asked
    with 39 others, to the bit."""
    rng = np.random.default_rng(seed)
    lo, hi = viper.limits_deg()
    q = rng.uniform(lo, hi, (40, 6))
    p0 = tool_position(viper.nominal, np.radians(THETA0)[None])[0]
    together = viper.cell_gaps(q, p0).gap
    alone = np.concatenate([viper.cell_gaps(q[k : k + 1], p0).gap for k in range(40)], axis=1)
    assert np.array_equal(together, alone)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 8))
def test_isolating_every_parameter_at_once_is_the_rule_per_pair(seed, m):
    """The largest other |Ψ| within the tolerance ⇔ each other |Ψ_t| within it (eq.
    18–19 per pair, as ``psi --strict`` judges a point), with ties, zeros, one parameter
    left, and |Ψ| near the floor and the 0.05 threshold."""
    rng = np.random.default_rng(seed)
    scale = rng.choice([0.001, 0.004, 0.05, 1.0, 10.0], size=(400, m))
    psi = np.round(rng.normal(size=(400, m)) * scale, int(rng.integers(1, 4)))
    psi[:, rng.integers(0, m)] = psi[:, 0]  # equal |Ψ| in two columns
    names = [f"p{k}" for k in range(m)]
    col = {n: k for k, n in enumerate(names)}
    remaining = [n for n in names if rng.random() < 0.8] or names[:1]
    opt = PlanOptions()
    got = isolating_each(psi, col, remaining, opt)
    for k, j in enumerate(remaining):
        pj = psi[:, col[j]]
        want = np.ones(len(psi), bool)
        for t in remaining:
            if t != j:
                want &= np.abs(psi[:, col[t]]) <= np.maximum(opt.tol * np.abs(pj), PSI_FLOOR)
        assert np.array_equal(got[k], want & (np.abs(pj) >= 0.05)), j


@pytest.mark.parametrize("step_deg", [2.0, 10.0])
def test_legs_swept_together_give_each_legs_answer_alone(viper, step_deg):
    """``reach_and_move_ok`` sweeps the moves from θ0, the second legs from the via
    points and the moves a → b in one call, with quick passes and a leg's block sparing
    its path's other legs: the answers of every leg swept alone over all its samples."""
    rng = np.random.default_rng(7)
    opt = PlanOptions()
    lo, hi = viper.limits_deg(opt.margin_deg)
    model = viper.nominal
    p0 = tool_position(model, np.radians(THETA0)[None])[0]
    near = lambda n, sd: np.clip(THETA0 + rng.normal(0.0, sd, (n, 6)), lo, hi)  # noqa: E731
    q = near(120, 40.0)
    via = np.where(rng.random(120)[:, None] < 0.5, np.nan, near(120, 20.0))
    a, b = near(30, 40.0), near(30, 40.0)
    longest = viper.encoder.range_mm - opt.range_margin_mm

    def alone(x, y):  # one leg: joint 6 within 180°, every sample clear
        gap = [
            move_clearance(viper, model, p0, x[k], y[k], step_deg, 1, longest)
            for k in range(len(x))
        ]
        return (np.abs(y[:, -1] - x[:, -1]) <= 180) & (np.concatenate(gap) >= opt.clearance_mm)

    direct = np.isnan(via[:, 0])
    t0 = np.broadcast_to(THETA0, q.shape)
    want = np.where(direct, alone(t0, q), alone(t0, np.where(direct[:, None], q, via)))
    want[~direct] &= alone(via[~direct], q[~direct])
    reached, clear = reach_and_move_ok(viper, model, p0, THETA0, q, via, a, b, opt, step_deg)
    assert np.array_equal(reached, want)
    assert np.array_equal(clear, alone(a, b))
    for answers in (reached[direct], reached[~direct], clear):  # not all one answer
        assert 0 < answers.sum() < len(answers)
