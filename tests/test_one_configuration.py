"""One configuration on Python floats (issue 34): the same numbers as the arrays, bit for bit.

The twin and its controllers' inverse kinematics evaluate one configuration at a time at
every move; those paths (kinematics.one_chain, the Newton step of ik/solutions.py, the
sag's gravity torques) must give exactly the numbers of the vectorised code evaluating a
batch of configurations, or the twin's logs would change with the speed-up.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors
from wirecal.solver.gravity import (
    MassModel,
    gravity_torques_floats,
    gravity_torques_nm,
    wrist_weight,
)
from wirecal.solver.ik import solutions as ik
from wirecal.solver.kinematics import flange_jacobian, frames, one_chain
from wirecal.solver.run_parameters import cruise_per_pct, one_travel_duration_s, travel_duration_s
from wirecal.solver.simulate import Unmodelled

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARMS = ("viper_s650", "ur5e", "abb_irb120", "puma560")
ANGLES = st.lists(st.floats(-3.2, 3.2), min_size=6, max_size=6).map(np.array)


@pytest.fixture(scope="module", params=ARMS)
def models(request):
    robot = load_robot(EXAMPLES / request.param / "robot.toml")
    truth = random_errors(robot, 1.0, np.random.default_rng(3))
    return robot.nominal, robot.model(truth)


def _batch(model, q):
    """The frames of q as the second row of a batch (the vectorised path)."""
    return frames(model, np.stack([np.zeros_like(q), q]))


@settings(max_examples=40, deadline=None)
@given(q=ANGLES)
def test_one_chain_gives_the_batch_frames(models, q):
    for model in models:
        stored, (X, Y, Z) = one_chain(model, q)
        f = _batch(model, q)
        assert np.array_equal(np.array([s[0] for s in stored]), f.x[1])
        assert np.array_equal(np.array([s[1] for s in stored]), f.z[1])
        assert np.array_equal(np.array([s[2] for s in stored]), f.o[1])
        assert np.array_equal(np.array([X, Y, Z]).T, f.R_last[1])


@settings(max_examples=40, deadline=None)
@given(q=ANGLES, target=ANGLES)
def test_the_newton_step_on_floats_gives_the_arrays_step(models, q, target):
    for model in models:
        R, o = (a[1] for a in (_batch(model, target).R_last, _batch(model, target).o[:, -1]))
        f = _batch(model, q)
        e, jacobian = ik._newton_terms(model, q, R, o)
        f1 = frames(model, q[None])
        assert np.array_equal(e, ik._pose_error(model, q, R, o, f1))
        assert np.array_equal(jacobian(), flange_jacobian(model, q, f1))
        assert np.array_equal(ik.flange_pose(model, q)[0], f.R_last[1])


def test_the_configuration_names_from_floats_are_the_arrays(models, monkeypatch):
    q = np.random.default_rng(5).uniform(-3, 3, (200, 6))
    on_floats = [[ik.configuration(model, x) for x in q] for model in models]
    with monkeypatch.context() as m:
        m.setattr(ik, "one_chain", lambda model, q: None)  # frames' arrays, as before
        assert on_floats == [[ik.configuration(model, x) for x in q] for model in models]


@settings(max_examples=40, deadline=None)
@given(q=ANGLES, seed=st.integers(0, 2**32 - 1))
def test_gravity_torques_on_floats_equal_the_vectorised_ones(models, q, seed):
    rng = np.random.default_rng(seed)
    masses = (
        wrist_weight(6),
        MassModel(rng.uniform(0.5, 5.0, 6), rng.uniform(-80.0, 80.0, (6, 3))),
    )
    for model in models:
        f = _batch(model, q)
        stored, _ = one_chain(model, q)
        x, z, o = (list(v) for v in zip(*stored, strict=True))
        for m in masses:
            torque = gravity_torques_floats(m, x, z, o)
            assert np.array_equal(np.array(torque), gravity_torques_nm(m, f.x, f.z, f.o)[1])


def test_the_sag_of_one_configuration_is_a_row_of_the_batchs(models):
    q = np.random.default_rng(6).uniform(-150.0, 150.0, (50, 6))
    for model in models:
        batch = Unmodelled().sag_deg(model, q)
        for k in range(len(q)):
            assert np.array_equal(Unmodelled().sag_deg(model, q[k]), batch[k : k + 1])


def test_a_payload_keeps_the_vectorised_form():
    m = MassModel(np.ones(6), np.zeros((6, 3)), payload_mass_kg=1.0)
    axes = [(1.0, 0.0, 0.0)] * 7
    assert gravity_torques_floats(m, axes, axes, [(0.0, 0.0, 0.0)] * 7) is None


def _across(model, q_a, q_b, part):
    """Bisect the joint segment q_a → q_b to where configuration name ``part`` changes."""
    side = ik.configuration(model, q_a)[part]
    for _ in range(80):
        mid = (q_a + q_b) / 2
        if ik.configuration(model, mid)[part] == side:
            q_a = mid
        else:
            q_b = mid
    return q_a, q_b


@pytest.mark.parametrize("part", [0, 1])
def test_the_names_on_floats_leave_a_sign_near_zero_to_the_arrays(models, monkeypatch, part):
    """Where righty/lefty or above/below changes, the floats decide nothing; names still equal."""
    rng = np.random.default_rng(11)
    undecided = 0
    for model in models:
        if one_chain(model, np.zeros(6)) is None or ik.ik_ur.ur_structure(model):
            continue  # the arrays' path already, or the UR's own names
        q = rng.uniform(-3, 3, (400, 6))
        names = [ik.configuration(model, x)[part] for x in q]
        pairs = [(q[k], q[k + 1]) for k in range(len(q) - 1) if names[k] != names[k + 1]][:5]
        for q_a, q_b in pairs:
            for x in _across(model, q_a, q_b, part):
                on_floats = ik.configuration(model, x)
                undecided += ik._configuration_floats(model, x, one_chain(model, x)[0]) is None
                with monkeypatch.context() as m:
                    m.setattr(ik, "one_chain", lambda model, q: None)
                    assert ik.configuration(model, x) == on_floats
    if all(one_chain(m, np.zeros(6)) is None or ik.ik_ur.ur_structure(m) for m in models):
        pytest.skip("no arm here whose names come from the floats")
    assert undecided > 0  # the bisection ends within the margin: the arrays decided there


@settings(max_examples=60, deadline=None)
@given(
    q=st.lists(st.floats(-20.0, 20.0), min_size=6, max_size=6),
    others=st.lists(st.lists(st.floats(-4.0, 4.0), min_size=6, max_size=6), max_size=3),
)
def test_a_solutions_wrapping_limits_and_merging_on_floats_are_the_arrays(q, others):
    """ik.each_solution's floats: numpy's wrap into [-π, π), turns into the limits, merge."""
    lo_deg, hi_deg = (
        np.array([-170.0, -190, -29, -190, -120, -360]),
        np.array([170.0, 45, 256, 190, 120, 360]),
    )
    lo, hi = np.radians(lo_deg), np.radians(hi_deg)
    arrays = (np.array(q) + np.pi) % (2 * np.pi) - np.pi  # the code before, on arrays
    for j in range(6):
        for turn in (0.0, 2 * np.pi, -2 * np.pi):
            if lo[j] <= arrays[j] + turn <= hi[j]:
                arrays[j] += turn
                break
    inside = bool(np.all((arrays >= lo - 1e-12) & (arrays <= hi + 1e-12)))
    wrapped = [ik._wrapped(x) for x in q]
    assert np.array_equal(np.array(wrapped), (np.array(q) + np.pi) % (2 * np.pi) - np.pi)
    assert ik._into_limits(wrapped, lo.tolist(), hi.tolist()) == (arrays.tolist(), inside)
    near = [list(arrays + np.array(o) * 1e-6) for o in others]
    merged = bool(
        others and np.any(np.all(np.abs(ik._wrapped(arrays - np.array(near))) <= 2e-6, axis=1))
    )
    assert ik._same_as_any(arrays.tolist(), near, 2e-6) == merged


@settings(max_examples=60, deadline=None)
@given(
    start=st.lists(st.floats(-360.0, 360.0), min_size=6, max_size=6),
    step=st.lists(st.sampled_from([0.0, 1e-9, 0.3, -2.0, 45.0]), min_size=6, max_size=6),
    speed=st.sampled_from([0.0, 1.0, 37.5, 100.0]),
)
def test_one_moves_duration_on_floats_is_the_arrays(start, step, speed):
    """The twin's every move: travel_duration_s of cruise_per_pct, on floats, bit for bit."""
    robot = load_robot(EXAMPLES / "viper_s650" / "robot.toml")
    a = np.array(start)
    b = a + np.array(step)
    with np.errstate(divide="ignore", invalid="ignore"):
        want = float(travel_duration_s(cruise_per_pct(robot, (b - a)[None]), np.asarray(speed))[0])
    got = one_travel_duration_s(robot, a, b, speed)
    assert got == want or (np.isnan(got) and np.isnan(want))
