"""Inverse kinematics: FK∘IK round trips over random poses (hypothesis), all solutions,
their configuration names, and the numeric fallback."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.solver.ik import analytic_structure, configuration, flange_pose, solve

from .conftest import TABLE5 as TRUTH

unit = st.floats(0.02, 0.98)


def _q(viper, u):
    lo, hi = viper.joint_min_deg, viper.joint_max_deg
    return np.radians(lo + np.asarray(u) * (hi - lo))


def _same(a, b):
    return np.allclose((a - b + np.pi) % (2 * np.pi) - np.pi, 0, atol=1e-6)


@settings(max_examples=40, deadline=None)
@given(u=st.lists(unit, min_size=6, max_size=6), calibrated=st.booleans())
def test_round_trip_analytic(viper, u, calibrated):
    model = viper.model(TRUTH if calibrated else {})
    assert analytic_structure(model)
    q = _q(viper, u)
    R, o = flange_pose(model, q)
    solutions = solve(viper, R, o, model=model)
    singular = abs(np.sin(q[4] + model.dh[4, 2])) < 1e-6  # φ4, φ6 then form a continuum
    assert singular or any(_same(s.q, q) for s in solutions)
    assert 1 <= len(solutions) <= 8
    for s in solutions:
        R2, o2 = flange_pose(model, s.q)
        np.testing.assert_allclose(o2, o, atol=1e-8)
        np.testing.assert_allclose(R2, R, atol=1e-10)
    configs = [s.config for s in solutions]
    assert len(set(configs)) == len(configs)  # each solution a different configuration


@settings(max_examples=15, deadline=None)
@given(u=st.lists(unit, min_size=6, max_size=6))
def test_numeric_fallback_for_a_non_spherical_wrist(viper, u):
    model = viper.model({"al4": 0.4, "a4": 0.8, "d5": 0.3})
    assert not analytic_structure(model)
    q = _q(viper, u)
    R, o = flange_pose(model, q)
    solutions = solve(viper, R, o, model=model)
    near_singular = abs(np.sin(q[4] + model.dh[4, 2])) < 0.05  # wrist nearly straight
    assert near_singular or any(_same(s.q, q) for s in solutions)
    for s in solutions:
        np.testing.assert_allclose(flange_pose(model, s.q)[1], o, atol=1e-7)


def test_eight_configurations_of_a_generic_pose(viper):
    model = viper.nominal
    R, o = flange_pose(model, np.radians([10, -60, 150, 20, 40, 30.0]))
    configs = {s.config for s in solve(viper, R, o)}
    assert {c[1:] for c in configs} == {
        ("above", "noflip"),
        ("above", "flip"),
        ("below", "noflip"),
        ("below", "flip"),
    }
    assert configuration(model, np.radians([10, -60, 150, 20, 40, 30.0])) == (
        "righty",
        "above",
        "noflip",
    )


def test_unreachable_pose_has_no_solution(viper):
    model = viper.nominal
    R, _ = flange_pose(model, np.zeros(6))
    assert solve(viper, R, np.array([2000.0, 0, 0])) == []
