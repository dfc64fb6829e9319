"""Does the error budget's 95 % bound hold? Simulated calibrations checked against the truth.

One calibration here is what ``wirecal solve`` would see of a simulated run: a true robot
with offsets uniform within ±1 deg/mm, a realistic encoder (its scale drawn within the
robot file's tolerance, 0.5 K of warming, the gauge's error:
:func:`~wirecal.solver.simulate.realistic_encoder`), optionally the twin's unmodelled errors
(repeatability and gravity sag: :class:`~wirecal.solver.simulate.Unmodelled`), the log
read and checked, and :func:`~wirecal.solver.solve.solve`. Its true tool-point error is the
demo's: the mean over the budget's workspace of ‖p_true − p_est‖ for the recommended
estimate (:func:`~wirecal.solver.accuracy.error_vs_truth_mm`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.formats.log import parse_log
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.accuracy import error_vs_truth_mm, workspace
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, RunParameters
from wirecal.solver.simulate import EncoderTruth, Unmodelled, realistic_encoder
from wirecal.solver.solve import SolveResult, solve

GAUGE_LENGTH_MM = 500.0
"""The simulated reference gauge's certified nest distance (a catalogue gauge's)."""


def with_gauge(robot: Robot, uncertainty_mm: float = 0.002, repeats: int = 3) -> Robot:
    """Return ``robot`` with a reference gauge of :data:`GAUGE_LENGTH_MM` (the reference step)."""
    encoder = replace(
        robot.encoder,
        reference_length_mm=GAUGE_LENGTH_MM,
        reference_uncertainty_mm=uncertainty_mm,
        reference_repeats=repeats,
    )
    return replace(robot, encoder=encoder)


WILSON_Z = 1.959964
"""The normal quantile of a two-sided 95 % interval."""


@dataclass(frozen=True)
class Trial:
    """One simulated calibration: its true error, the budget's mean and bound (mm)."""

    error_mm: float
    mean_mm: float  # the budget's total (an RMS: the expected error)
    bound_mm: float  # the budget's 95 % bound
    scale_ppm: float  # the true encoder's scale error


def simulated_calibration(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    seed: int,
    *,
    unmodelled: Unmodelled | None = None,
    drift_mm_per_h: float = 0.0,
    run: RunParameters = DEFAULT_RUN,
    scale_ppm: float | None = None,
) -> tuple[SolveResult, EncoderTruth]:
    """Simulate a run of ``plan`` on the true arm and solve it; return it and the true encoder.

    The true arm is ``robot`` with the ``truth`` offsets, read by a realistic encoder drawn
    from ``seed`` (its zero drifting by ``drift_mm_per_h``; its scale ``scale_ppm`` off when
    given, else drawn), at the ``run`` settings.
    """
    encoder = realistic_encoder(
        robot.encoder,
        np.random.default_rng([seed, 4]),
        scale_ppm=scale_ppm,
        zero_drift_mm_per_h=drift_mm_per_h,
    )
    text = simulate_log(
        robot, plan, truth, seed=seed, encoder=encoder, unmodelled=unmodelled, run=run
    )
    log = parse_log(text, f"simulated run {seed}")
    return solve(robot, plan, check_log(log, plan, robot)), encoder


def trial(robot: Robot, plan: Plan, seed: int, unmodelled: Unmodelled | None) -> Trial:
    """Simulate, solve and judge one calibration (module docstring)."""
    truth = random_errors(robot, 1.0, np.random.default_rng([seed, 1]))
    result, encoder = simulated_calibration(robot, plan, truth, seed, unmodelled=unmodelled)
    best = result.recommended
    budget = result.budgets[best]
    error = error_vs_truth_mm(robot, truth, result.estimates[best].as_dict(), workspace(robot))
    return Trial(error, budget.total, budget.bound, encoder.scale_ppm)


def wilson(k: int, n: int, z: float = WILSON_Z) -> tuple[float, float]:
    """Return the Wilson score interval of a proportion k/n (95 % by default)."""
    p = k / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / (1 + z**2 / n)
    return float(centre - half), float(centre + half)


@dataclass(frozen=True)
class Scenario:
    """What a simulated run's encoder and speed are beyond the realistic defaults."""

    drift_mm_per_h: float = 0.0  # the zero's drift
    run: RunParameters = DEFAULT_RUN
    scale_ppm: float | None = None  # the true scale's error; None: drawn in the tolerance


@dataclass(frozen=True)
class ComplianceTrial:
    """One calibration of an arm whose file identifies compliances: both errors, both bounds.

    ``error_patch_mm``: the geometry alone (what the controller applies; the sag left in
    it) against the true, bent arm; ``error_compensated_mm``: the geometry and the
    identified compliances (targets compensated offline). Means over the workspace (mm).
    """

    error_patch_mm: float
    error_compensated_mm: float
    bound_mm: float  # bound95_mm
    bound_compensated_mm: float  # bound95_compensated_mm
    truth: dict[str, float]
    estimate: dict[str, float]
    std: dict[str, float]
    posterior: dict[str, tuple[float, float]]  # the unidentified compliances' (value, σ)


def compliance_trial(
    robot: Robot,
    plan: Plan,
    seed: int,
    unmodelled: Unmodelled | None,
    compliant: bool,
    encoder: Scenario = Scenario(),
) -> ComplianceTrial:
    """Simulate, solve and judge one calibration of a compliant (or rigid) true arm.

    ``robot`` lists ``compliances``; the truth draws them (:func:`random_errors`) or, for a
    rigid arm, sets them to 0. ``encoder``: the run's zero drift, speed and scale.
    """
    truth = random_errors(robot, 1.0, np.random.default_rng([seed, 1]))
    if not compliant:
        truth.update({n: -robot.nominal_value(n) for n in robot.compliances})
    result, _ = simulated_calibration(
        robot,
        plan,
        truth,
        seed,
        unmodelled=unmodelled,
        drift_mm_per_h=encoder.drift_mm_per_h,
        run=encoder.run,
        scale_ppm=encoder.scale_ppm,
    )
    joint = result.estimates["joint"]
    budget = result.budgets["joint"]
    believed = joint.as_dict()
    geometry = {n: v for n, v in believed.items() if n not in robot.compliances}
    ws = workspace(robot)
    return ComplianceTrial(
        error_vs_truth_mm(robot, truth, geometry, ws),
        error_vs_truth_mm(robot, truth, believed, ws),
        budget.bound,
        budget.bound if budget.bound_compensated is None else budget.bound_compensated,
        truth,
        believed,
        joint.std_by_name(),
        budget.posterior or {},
    )
