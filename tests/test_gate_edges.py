"""The plausibility gate's documented thresholds at their edges: just inside passes, just
outside is refused by that check (README "Can the result be trusted?", solver/plausibility.py).
The edge values are the documented numbers, not read from the code under test."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from wirecal.formats.log import parse_log
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.distance import wire_lengths
from wirecal.solver.identifiability import analyse_jacobian
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plausibility import _identifiability, assess
from wirecal.solver.scale import Drift
from wirecal.solver.solve import solve

JUST = 1e-6  # relative step either side of an edge


@pytest.fixture(scope="module")
def sound(viper, paper_plan):
    """A sound solve of the corrected paper plan (passes every check)."""
    truth = random_errors(viper, 1.0, np.random.default_rng(3))
    text = simulate_log(viper, paper_plan, truth, seed=3)
    result = solve(viper, paper_plan, check_log(parse_log(text, "s.csv"), paper_plan, viper))
    assert assess(result, "joint").passed
    return result


def _checks(result, method="joint", **kw) -> set[str]:
    return {f.check for f in assess(result, method, **kw).findings}


@pytest.mark.parametrize(
    ("ratio", "refused"),
    [
        (2.0 * (1 - JUST), False),
        (2.0 * (1 + JUST), True),
        (0.5 * (1 + JUST), False),
        (0.5 * (1 - JUST), True),
    ],
)
def test_length_span_edges_are_half_and_twice_the_model(sound, ratio, refused):
    """Measured lengths exactly ``ratio`` × the nominal model's at the measured points."""
    m = sound.measurements
    model = wire_lengths(
        sound.robot.nominal, np.radians(m.joints_deg[m.present]), np.radians(m.theta0_deg)
    )
    d = m.distance_mm.copy()
    d[m.present] = ratio * model
    result = replace(sound, measurements=replace(m, distance_mm=d))
    assert ("lengths" in _checks(result)) is refused


def test_residual_edge_is_the_chi_square_bound_of_the_default_noise(sound):
    """README: the paper plan's limit is 0.031 mm with the default --noise-mm 0.02: σ_model² =
    0.02² + 0.025488²/12, χ²(59 dof) upper 10⁻⁶ quantile 125.665 (tables)."""
    limit = np.sqrt(0.02**2 + 0.025488**2 / 12) * np.sqrt(125.665 / 59)
    assert limit == pytest.approx(0.031, abs=0.0005)
    inside = replace(sound, sigma_mm=limit * (1 - 1e-4))  # the table's 6 digits
    outside = replace(sound, sigma_mm=limit * (1 + 1e-4))
    assert "residual" not in _checks(inside)
    assert "residual" in _checks(outside)
    # --noise-mm moves the edge: at 0.01 mm the same σ is refused
    assert "residual" in _checks(replace(sound, sigma_mm=0.02), noise_mm=0.01)
    assert "residual" not in _checks(replace(sound, sigma_mm=0.02))


def _with_value(result, method: str, name: str, value: float):
    est = result.estimates[method]
    values = est.values.copy()
    values[est.names.index(name)] = value
    return replace(result, estimates={**result.estimates, method: replace(est, values=values)})


@pytest.mark.parametrize("method", ["stepwise", "joint"])
def test_bound_edge_is_omega_default_5(sound, method):
    """README: refused on or beyond its Ω (default ±5): 4.999 passes, 5 and −5 are refused."""
    assert "bound" not in _checks(_with_value(sound, method, "th2", 5 * (1 - JUST)), method)
    assert "bound" in _checks(_with_value(sound, method, "th2", 5.0), method)
    assert "bound" in _checks(_with_value(sound, method, "a2", -5.0), method)


def test_plausible_size_edge_is_10_deg_and_10_mm(sound):
    """README: beyond 10 deg / 10 mm is refused (with Ω widened to 20 so Ω does not decide)."""
    for name in ("th3", "d4"):
        at = _with_value(sound, "joint", name, 10.0)
        beyond = _with_value(sound, "joint", name, -10.0 * (1 + JUST))
        assert "bound" not in _checks(at, omega_default=20.0)
        assert "bound" in _checks(beyond, omega_default=20.0)


def test_drift_edge_is_half_a_mm_per_hour_beyond_three_sigma(sound):
    """Refused when |b| − 3σ_b > 0.5 mm/h (scale.DRIFT_TOLERANCE_MM_PER_H) and removing it
    cannot correct the lengths (here: the zeros do not lie on a line)."""
    sigma_h = 0.1
    for rate_h, refused in ((0.8 * (1 - JUST), False), (0.8 * (1 + JUST), True)):
        drift = Drift(-rate_h / 3600, sigma_h / 3600, 100.0, 12, True, linear=False)
        assert ("drift" in _checks(replace(sound, drift=drift))) is refused


@pytest.mark.parametrize(
    ("rate_h", "sigma_h", "refused"),
    [
        (1.0, 0.1, False),  # issue 35: the paper's speed, 1 mm/h measured to ±0.1
        (1.6, 0.25 * (1 - JUST), False),  # known to the tolerance: 2σ ≤ 0.5 mm/h
        (1.6, 0.25 * (1 + JUST), True),
        (5.0 * (1 - JUST), 0.1, False),  # scale.DRIFT_REMOVABLE_MM_PER_H
        (-5.0 * (1 + JUST), 0.1, True),
    ],
)
def test_a_linear_drift_known_to_the_tolerance_is_removed_not_refused(
    sound, rate_h, sigma_h, refused
):
    drift = Drift(rate_h / 3600, sigma_h / 3600, 100.0, 12, True)
    assert ("drift" in _checks(replace(sound, drift=drift))) is refused
    assert (drift.warning is None) is refused


def test_poorly_identified_edge_is_a_sigma_of_1():
    """README: σ from reading noise alone at 1 deg/mm or more is refused. One parameter seen
    by 4 points of Ψ = c: σ = σ_model / (2c)."""
    sigma_model = 0.0213
    for c, refused in ((sigma_model / 2 * (1 + JUST), False), (sigma_model / 2 * (1 - JUST), True)):
        J = np.full((4, 1), c)
        findings = _identifiability(analyse_jacobian(J, ("a1",)), J, sigma_model)
        assert bool(findings) is refused
