"""The controller solver's emulation against the Python reference: same answer to
≤ 1e-4 deg/mm (float64 and float32) on many random truths within Ω."""

from __future__ import annotations

import numpy as np
import pytest

from wirecal.gen.emulate import operation_counts, readings_from_log, run_controller
from wirecal.gen.tables import build_tables, sin_cosm1_small
from wirecal.solver.formats.log import parse_log
from wirecal.solver.measurements import check_log
from wirecal.solver.simulate import simulate_log
from wirecal.solver.solve import solve

SEEDS = range(12)


@pytest.fixture(scope="module")
def tables(viper, paper_plan):
    return build_tables(viper, paper_plan)


def _case(viper, plan, seed):
    rng = np.random.default_rng([seed, 77])
    truth = dict(zip(viper.parameters, rng.uniform(-4.5, 4.5, 10), strict=True))
    start = 2**23 - 15_000 if seed % 3 == 0 else None  # a counter that wraps
    log = parse_log(
        simulate_log(viper, plan, truth, seed=seed, counter_start=start), f"seed{seed}.csv"
    )
    ref = solve(viper, plan, check_log(log, plan, viper))
    return readings_from_log(log, plan), ref


@pytest.mark.parametrize("seed", SEEDS)
def test_emulation_matches_reference(viper, paper_plan, tables, seed):
    readings, ref = _case(viper, paper_plan, seed)
    sw_ref = ref.estimates["stepwise"].values
    joint_ref = ref.estimates["joint"].values
    for flavour, tol in (("float64", 1e-6), ("float32", 1e-4)):
        sw, polished = run_controller(tables, readings, flavour, polish=True)
        assert np.abs(sw - sw_ref).max() <= tol, (flavour, sw - sw_ref)
        assert np.abs(polished - joint_ref).max() <= tol, (flavour, polished - joint_ref)


def test_small_angle_polynomials_within_their_stated_bound():
    e = np.linspace(-0.0881, 0.0881, 2001)
    s, cm1 = sin_cosm1_small(e, 1.0)
    assert np.abs(s - np.sin(e)).max() <= 0.0881**7 / 5040 * 1.01
    assert np.abs(cm1 - (np.cos(e) - 1)).max() <= 0.0881**8 / 40320 * 1.01 + 1e-17


def test_operation_counts(viper, paper_plan, tables):
    readings, _ = _case(viper, paper_plan, 1)
    stepwise = operation_counts(tables, readings, polish=False)
    both = operation_counts(tables, readings, polish=True)
    assert set(stepwise) == {"add", "mul", "div", "sqrt"}
    # one square root per point and iteration: (69 points) × 5 iterations
    assert stepwise["sqrt"] == 69 * 5
    assert both["sqrt"] == 69 * 5 + 69 * 3
    assert 2e5 < stepwise["mul"] < 5e5
