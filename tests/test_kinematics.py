"""Forward kinematics against an independent construction; analytic derivatives against
finite differences (hypothesis over random configurations and random perturbed models)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy.spatial.transform import Rotation

from wirecal.solver import params as P
from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.kinematics import (
    frames,
    joint_jacobian,
    tool_jacobian,
    tool_position,
    with_errors,
)

ALL = P.all_names(6, with_tool=True)


def _rad(model, err: dict[str, float]):
    """``model`` with offsets in internal units (rad, mm)."""
    return with_errors(model, list(err), np.array(list(err.values()), dtype=float))


joints = arrays(np.float64, (6,), elements=st.floats(-np.pi, np.pi))
batches = arrays(
    np.float64, st.tuples(st.integers(1, 8), st.just(6)), elements=st.floats(-np.pi, np.pi)
)
errors = st.dictionaries(st.sampled_from(ALL), st.floats(-2.0, 2.0), max_size=8)


def _hom(R: np.ndarray, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


def reference_position(model, q: np.ndarray) -> np.ndarray:
    """Craig's T_{i-1,i} = RotX(α)·TransX(a)·RotZ(θ)·TransZ(d), built from scipy rotations."""
    T = np.eye(4)
    for (alpha, a, off, d), qi in zip(model.dh, q, strict=True):
        T = T @ _hom(Rotation.from_euler("x", alpha).as_matrix(), [0, 0, 0])
        T = T @ _hom(np.eye(3), [a, 0, 0])
        T = T @ _hom(Rotation.from_euler("z", qi + off).as_matrix(), [0, 0, 0])
        T = T @ _hom(np.eye(3), [0, 0, d])
    return (T @ np.append(model.tool_point, 1.0))[:3]


@settings(max_examples=60, deadline=None)
@given(q=batches, err=errors)
def test_forward_kinematics_matches_independent_construction(viper, q, err):
    model = viper.model(err)
    got = tool_position(model, q)
    want = np.array([reference_position(model, row) for row in q])
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_viper_home_position_by_hand(viper):
    # At θ = 0 the twists pair up: α1 = −90° (row 2) cancels α3 = +90° (row 4), and
    # α4 = −90° cancels α5 = +90°, so frames 4 and 6 are parallel to the base frame.
    # o4 = (a1 + a2 + a3, 0, d4) = (75 + 270 − 90, 0, 295); o6 = o4 + d6·z;
    # the tool point (−60, 0, 50) is then added in base axes.
    p = np.array([75 + 270 - 90, 0, 295 + 80]) + np.array([-60.0, 0, 50])
    np.testing.assert_allclose(tool_position(viper.nominal, np.zeros((1, 6)))[0], p, atol=1e-9)
    np.testing.assert_allclose(p, [195, 0, 425])


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(q=batches, err=errors)
def test_tool_jacobian_matches_finite_differences(viper, q, err):
    model = _rad(viper.nominal, err)
    _, J = tool_jacobian(model, q, ALL)
    h = 1e-6
    for k, name in enumerate(ALL):
        plus = tool_position(_rad(model, {name: h}), q)
        minus = tool_position(_rad(model, {name: -h}), q)
        np.testing.assert_allclose(J[:, :, k], (plus - minus) / (2 * h), atol=2e-5, err_msg=name)


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(q=batches, q0=joints, err=errors)
def test_wire_jacobian_matches_finite_differences(viper, q, q0, err):
    model = _rad(viper.nominal, err)
    d, dd = wire_jacobian(model, q, q0, ALL)
    far = d > 1.0  # the derivative of a length is undefined where the wire length is zero
    np.testing.assert_allclose(d, wire_lengths(model, q, q0), atol=1e-9)
    h = 1e-6
    for k, name in enumerate(ALL):
        plus = wire_lengths(_rad(model, {name: h}), q, q0)
        minus = wire_lengths(_rad(model, {name: -h}), q, q0)
        np.testing.assert_allclose(
            dd[far, k], ((plus - minus) / (2 * h))[far], atol=1e-4, err_msg=name
        )


@settings(max_examples=30, deadline=None)
@given(q=batches)
def test_joint_jacobian_matches_finite_differences(viper, q):
    model = viper.nominal
    _, J = joint_jacobian(model, q)
    h = 1e-6
    for i in range(6):
        dq = np.zeros(6)
        dq[i] = h
        fd = (tool_position(model, q + dq) - tool_position(model, q - dq)) / (2 * h)
        np.testing.assert_allclose(J[:, :, i], fd, atol=2e-5)


@settings(max_examples=40, deadline=None)
@given(q=batches, err=errors)
def test_batch_equals_one_at_a_time(viper, q, err):
    """One configuration runs on floats, a batch on arrays: the same frames, bit for bit."""
    model = viper.model(err)
    batch = frames(model, q)
    per_row = with_errors(model, ["d1"], np.zeros((len(q), 1)))  # one model per row
    for f in (batch, frames(per_row, q)):
        for k, row in enumerate(q):
            single = frames(model, row[None])
            for name in ("x", "z", "o", "R_last"):
                np.testing.assert_array_equal(getattr(f, name)[k], getattr(single, name)[0])
    assert batch.x.shape == (len(q), 7, 3)
    assert batch.R_last.shape == (len(q), 3, 3)


def test_robot_model_takes_degrees_and_mm(viper):
    deg = viper.model({"th2": 1.0, "d4": 0.5})
    rad = _rad(viper.nominal, {"th2": np.radians(1.0), "d4": 0.5})
    np.testing.assert_allclose(deg.dh, rad.dh)
    assert deg.dh[1, 2] == np.radians(1.0)
    assert deg.dh[3, 3] == 295.5


def test_parameter_names():
    assert P.parse("a1", 6) == P.Param("a1", "a", 1)  # the paper's a1 = row 2's 75 mm
    assert P.parse("th6", 6).row == 5
    assert P.parse("al0", 6).row == 0
    for bad in ("a6", "th0", "d7", "x1", "al6"):
        with pytest.raises(ValueError, match=r"use th1\.\.th6"):
            P.parse(bad, 6)
