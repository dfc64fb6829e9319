"""The core types: the error set's units (deg/mm at the boundary, rad/mm inside), the
controller's wrapping counter of any width the robot file allows, the robot's nominal
model and the inverse kinematics taking its limits from the robot."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.solver import params as P
from wirecal.solver.counter import Counter
from wirecal.solver.ik.solutions import flange_pose, solve
from wirecal.solver.params import ErrorSet


@st.composite
def error_sets(draw):
    n = draw(st.integers(1, 8))
    names = draw(st.lists(st.sampled_from(P.all_names(n, with_tool=True)), unique=True))
    return ErrorSet(tuple(names), n)


# Offsets and derivatives of physical size: |x| from 1e-200 up to 1e6 or 0 (a product with
# π/180 near the smallest normal double would lose digits to subnormal rounding).
finite = st.one_of(
    st.just(0.0),
    st.floats(1e-200, 1e6) | st.floats(-1e6, -1e-200),
)


@settings(max_examples=100, deadline=None)
@given(es=error_sets(), data=st.data())
def test_error_set_round_trip_and_chain_rule(es, data):
    m = len(es)
    b = np.array(data.draw(st.lists(finite, min_size=m, max_size=m)))
    np.testing.assert_allclose(es.to_boundary(es.to_internal(b)), b, rtol=1e-15, atol=0)
    np.testing.assert_allclose(es.to_internal(es.to_boundary(b)), b, rtol=1e-15, atol=0)
    # a derivative per internal unit, turned per boundary unit, gives the same change
    J = np.array(data.draw(st.lists(finite, min_size=m, max_size=m)))
    np.testing.assert_allclose(es.per_boundary(J) @ b, J @ es.to_internal(b), rtol=1e-12, atol=1e-6)
    np.testing.assert_allclose(es.per_internal(es.per_boundary(J)), J, rtol=1e-15, atol=0)


def test_error_set_units_columns_and_rows():
    es = ErrorSet(("th2", "al3", "a1", "d6", "tool_z"), 6)
    assert es.units == ("deg", "deg", "mm", "mm", "mm")
    assert es.angular.tolist() == [True, True, False, False, False]
    assert es.columns.tolist() == [2, 0, 1, 3, -1]  # θ offset, α, a, d; tool: none
    assert es.rows.tolist() == [1, 3, 1, 5, 2]  # th2 → row 2, a1 → row 2 (a_{i-1})
    internal = es.to_internal([180.0, -90.0, 2.5, -1.0, 3.0])
    np.testing.assert_allclose(internal, [math.pi, -math.pi / 2, 2.5, -1.0, 3.0], rtol=1e-15)
    np.testing.assert_allclose(es.to_boundary([math.pi, 0, 0, 0, 0])[0], 180.0, rtol=1e-15)


@pytest.mark.parametrize(
    ("name", "unit"),
    [
        ("th2", "deg"),
        ("al0", "deg"),
        ("al12", "deg"),
        ("a0", "mm"),
        ("d6", "mm"),
        ("tool_x", "mm"),
        ("c3", "urad/Nm"),
    ],
)
def test_unit_of_a_name_without_an_arm(name, unit):
    """The deg/mm rule from the name alone: al before a, tool_* a length."""
    assert P.unit_of(name) == unit


def test_one_unit_table_words_and_factors():
    assert P.UNIT_KINDS == {"deg": "th, al", "mm": "a, d, tool"}
    assert P.INTERNAL_PER_BOUNDARY["deg"] == pytest.approx(0.017453292519943295, rel=1e-15)
    assert P.BOUNDARY_PER_INTERNAL == {
        "deg": pytest.approx(57.29577951308232, rel=1e-15),
        "mm": 1,
        "urad/Nm": pytest.approx(1e6, rel=1e-15),  # compliances: µrad/(N·m) outside
    }


def test_error_set_refuses_an_unknown_parameter():
    with pytest.raises(ValueError, match=r"use th1\.\.th6"):
        ErrorSet(("th7",), 6)


def _wrapped(x: int, bits: int) -> int:
    """Exact integer reference: x brought into [−2^(bits−1), 2^(bits−1))."""
    half = 2 ** (bits - 1)
    return (x + half) % 2**bits - half


exact = st.integers(-(2**52), 2**52)


@settings(max_examples=200, deadline=None)
@given(bits=st.integers(8, 64), x=exact)
def test_counter_wrap_matches_integer_arithmetic(bits, x):
    c = Counter(bits)
    got = float(c.wrap(float(x)))
    assert got == _wrapped(x, bits)
    assert -c.half <= got < c.half


@settings(max_examples=200, deadline=None)
@given(bits=st.integers(8, 64), start=exact, data=st.data())
def test_counter_difference_undoes_a_wrap(bits, start, data):
    c = Counter(bits)
    reach = min(c.half - 1, 2**52 - abs(start))
    d = data.draw(st.integers(-reach, reach))
    assert float(c.difference(c.wrap(start + d), c.wrap(start))) == d


@settings(max_examples=50, deadline=None)
@given(bits=st.integers(8, 64), seed=st.integers(0, 2**32 - 1), within=st.sampled_from([0.5, 1]))
def test_counter_random_start_is_a_counter_value(bits, seed, within):
    c = Counter(bits)
    s = c.random_start(np.random.default_rng(seed), within)
    assert s == int(s)
    assert -c.half * within <= s < c.half * within
    assert abs(s) <= 2**52  # exact in a double


def test_counter_8_bits_by_hand():
    c = Counter(8)
    assert (c.half, c.full) == (128, 256)
    assert c.wrap(np.array([127.0, 128.0, -129.0, 300.0])).tolist() == [127, -128, 127, 44]
    assert float(c.difference(-126, 125)) == 5  # 125 → 127, wraps, → −126


@pytest.mark.parametrize("bits", [7, 65])
def test_counter_width_outside_the_robot_files_range(bits):
    with pytest.raises(ValueError, match="8 to 64"):
        Counter(bits)


def test_robot_counter_is_the_robot_files_width(viper):
    assert viper.encoder.counter == Counter(24)
    narrow = dataclasses.replace(viper, encoder=dataclasses.replace(viper.encoder, counter_bits=16))
    assert narrow.encoder.counter.half == 2**15


def test_robot_nominal_is_the_dh_table_cached_and_untouched(viper):
    nominal = viper.nominal
    assert nominal is viper.nominal  # cached
    np.testing.assert_array_equal(nominal.dh, viper.dh)
    np.testing.assert_array_equal(nominal.tool_point, viper.tool_point)
    assert viper.model({}) is nominal
    model = viper.model({"th2": 90.0, "a2": 0.5, "tool_x": -1.0})
    assert model.dh[1, 2] == viper.dh[1, 2] + math.pi / 2
    assert model.dh[2, 1] == viper.dh[2, 1] + 0.5
    assert model.tool_point[0] == viper.tool_point[0] - 1.0
    np.testing.assert_array_equal(viper.nominal.dh, viper.dh)  # the nominal is not changed


def test_ik_takes_the_limits_and_margin_from_the_robot(viper):
    q_deg = np.array([30.0, -60, 150, 20, 40, 30])
    R, o = flange_pose(viper.nominal, np.radians(q_deg))

    def found(robot, **kw):
        hit = [s for s in solve(robot, R, o, **kw) if np.allclose(np.degrees(s.q), q_deg)]
        assert len(hit) == 1
        return hit[0].within_limits

    assert found(viper)
    assert not found(viper, margin_deg=viper.joint_max_deg[4] - 40 + 0.5)  # j5 within margin
    tight = dataclasses.replace(viper, joint_max_deg=np.r_[29.0, viper.joint_max_deg[1:]])
    assert not found(tight)
    # the model the controller believes: a patched one finds the pose elsewhere
    patched = viper.model({"th1": 2.0})
    assert not any(np.allclose(np.degrees(s.q), q_deg) for s in solve(viper, R, o, model=patched))
