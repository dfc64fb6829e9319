"""Rules the README states, each pinned by a number computed by hand (not by the code under
test), so that changing the rule fails a test."""

from __future__ import annotations

import math

import numpy as np
import pytest

from wirecal.solver.accuracy import tool_error
from wirecal.solver.cell.clearance import wire_clearance, wire_trim_mm
from wirecal.solver.kinematics import Model
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.steps import isolating, step_error
from wirecal.solver.sensitivity import PSI_FLOOR, verdict


def test_psi_below_the_floor_counts_as_zero():
    # README (wirecal psi): values below 0.005 count as zero. With |Ψ_j| = 0.02 and
    # TOL = 0.15 the relative limit is 0.003, so the floor 0.005 decides.
    assert PSI_FLOOR == 0.005
    assert verdict({"a": 0.02, "b": 0.0049}, "a", ["b"], tol=0.15).ok
    assert verdict({"a": 0.02, "b": 0.0051}, "a", ["b"], tol=0.15).violations == ("b",)
    # Above the floor the relative rule decides: 0.15 · 2.0 = 0.3.
    assert verdict({"a": 2.0, "b": 0.29}, "a", ["b"], tol=0.15).ok
    assert not verdict({"a": 2.0, "b": 0.31}, "a", ["b"], tol=0.15).ok


def _planar_arm() -> Model:
    """Two joints about z, a 300 mm link, the tool point 100 mm further along x."""
    dh = np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 300.0, 0.0, 0.0]])
    return Model(dh=dh, tool_point=np.array([100.0, 0.0, 0.0]))


def test_tool_error_is_the_mean_over_configurations_of_the_rms():
    # th1's error rotates the tool point about the base z axis: its RMS error at a
    # configuration is σ times the point's distance from the axis. With joint 2 at 0 and
    # 90 deg that distance is 400 mm and hypot(300, 100) mm.
    sigma_rad = 1e-3
    q = np.radians([[0.0, 0.0], [0.0, 90.0]])
    err = tool_error(_planar_arm(), ["th1"], np.array([[sigma_rad**2]]), q)
    r = np.array([400.0, math.hypot(300.0, 100.0)]) * sigma_rad
    assert err.mean_mm == pytest.approx(r.mean(), rel=1e-12)
    assert err.max_mm == pytest.approx(r.max(), rel=1e-12)


def test_the_wire_end_at_the_fixture_is_left_out_of_the_clearance():
    # The capsule of link 1 runs from the origin to (300, 0, 0), radius 20; the tool point
    # is at (400, 0, 0) and the encoder at (400, 200, 0): a 200 mm wire along −y.
    model, q = _planar_arm(), np.zeros((1, 2))
    encoder, radii = np.array([400.0, 200.0, 0.0]), np.array([20.0])
    # Whole wire: its end (400, 0) is 100 mm from the capsule's end (300, 0).
    assert wire_clearance(model, q, encoder, radii, 0.0)[0] == pytest.approx(100.0 - 20.0)
    # Trimmed by 150 mm the wire ends at (400, 150): hypot(100, 150) from (300, 0).
    gap = wire_clearance(model, q, encoder, radii, 150.0)[0]
    assert gap == pytest.approx(math.hypot(100.0, 150.0) - 20.0)


def test_the_trim_is_tool_offset_plus_last_link_radius_plus_15_mm(viper):
    # The Viper's wire attachment point (−60, 0, 50) mm and last link radius 35 mm
    # (examples/viper_s650/robot.toml).
    assert wire_trim_mm(viper) == pytest.approx(math.hypot(60.0, 50.0) + 37.0 + 15.0)


def test_the_planner_counts_the_leak_of_earlier_estimates():
    # Two points with Ψ_j = 1, one earlier parameter with Ψ = 1 at both, no later one:
    # the step's estimate inherits the earlier estimate's error one for one, so its
    # expected squared error is σ²/2 plus the earlier variance (0.04).
    opt = PlanOptions(sigma_mm=0.011)
    psi_j = np.array([1.0, 1.0])
    earlier = np.array([[1.0], [1.0]])
    none = np.zeros((2, 0))
    value = step_error(psi_j, earlier, np.array([[0.04]]), none, opt)
    assert value == pytest.approx(0.011**2 / 2 + 0.04, rel=1e-12)
    # Later parameters leak in with the prior: Ψ_t = 0.5 at both points, prior 0.5.
    later = np.array([[0.5], [0.5]])
    value = step_error(psi_j, none, np.zeros((0, 0)), later, opt)
    assert value == pytest.approx(0.011**2 / 2 + opt.prior**2 * 0.5**2, rel=1e-12)


def test_the_planner_isolates_by_the_psi_rule():
    # The planner's isolating points (plan_steps.isolating) follow the one rule of
    # wirecal psi (sensitivity.within_tolerance): |Ψ_t| ≤ max(tol·|Ψ_j|, 0.005), and the
    # planner's own |Ψ_j| ≥ 0.05. With tol = 0.05: 0.05 · 2.0 = 0.1 (equal passes);
    # 0.05 · 0.06 = 0.003 < 0.005, so the floor decides at |Ψ_j| = 0.06.
    psi = np.array(
        [[2.0, 0.1], [2.0, 0.1001], [0.06, 0.0049], [0.06, 0.0051], [0.049, 0.0], [0.05, 0.0]]
    )
    found = isolating(psi, {"j": 0, "t": 1}, "j", ["j", "t"], PlanOptions(tol=0.05))
    assert found.tolist() == [True, False, True, False, False, True]
    alone = isolating(psi, {"j": 0, "t": 1}, "j", ["j"], PlanOptions(tol=0.05))
    assert alone.tolist() == [True, True, True, True, False, True]  # no other: |Ψ_j| only
