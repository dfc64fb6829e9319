"""The solvers ask for less of the model: what they skip gives the very numbers.

A Jacobian taken only where the fit's solver accepts a step, identifications kept by
their inputs.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver import identify
from wirecal.solver import kinematics as K
from wirecal.solver.fit.solver import minimised


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


def test_a_step_clipped_at_its_bound_does_not_evaluate_the_point_again(viper, monkeypatch):
    """An error beyond Ω: the step ends on the bound, where the clipped Gauss–Newton step
    is the point itself; each point of a step is evaluated once."""
    problem, omega = _viper_problem(viper)
    truth = np.zeros(len(problem.names))
    truth[0] = 0.05  # th6 by 2.9°, its bound 0.5°
    from wirecal.solver.distance import wire_lengths

    d = wire_lengths(K.with_errors(problem.base, problem.names, truth), problem.q, problem.q0)
    problem = identify.Problem(problem.base, problem.names, problem.q, problem.q0, d, problem.step)
    omega = np.full(len(problem.names), np.radians(0.5))
    points = []
    original = identify.wire_jacobian

    def recorded(model, q, q0, names):
        points.append((model.dh.tobytes(), q.tobytes(), tuple(names)))
        return original(model, q, q0, names)

    monkeypatch.setattr(identify, "wire_jacobian", recorded)
    x, _ = identify._stepwise(problem, omega, 50)
    assert x[0] == omega[0]  # on the bound
    assert len(points) == len(set(points))


def test_a_fit_asked_again_is_kept_and_each_caller_has_its_own(monkeypatch):
    """``fit_core`` of the same rows and options: computed once, the same numbers, and a
    caller changing its copy changes no other's; other options are another fit."""
    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.fit import calibrate as F
    from wirecal.solver.fit.result import _data
    from wirecal.solver.fit.synth import synthetic_table
    from wirecal.solver.memo import Kept

    from .conftest import VIPER

    robot = load_robot(VIPER / "robot.toml")
    table = synthetic_table(robot, 120, seed=5, sessions=1, snags=0, typos=0).table
    base = F.point_model(robot)
    data = _data(base, table.q_deg, table, (0.1, 0.01), None)
    calls = []
    original = F._fit_core
    monkeypatch.setattr(F, "_FITS", Kept(F.KEPT_FITS))
    monkeypatch.setattr(F, "_fit_core", lambda *a: calls.append(1) or original(*a))
    first = F.fit_core(base, data)
    kept = first.x.copy()
    first.x[:] = 0.0
    second = F.fit_core(base, data)
    assert len(calls) == 1
    assert second.x.tobytes() == kept.tobytes()
    F.fit_core(base, data, scale=True)
    assert len(calls) == 2
