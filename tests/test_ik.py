"""Inverse kinematics: FK∘IK round trips over random poses (hypothesis), all solutions,
their configuration names, and the numeric fallback."""

from __future__ import annotations

import itertools
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from wirecal.formats.robot_file import load_robot
from wirecal.solver.ik import solutions as ik
from wirecal.solver.ik import ur as ik_ur
from wirecal.solver.ik.solutions import analytic_structure, configuration, flange_pose, solve
from wirecal.solver.ik.ur import ur_structure

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


@pytest.mark.slow
@settings(max_examples=15, deadline=None)
@given(u=st.lists(unit, min_size=6, max_size=6))
# elbow near its fold (φ3 = 109°): the structural table just out of reach, two branches 3.9° apart
@example(u=[0.3125, 0.90625, 0.484375, 0.9375, 0.0625, 0.453125])
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


def test_each_solution_polishes_only_as_far_as_it_is_asked(viper):
    """The V+ controller takes the first solution of its configuration: those after it are
    never polished, and the ones yielded are solve's, in its order."""
    model = viper.model({"th2": 0.3, "a2": 0.2})
    R, o = flange_pose(model, np.radians([10, -60, 150, 20, 40, 30.0]))
    every = solve(viper, R, o, model=model)
    with mock.patch.object(ik, "_polish", wraps=ik._polish) as polish:
        first = next(ik.each_solution(viper, R, o, model=model))
    assert polish.call_count < len(every)
    assert np.array_equal(first.q, every[0].q)
    assert first.config == every[0].config
    lazy = list(ik.each_solution(viper, R, o, model=model))
    assert [(s.config, s.within_limits) for s in lazy] == [
        (s.config, s.within_limits) for s in every
    ]
    assert all(np.array_equal(a.q, b.q) for a, b in zip(lazy, every, strict=True))


def test_unreachable_pose_has_no_solution(viper):
    model = viper.nominal
    R, _ = flange_pose(model, np.zeros(6))
    assert solve(viper, R, np.array([2000.0, 0, 0])) == []


# --- UR-type arms: the closed form of solver/ik/ur.py ----------------------------------------

UR5_FILE = Path(__file__).resolve().parents[1] / "examples" / "ur5e" / "robot.toml"
UR5 = load_robot(UR5_FILE)
UR5_ERRORS = {"th2": 0.3, "th4": -0.2, "a2": 0.8, "a3": -0.5, "d4": 0.4, "d5": 0.3, "al3": 0.1}


@settings(max_examples=40, deadline=None)
@given(u=st.lists(unit, min_size=6, max_size=6), calibrated=st.booleans())
# wrist point inside the structural shoulder cylinder: the calibrated shoulders 1.6° apart in q1
@example(u=[0.5, 0.4609375, 0.732421875, 0.89453125, 0.625, 0.5], calibrated=True)
# φ5 = 177.5°: the calibrated arm has 10 solutions, two of them 7° apart on one branch
@example(u=[0.5, 0.98, 0.296875, 0.75, 0.75, 0.5], calibrated=True)
# wrist point just inside the structural table's shoulder cylinder (by 0.07 mm), φ5 = 0
@example(u=[0.5, 0.978515625, 0.2890625, 0.978515625, 0.5, 0.5], calibrated=True)
# elbow folded (φ3 = −177.5°) and φ5 = 0: Newton from the seed first wanders (σ_min 0.002)
@example(u=[0.5, 0.5, 0.25, 0.5, 0.5, 0.5], calibrated=True)
# arm stretched (φ3 = 0) and φ5 = 0 exactly: only the φ6 = 0 seed reaches
@example(u=[0.5, 0.75, 0.5, 0.5, 0.5, 0.5], calibrated=False)
# the shoulder–wrist line vertical: both elbow branches level with it (named by their side)
@example(u=[0.5, 0.5, 0.78125, 0.5, 0.125, 0.5], calibrated=True)
# elbow folded to 179.6° on the calibrated arm: the structural table's seeds both at 180°
@example(u=[0.5, 0.5, 0.7529418094771448, 0.5, 0.125, 0.5], calibrated=True)
# elbow folded onto itself (φ3 = 180.02°) on the exact table: its two elbow branches exact
# and 0.5° apart, once merged as one Newton start (met within 1e-2 rad)
@example(u=[0.5, 0.5, 0.75355, 0.5, 0.75, 0.5], calibrated=False)
# calibrated arm folded to 180.27°: the shoulder–wrist lines of the righty-flip branches
# 0.87° and 1.17° from vertical, once both named below
@example(u=[0.5, 0.0899, 0.7539, 0.9375, 0.625, 0.5], calibrated=True)
# calibrated arm 0.05° short of the fold: two lefty branches that meet beyond it, both were
# "above" by their side of the line
@example(u=[0.5, 0.0899, 0.75345, 0.9375, 0.625, 0.5], calibrated=True)
# arm stretched and wrist singular on the exact table: φ6 = 0 puts the wrist point beyond reach
@pytest.mark.slow
@example(u=[0.5, 0.5, 0.5, 0.875, 0.5, 0.25], calibrated=False)
def test_ur_round_trip_closed_form(u, calibrated):
    """Every returned solution reproduces the pose; the sampled one is among them.

    A calibrated model (al3 ≠ 0: axes 3 and 4 not parallel) is a general 6R arm with up to
    16 solutions, not 8. Near the wrist singularity (|sin φ5| < sin 15°) it can have more
    than the structural table's 8 (10 at φ5 = 177.5° in the first example, each with a flange
    error below 1e-12 mm), so there the count may exceed 8 and branch names repeat.
    """
    model = UR5.model(UR5_ERRORS if calibrated else {})
    assert ur_structure(model)
    assert not analytic_structure(model)
    q = _q(UR5, u)
    R, o = flange_pose(model, q)
    solutions = solve(UR5, R, o, model=model)
    # wrist (φ5 = 0) or elbow (arm stretched, φ3 = 0) singular: Newton's Jacobian is singular
    singular = min(abs(np.sin(q[4] + model.dh[4, 2])), abs(np.sin(q[2] + model.dh[2, 2]))) < 1e-6
    assert singular or any(_same(s.q, q) for s in solutions)
    near_wrist = abs(np.sin(q[4] + model.dh[4, 2])) < np.sin(np.radians(ik_ur.NEAR_SINGULAR_DEG))
    more = calibrated and near_wrist
    assert 1 <= len(solutions) <= (16 if more else 8)
    for s in solutions:
        R2, o2 = flange_pose(model, s.q)
        assert np.linalg.norm(o2 - o) <= 1e-9
        np.testing.assert_allclose(R2, R, atol=1e-12)
    configs = [s.config for s in solutions]
    # at a singularity (the elbow stretched, φ3 = 0) two branches meet and may share a name
    assert singular or more or len(set(configs)) == len(configs)


@pytest.mark.parametrize("calibrated", [False, True])
@pytest.mark.parametrize("fold_deg", [0.0, 180.0])
def test_ur_elbow_name_near_the_fold_continues_the_side_of_the_line(calibrated, fold_deg):
    """Within ik_ur.ELBOW_NEAR_DEG of the fold the name comes from det J, beyond from the
    elbow's side of the line: across that switch the name stays, across the fold it changes."""
    model = UR5.model(UR5_ERRORS if calibrated else {})
    rng = np.random.default_rng(7)
    near = ik_ur.ELBOW_NEAR_DEG
    checked = 0
    for q in np.radians(rng.uniform(-180, 180, (200, 6))):
        phi = np.degrees(q) + np.degrees(model.dh[:, 2])
        if abs(np.sin(np.radians(phi[4]))) < 0.2:
            continue  # away from the wrist singularity (φ5 also enters det J)
        names = []
        for bend in (near + 0.1, near - 0.1, 0.5, -0.5, -near + 0.1, -near - 0.1):
            q[2] = np.radians(fold_deg + bend) - model.dh[2, 2]
            names.append(configuration(model, q))
        if len({n[0] for n in names}) > 1:
            continue  # the shoulder changed on the way (o5 crossed the joint-1 axis)
        assert names[0] == names[1] == names[2]
        assert names[3] == names[4] == names[5]
        assert names[2][1] != names[3][1]
        checked += 1
    assert checked >= 50


def test_ur_generic_pose_has_eight_named_solutions():
    model = UR5.nominal
    q = np.radians([20, -70, 100, -40, 60, 30.0])
    solutions = solve(UR5, *flange_pose(model, q), model=model)
    assert len(solutions) == 8
    assert {s.config for s in solutions} == set(
        itertools.product(("righty", "lefty"), ("above", "below"), ("noflip", "flip"))
    )


@pytest.mark.slow  # the numeric search takes about a second per pose
@pytest.mark.parametrize("arm", ["ur5e", "viper"])
def test_numeric_search_finds_only_closed_form_solutions(arm, viper):
    robot = UR5 if arm == "ur5e" else viper
    model = robot.nominal
    rng = np.random.default_rng(5)
    lo, hi = robot.joint_min_deg, robot.joint_max_deg
    found = total = 0
    for x in np.radians(lo + rng.uniform(0.05, 0.95, (6, 6)) * (hi - lo)):
        R, o = flange_pose(model, x)
        closed = solve(robot, R, o, model=model)
        with (
            mock.patch.object(ik_ur, "ur_structure", return_value=False),
            mock.patch.object(ik, "analytic_structure", return_value=False),
        ):
            numeric = solve(robot, R, o, model=model)
        assert numeric, "the search found nothing"
        for s in numeric:  # nothing the closed form does not know
            assert any(_same(s.q, c.q) for c in closed)
        found += len(numeric)
        total += len(closed)
    assert found >= 0.75 * total  # it may miss a few; it finds most
