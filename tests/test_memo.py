"""Results kept by their inputs' contents (issue 34): the same inputs, the same numbers, once."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest

from wirecal.formats.validation_files import load_setup
from wirecal.solver import bound, budget, identifiability, run_parameters
from wirecal.solver.bound import ErrorModel, bound_mm
from wirecal.solver.kinematics import tool_jacobian
from wirecal.solver.memo import Kept, digest
from wirecal.solver.validation import design
from wirecal.solver.validation.design import plate_grid

from .conftest import VIPER


@dataclass(frozen=True)
class _Pair:
    a: np.ndarray
    b: float | None


def test_the_digest_tells_apart_what_a_result_may_depend_on():
    x = np.arange(6.0).reshape(2, 3)
    one_bit = x.copy()
    one_bit.view(np.uint64)[1, 2] ^= 1  # the least bit of one value
    keys = [
        digest(x),
        digest(x.reshape(3, 2)),  # the same bytes, another shape
        digest(x.astype(np.float32)),
        digest(one_bit),
        digest(x, 0.95),
        digest(x, 0.9500000000000001),  # the next float
        digest(x, None),
        digest(x, 0),
        digest(_Pair(x, None)),
        digest(_Pair(x, 1.0)),
        digest((x,)),
        digest(np.array(5.0)),  # 0-d
        digest(np.array([5.0])),
    ]
    assert len(set(keys)) == len(keys)
    assert digest(x) == digest(x.copy()) == digest(np.asfortranarray(x))
    assert digest(_Pair(x, 1.0)) == digest(_Pair(x.copy(), 1.0))
    with pytest.raises(TypeError, match="no digest of a dict"):
        digest({"a": 1})
    with pytest.raises(TypeError, match="no digest of a ndarray"):  # of objects: addresses
        digest(np.array([1.0, None]))


def test_a_result_is_computed_once_and_the_store_stays_bounded():
    kept: Kept[float] = Kept(2)
    calls = []

    def compute(v: float):
        return lambda: calls.append(v) or v

    assert [kept.get(b"a", compute(1.0)), kept.get(b"a", compute(2.0))] == [1.0, 1.0]
    assert calls == [1.0]
    kept.get(b"b", compute(3.0))
    kept.get(b"c", compute(4.0))  # full: started afresh
    assert kept.get(b"a", compute(5.0)) == 5.0
    assert calls == [1.0, 3.0, 4.0, 5.0]


def test_a_bound_asked_again_is_the_same_number_without_drawing_again(monkeypatch):
    rng = np.random.default_rng(3)
    Jp = rng.normal(size=(50, 3, 4))
    model = ErrorModel(np.diag([1e-4, 2e-4, 1e-4, 3e-4]), np.full(4, 1e-3), np.zeros((0, 4)))
    first = bound_mm(Jp, model)

    def drawn(*args):
        raise RuntimeError("drawn again")

    monkeypatch.setattr(bound, "draws_of", drawn)
    assert bound_mm(Jp.copy(), model) == first  # kept: not drawn again
    with pytest.raises(RuntimeError, match="drawn again"):  # another model is drawn
        bound_mm(Jp, ErrorModel(model.cov, model.bias * 2, model.edges))


def test_kept_factors_and_jacobians_are_read_only_and_the_same_numbers(viper):
    J = np.random.default_rng(4).normal(size=(20, 5))
    s, vt = identifiability.right_svd(J)
    again = identifiability.right_svd(J.copy())
    assert again[0] is s
    assert again[1] is vt
    assert np.array_equal(s, np.linalg.svd(J, full_matrices=False)[1])  # computed once
    q = np.random.default_rng(5).uniform(-2, 2, size=(30, viper.n_joints))
    names = ("th2", "a2", "d3")
    Jp = budget._workspace_jacobian(viper.nominal, q, names)
    assert budget._workspace_jacobian(viper.nominal, q.copy(), names) is Jp
    assert np.array_equal(Jp, tool_jacobian(viper.nominal, q, names)[1])
    for a in (s, vt, Jp):
        with pytest.raises(ValueError, match="read-only"):
            a.flat[0] = 1.0


def test_a_moves_profile_is_kept_read_only_and_another_arm_has_its_own(viper, monkeypatch):
    rng = np.random.default_rng(6)
    a, b = rng.uniform(-60, 60, (2, 4, viper.n_joints))
    p0 = np.array([300.0, 0.0, 200.0])
    first = run_parameters.move_profiles(viper, viper.nominal, p0, a, b)
    fresh = run_parameters._profiles(viper, viper.nominal, p0, a, b)
    for f in dataclasses.fields(first):
        kept = getattr(first, f.name)
        assert np.array_equal(kept, getattr(fresh, f.name))  # the same numbers, bit for bit
        with pytest.raises(ValueError, match="read-only"):
            kept.flat[0] = 1.0

    def evaluated(*args):
        raise RuntimeError("evaluated again")

    monkeypatch.setattr(run_parameters, "_profiles", evaluated)
    assert run_parameters.move_profiles(viper, viper.nominal, p0.copy(), a.copy(), b) is first
    one_bit = viper.nominal.dh.copy()
    one_bit.view(np.uint64)[1, 1] ^= 1  # a_1 one bit longer: another arm
    for other in (
        (viper, dataclasses.replace(viper.nominal, dh=one_bit), p0, a, b),
        (viper, viper.nominal, p0 + 1e-9, a, b),
        (viper, viper.nominal, p0, a, b[::-1]),
        (
            dataclasses.replace(viper, joint_speed_deg_s=viper.joint_speed_deg_s * 2),
            viper.nominal,
            p0,
            a,
            b,
        ),
    ):
        with pytest.raises(RuntimeError, match="evaluated again"):
            run_parameters.move_profiles(*other)


def test_a_plates_grid_is_kept_read_only_and_another_setup_is_solved(viper, monkeypatch):
    setup = load_setup(VIPER / "validation.toml")
    index, points, targets = plate_grid(viper, setup)
    fresh = design._solved_grid(viper, setup, 1.0)
    assert index == fresh[0]
    assert np.array_equal(points, fresh[1])
    assert np.array_equal(targets, fresh[2])
    for a in (points, targets):
        with pytest.raises(ValueError, match="read-only"):
            a.flat[0] = 1.0

    def solved(*args):
        raise RuntimeError("solved again")

    monkeypatch.setattr(design, "_solved_grid", solved)
    again = plate_grid(viper, load_setup(VIPER / "validation.toml"))
    assert again[0] == index
    assert again[0] is not index
    assert again[1] is points
    assert again[2] is targets
    moved = dataclasses.replace(setup, plate_yaw_deg=setup.plate_yaw_deg + 1e-9)
    for other in ((viper, moved, 1.0), (viper, setup, 2.0)):
        with pytest.raises(RuntimeError, match="solved again"):
            plate_grid(*other)


def test_a_copy_of_a_kept_result_is_computed_once_and_changing_it_leaves_the_kept_one():
    kept: Kept[dict] = Kept(4)
    calls = []

    def compute() -> dict:
        calls.append(1)
        return {"x": np.array([1.0, 2.0])}

    first = kept.copy_of(b"k", compute)
    first["x"][0] = 99.0
    second = kept.copy_of(b"k", compute)
    assert len(calls) == 1
    assert second is not first
    assert second["x"] is not first["x"]
    assert second["x"].tolist() == [1.0, 2.0]
