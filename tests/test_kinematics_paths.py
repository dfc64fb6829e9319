"""The kinematics' and gravity's faster paths (issue 34) against independent references.

The chain of a long batch written block by block into its storage, the cross product
without ``np.cross``, the offsets added per table in one call, the centres of mass summed
without the rotations, and the sag skipped where it is zero: each gives the numbers of the
reference it replaces (``np.cross``; a Python loop of single sums; the textbook moment sum;
the random draws), bit for bit where the operations are the same.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from wirecal.solver import params as P
from wirecal.solver.gravity import STANDARD_GRAVITY_M_S2, MassModel, cross, gravity_torques_nm
from wirecal.solver.kinematics import frames, rigid_frames, with_errors
from wirecal.solver.rows import ROW_BLOCK
from wirecal.solver.simulate import Unmodelled
from wirecal.solver.zero_reading import joint_sigma_rad

FINITE = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    shape=st.tuples(st.integers(1, 5), st.integers(1, 4)),
    data=st.data(),
)
def test_cross_is_numpys_cross_bit_for_bit(shape, data):
    a = data.draw(arrays(np.float64, (*shape, 3), elements=FINITE))
    b = data.draw(arrays(np.float64, (shape[-1], 3), elements=FINITE))  # broadcast
    assert cross(a, b).tobytes() == np.cross(a, b).tobytes()
    into = np.empty((3, *shape)).transpose(*range(1, len(shape) + 1), 0)  # another order
    assert cross(a, b, out=into) is into
    assert into.tobytes() == np.cross(a, b).tobytes()
    a2, b2 = np.moveaxis(a, -1, -2), np.moveaxis(b, -1, -2)  # vectors along axis −2
    expected = np.moveaxis(np.cross(a, b), -1, -2)
    assert np.array_equal(cross(a2, b2, axis=-2), expected)
    assert cross(a2, b2, axis=-2).shape == expected.shape


def test_a_long_batch_built_block_by_block_is_each_blocks_frames(viper):
    """Over ROW_BLOCK rows the chain is written into one storage a block at a time."""
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, (ROW_BLOCK + 37, 6))
    model = viper.model({"th2": 0.3, "a2": 0.2})
    whole = rigid_frames(model, q)
    for rows in (slice(0, ROW_BLOCK), slice(ROW_BLOCK, None)):
        block = rigid_frames(model, q[rows])
        for name in ("x", "z", "o", "R_last"):
            assert np.array_equal(getattr(whole, name)[rows], getattr(block, name))
    assert not whole.o.flags.writeable


@settings(max_examples=60, deadline=None)
@given(
    picks=st.lists(st.integers(0, 32), min_size=1, max_size=12),
    rows=st.integers(0, 3),
    seed=st.integers(0, 2**32 - 1),
)
def test_offsets_are_added_one_name_at_a_time(viper, picks, rows, seed):
    """A name given twice is added twice, in order: a loop of single float sums."""
    pool = P.all_names(6, with_tool=True) + tuple(f"c{j}" for j in range(1, 7))
    names = [pool[k] for k in picks]
    rng = np.random.default_rng(seed)
    lead = () if rows == 0 else (rows,)
    values = rng.normal(0.0, 0.1, (*lead, len(names)))
    base = viper.nominal
    model = with_errors(base, names, values)
    for t in np.ndindex(*lead):
        dh, tool = base.dh.tolist(), base.tool_point.tolist()
        c = [0.0] * 6
        for k, name in enumerate(names):
            p, v = P.parse(name, 6), float(values[(*t, k)])
            if p.kind == "tool":
                tool[p.row] += v
            elif p.kind == "c":
                c[p.row] += v
            else:
                dh[p.row][P.DH_COLUMN[p.kind]] += v
        assert model.dh[t].tolist() == dh
        assert model.tool_point[t].tolist() == tool
        if model.compliance is not None:
            assert model.compliance[t].tolist() == c
    assert (model.compliance is None) == all(not n.startswith("c") for n in names)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_rows=st.integers(1, 40))
def test_gravity_torques_are_the_textbook_moment_sums(viper, seed, n_rows):
    """τ_j = z_j · Σ_{k≥j} (r_k − o_j) × m_k g ĝ, one link at a time (module docstring)."""
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=3)
    masses = MassModel(
        rng.uniform(0.0, 20.0, 6),
        rng.normal(0.0, 200.0, (6, 3)),
        direction=direction / np.linalg.norm(direction),
    )
    q = rng.uniform(-np.pi, np.pi, (n_rows, 6))
    f = frames(viper.nominal, q)
    tau = gravity_torques_nm(masses, f.x, f.z, f.o)
    weight = STANDARD_GRAVITY_M_S2 * masses.direction
    for i in range(n_rows):
        for j in range(6):
            moment = np.zeros(3)
            for k in range(j, 6):
                x, z = f.x[i, k + 1], f.z[i, k + 1]
                R = np.column_stack([x, np.cross(z, x), z])
                r = f.o[i, k + 1] + R @ masses.link_com_mm[k]
                moment += np.cross(r - f.o[i, j + 1], masses.link_mass_kg[k] * weight)
            expected = f.z[i, j + 1] @ moment / 1000.0
            assert abs(tau[i, j] - expected) <= 1e-9 * (1.0 + np.abs(moment).sum() / 1000.0)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n_rows=st.integers(1, 50), sigma_mm=st.floats(0, 0.1))
def test_no_sag_leaves_the_repeatabilitys_draws(viper, seed, n_rows, sigma_mm):
    """With no compliance the joints land by the draws alone (the sag is ±0)."""
    q = np.random.default_rng(seed).uniform(-180.0, 180.0, (n_rows, 6))
    unmodelled = Unmodelled(sigma_mm, 0.0)
    errors = unmodelled.joint_errors_deg(viper.nominal, q, np.random.default_rng(seed))
    sag = unmodelled.sag_deg(viper.nominal, q)  # computed, ±0 everywhere
    draws = np.random.default_rng(seed)
    expected = draws.normal(0.0, np.degrees(joint_sigma_rad(sigma_mm)), q.shape)
    assert np.array_equal(np.abs(sag), np.zeros_like(q))
    assert errors.tobytes() == expected.tobytes() == (expected - sag).tobytes()
