"""The solvers ask for less of the model: what they skip gives the very numbers.

A chain continued from kept frames (:func:`~wirecal.solver.kinematics._continued_chain`),
a Jacobian taken only where the fit's solver accepts a step, identifications kept by
their inputs.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.solver import identify
from wirecal.solver import kinematics as K
from wirecal.solver.fit.solver import minimised

_TABLE = st.lists(
    st.floats(-3.0, 3.0, allow_nan=False, allow_subnormal=False), min_size=24, max_size=24
)


def _bits(f: K.Frames) -> list[bytes]:
    return [np.ascontiguousarray(a).tobytes() for a in (f.x, f.z, f.o, f.R_last)]


def _fresh() -> None:
    """Forget the kept frames (the exact ones and the chains to continue)."""
    K._kept_frames.cache_clear()
    K._PREFIXES.clear()


@settings(max_examples=60, deadline=None)
@given(
    table=_TABLE,
    joints=st.integers(2, 20),
    tables=st.sampled_from([0, 1, 3]),
    row=st.integers(0, 5),
    column=st.integers(0, 3),
    delta=st.floats(-0.1, 0.1, allow_nan=False).filter(lambda v: v != 0.0),
    seed=st.integers(0, 2**16),
)
def test_a_continued_chain_is_the_whole_chain_bit_for_bit(
    table, joints, tables, row, column, delta, seed
):
    """Frames of a table differing from the one before in one joint's row on: the same bits
    as the recurrence over every joint (``_chain``, nothing kept), for one table or one per
    configuration; and the frames before that joint are the kept ones."""
    _fresh()
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, (joints, 6))
    dh = np.array(table).reshape(6, 4)
    if tables:  # one table per configuration, as the stepwise identification's
        dh = np.repeat(dh[None], joints, axis=0) + rng.normal(0, 1e-3, (joints, 6, 4)) * (
            tables > 1
        )
    first = K.rigid_frames(K.Model(dh, np.zeros(3)), q)
    changed = dh.copy()
    changed[..., row, column] += delta
    got = K.rigid_frames(K.Model(changed, np.zeros(3)), q)
    assert _bits(got) == _bits(K._frames_of(*K._chain(changed, q)))
    assert got.o[:, : row + 1].tobytes() == first.o[:, : row + 1].tobytes()


def test_a_row_differing_in_the_sign_of_a_zero_is_not_the_same_row():
    """−0.0 and 0.0 are equal numbers but not the same bits: the chain is computed again."""
    dh = np.zeros((2, 6, 4))
    assert K._same_rows(dh, dh.copy()) == 6
    signed = dh.copy()
    signed[:, 2, 3] = -0.0
    assert K._same_rows(dh, signed) == 2


def test_the_stepwise_identification_turns_fewer_joints(viper):
    """The stepwise steps vary one joint's parameter: its chains go on from that joint (the
    paper's order, last joint first, skips most of them), with the numbers of a run whose
    every chain starts at the base."""
    problem, omega = _viper_problem(viper)
    turns = []
    original, continued = K._turn, K._continued_chain

    def counted(*args):
        turns.append(1)
        return original(*args)

    def whole(dh, q, key):
        return K._chain(dh, q)

    runs = {}
    K._turn = counted
    try:
        for name, chain in (("kept", continued), ("whole", whole)):
            _fresh()
            turns.clear()
            K._continued_chain = chain
            runs[name] = identify._stepwise(problem, omega, 50), len(turns)
    finally:
        K._turn, K._continued_chain = original, continued
    assert runs["kept"][0][0].tobytes() == runs["whole"][0][0].tobytes()
    assert runs["kept"][1] < 0.8 * runs["whole"][1]


def _viper_problem(robot):
    """The stepwise problem of a simulated calibration of the Viper, 4 points a step."""
    from wirecal.solver.distance import wire_lengths

    model = robot.model({})
    rng = np.random.default_rng(3)
    names = ("th6", "d6", "th5", "th4", "a3", "d4", "a2", "th3", "th2", "a1")
    q, q0 = rng.uniform(-1.5, 1.5, (40, 6)), np.zeros(6)
    step = np.repeat(np.arange(1, 11), 4)
    d = wire_lengths(K.with_errors(model, names, rng.uniform(-1e-3, 1e-3, 10)), q, q0)
    return identify.Problem(model, names, q, q0, d, step), np.full(len(names), 0.1)


def test_an_identification_asked_again_is_kept_and_each_caller_has_its_own(viper):
    """The same inputs: the same numbers, computed once, and a caller changing its copy
    changes no other's."""
    problem, omega = _viper_problem(viper)
    calls = []
    original = identify._stepwise

    def counted(*args):
        calls.append(1)
        return original(*args)

    identify._SOLUTIONS._kept.clear()
    identify._stepwise = counted
    try:
        first, _ = identify.stepwise(problem, omega)
        kept = first.copy()
        first[:] = 99.0
        second, _ = identify.stepwise(problem, omega)
    finally:
        identify._stepwise = original
    assert len(calls) == 1
    assert second.tobytes() == kept.tobytes()
    a = identify.joint(problem, second)
    a.values[:] = 0.0
    b = identify.joint(problem, second)
    assert not np.all(b.values == 0.0)


def test_the_fit_solver_takes_the_jacobian_only_where_it_accepts_a_step():
    """A Jacobian given as a function: called at the start and at each accepted point only,
    and the same solution, bit for bit, as with the Jacobian given at every point."""
    t = np.linspace(0, 4, 200)
    noise = np.random.default_rng(0).normal(0, 0.01, t.size)
    y = 2.0 * np.exp(-0.7 * t) + 0.5 * np.sin(3.0 * t) + noise

    def residual(x):
        return x[0] * np.exp(-x[1] * t) + x[2] * np.sin(x[3] * t) - y

    def jac(x):
        e, s = np.exp(-x[1] * t), np.sin(x[3] * t)
        return np.column_stack([e, -x[0] * t * e, s, x[2] * t * np.cos(x[3] * t)])

    asked, evaluated = [], []

    def deferred(x):
        evaluated.append(1)
        return residual(x), lambda: asked.append(1) or jac(x)

    x0 = np.array([3.0, 0.5, 1.0, 3.5])  # far enough that steps are refused (11 of 21)
    got = minimised(deferred, x0, loss="soft_l1", f_scale=0.05)
    eager = minimised(lambda x: (residual(x), jac(x)), x0, loss="soft_l1", f_scale=0.05)
    assert all(a.tobytes() == b.tobytes() for a, b in zip(got, eager, strict=True))
    assert len(asked) <= len(evaluated) - 5
