"""Run Monte Carlo calibrations against known truth.

Many simulated calibrations, their errors, and the Cramér–Rao bound of the plan measured
by the same statistic.

Each trial draws readings (noise, quantisation, zero readings, as :mod:`simulate`) on a
true robot, identifies the parameters, and compares the identified model with the true
one: parameter errors, and the tool-point error ‖p_true(q) − p_est(q)‖ over workspace
configurations q (per trial: mean and max over q; reported: averages over trials). The
bound's figure is the same statistic for Gaussian parameter errors with the CRB covariance.

With a true ``encoder`` (:class:`~wirecal.solver.simulate.EncoderTruth`) the readings carry
its scale and temperature; when the robot file gives a reference gauge, each trial reads
it first (pairs of nests, as :func:`~wirecal.solver.simulate.simulate_run`) and its
lengths are scaled by the measured k̂ (:func:`~wirecal.solver.scale.estimate_scale`), and
the joint method refines the scale as ``wirecal solve`` does. ``budget`` holds each
method's error budget (:mod:`wirecal.solver.budget`) for the same set-up: its prediction.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from wirecal.solver.accuracy import crb, noise_covariance, workspace
from wirecal.solver.budget import Budget, Sources, budget, sources
from wirecal.solver.distance import wire_jacobian
from wirecal.solver.identify import Problem, joint, omega_vector, stepwise
from wirecal.solver.kinematics import repeat, tool_jacobian, tool_position, with_errors
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.exit import unmodelled_exit_mm
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, run_timeline
from wirecal.solver.scale import PPM
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    NEST_A_MM,
    OPERATOR_SEAT_S,
    EncoderTruth,
    measured_lengths,
    reference_duration_s,
)


@dataclass(frozen=True)
class MethodFigures:
    """One method's Monte Carlo figures: parameter and tool-point errors, time."""

    param_rms_deg: float  # RMS error of angular parameters over trials
    param_rms_mm: float  # RMS error of length parameters
    tool_mean_mm: float  # mean over trials of the mean error over configurations
    tool_max_mm: float  # mean over trials of the worst configuration's error
    seconds: float  # identification time for all trials

    def rate(self, trials: int) -> float:
        """Return identifications per second for ``trials`` trials."""
        return trials / self.seconds if self.seconds > 0 else float("inf")


@dataclass(frozen=True)
class MonteCarlo:
    """A Monte Carlo run: each method's figures, the CRB's, and the uncalibrated error."""

    trials: int
    methods: dict[str, MethodFigures]
    crb: MethodFigures
    before_mm: float  # mean tool-point error of the uncalibrated (nominal) model
    budget: dict[str, Budget] = field(default_factory=dict)  # each method's prediction
    scale_error_ppm: float = 0.0  # RMS over trials of the scale left after the reference


def tool_errors(
    robot: Robot, names, est: np.ndarray, truth: np.ndarray, q_ws: np.ndarray
) -> np.ndarray:
    """‖p_true − p_est‖ (T, Q) for T estimated and true parameter vectors (internal units)."""
    T, Q = est.shape[0], len(q_ws)
    q = np.tile(q_ws, (T, 1))
    base = robot.nominal
    p_est = tool_position(repeat(with_errors(base, names, est), Q), q)
    p_true = tool_position(repeat(with_errors(base, names, truth), Q), q)
    return np.linalg.norm(p_est - p_true, axis=1).reshape(T, Q)


def _figures(err: np.ndarray, tool: np.ndarray, errors: ErrorSet, seconds: float) -> MethodFigures:
    """Figures of parameter errors ``err`` (T, m) in internal units and tool errors (T, Q)."""
    e, angular = errors.to_boundary(err), errors.angular
    return MethodFigures(
        param_rms_deg=float(np.sqrt(np.mean(e[:, angular] ** 2))) if angular.any() else 0.0,
        param_rms_mm=float(np.sqrt(np.mean(e[:, ~angular] ** 2))) if (~angular).any() else 0.0,
        tool_mean_mm=float(tool.mean(axis=1).mean()),
        tool_max_mm=float(tool.max(axis=1).mean()),
        seconds=seconds,
    )


def run(
    robot: Robot,
    plan: Plan,
    truths: np.ndarray,
    *,
    noise_mm: float = 0.01,
    seed: int = 0,
    n_workspace: int = 1000,
    methods: tuple[str, ...] = ("stepwise", "joint"),
    encoder: EncoderTruth = IDEAL_ENCODER,
) -> MonteCarlo:
    """Calibrate T simulated robots; ``truths`` (T, m) in deg/mm, the plan's order."""
    rng = np.random.default_rng(seed)
    names = plan.order
    n = robot.n_joints
    errors = ErrorSet(names, n)
    truth = errors.to_internal(np.atleast_2d(truths))
    T = truth.shape[0]
    base = robot.nominal
    mpc = robot.encoder.mm_per_count
    times = _times(robot, plan)
    problem, factor, scale_std = _measured(robot, plan, truth, noise_mm, rng, encoder, times)
    sigma_model = float(np.sqrt(noise_mm**2 + mpc**2 / 12))
    omega = omega_vector(names, n, plan)
    q_ws = workspace(robot, n_workspace)

    t0 = time.perf_counter()
    est_sw, _ = stepwise(problem, omega)
    t_sw = time.perf_counter() - t0
    out: dict[str, MethodFigures] = {}
    if "stepwise" in methods:
        out["stepwise"] = _figures(
            est_sw - truth, tool_errors(robot, names, est_sw, truth, q_ws), errors, t_sw
        )
    if "joint" in methods:
        t0 = time.perf_counter()
        est_j = _joint_estimates(problem, errors, est_sw)
        t_j = time.perf_counter() - t0 + t_sw  # the joint method starts from stepwise
        out["joint"] = _figures(
            est_j - truth, tool_errors(robot, names, est_j, truth, q_ws), errors, t_j
        )

    mean_model = with_errors(base, names, truth.mean(axis=0))
    d_mean, J = wire_jacobian(mean_model, problem.q, problem.q0, names)
    draws, tool_crb = _bound_draws(problem, J, len(plan.steps), sigma_model, q_ws, T, rng)
    before = tool_errors(robot, names, np.zeros_like(truth), truth, q_ws).mean()
    true_factor = 1 + encoder.scale_ppm * PPM
    src = _sources(robot, plan, sigma_model, d_mean, scale_std, times)
    budgets = {
        mth: budget(base, names, J, problem.step if mth == "stepwise" else None, src, q_ws)
        for mth in out
    }
    return MonteCarlo(
        T,
        out,
        _figures(draws, tool_crb, errors, 0.0),
        float(before),
        budgets,
        float(np.sqrt(np.mean((factor - true_factor) ** 2))) / PPM,
    )


def _measured(
    robot: Robot,
    plan: Plan,
    truth: np.ndarray,
    noise_mm: float,
    rng: np.random.Generator,
    encoder: EncoderTruth,
    times: tuple[np.ndarray, np.ndarray, float],
) -> tuple[Problem, np.ndarray, float | None]:
    """Return the problem of the T robots' simulated readings, their reference scale and σ.

    The lengths (T, N) are read by ``encoder`` and scaled by each run's reference factor
    (:func:`_reference`; its σ None without a reference gauge).
    """
    base, names = robot.nominal, plan.order
    mpc = robot.encoder.mm_per_count
    d = measured_lengths(with_errors(base, names, truth), plan, mpc, noise_mm, rng, encoder, times)
    factor, scale_std = _reference(robot, encoder, truth.shape[0], noise_mm, times[2], rng)
    q, step, _ = plan.all_points()
    d = d * factor[:, None]
    return (
        Problem(
            base, names, np.radians(q), np.radians(plan.theta0_deg), d, step, *(plan.loads() or ())
        ),
        factor,
        scale_std,
    )


def _joint_estimates(problem: Problem, errors: ErrorSet, est_sw: np.ndarray) -> np.ndarray:
    """Return the joint method's estimates (T, m), each robot's started from its stepwise one.

    ``problem.d`` holds the T robots' lengths (T, N); internal units.
    """
    return np.array(
        [
            errors.to_internal(joint(replace(problem, d=problem.d[t]), est_sw[t]).values)
            for t in range(len(est_sw))
        ]
    )


def _bound_draws(
    problem: Problem,
    J: np.ndarray,
    n_steps: int,
    sigma_mm: float,
    q_ws: np.ndarray,
    T: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Return draws of the parameters' error at the Cramér–Rao bound and their tool errors.

    The bound at the mean truth (``J`` there), for the noise model of the readings:
    per-point σ and quantisation, plus the mean zero reading's error common to every
    length. At least 200 draws.
    """
    sigma2 = sigma_mm**2
    n_points = J.shape[0]
    cov = crb(J, noise_covariance(n_points, np.sqrt(sigma2), np.sqrt(sigma2 / n_steps)))
    draws = rng.multivariate_normal(np.zeros(len(problem.names)), cov, size=max(T, 200))
    _, Jp = tool_jacobian(problem.base, q_ws, problem.names)
    return draws, np.linalg.norm(np.einsum("qim,tm->tqi", Jp, draws), axis=2)


def _sources(
    robot: Robot,
    plan: Plan,
    sigma_mm: float,
    d_mean: np.ndarray,
    scale_std: float | None,
    times: tuple[np.ndarray, np.ndarray, float],
) -> Sources:
    """Return the budget's sources for the simulated runs (no drift, no sag)."""
    return sources(
        sigma_mm,
        d_mean,
        robot.encoder.scale_tolerance_ppm * PPM if scale_std is None else scale_std,
        scale_std is not None,
        robot.encoder.temperature_coefficient_ppm_per_k,
        times[1],
        None,
        float(times[0].mean()),
        unmodelled_exit_mm(robot, plan),
        np.zeros(len(d_mean)),  # the simulated arm does not sag
        len(plan.steps),
        zero_corrected=robot.repeatability_mm is not None,
    )


def _times(robot: Robot, plan: Plan) -> tuple[np.ndarray, np.ndarray, float]:
    """Return the steps' zero times, the points' times (plan order) and the run's total."""
    timeline = run_timeline(robot, plan, DEFAULT_RUN)
    offset = reference_duration_s(robot.encoder)
    t = timeline.reading_s + offset
    _, step_no, _ = plan.all_points()
    n_steps = len(plan.steps)
    # the run order: each step's zero then its points (plan order); last the closing zero
    is_zero = np.concatenate(
        [np.r_[True, np.zeros(int(np.sum(step_no == j)), bool)] for j in range(1, n_steps + 1)]
    )
    return t[:-1][is_zero], t[:-1][~is_zero], timeline.total_s + offset


def _reference(
    robot: Robot,
    encoder: EncoderTruth,
    T: int,
    noise_mm: float,
    total_s: float,
    rng: np.random.Generator,
) -> tuple[np.ndarray, float | None]:
    """Return each trial's scale factor k̂ from the reference step (1 without) and its σ."""
    enc = robot.encoder
    if enc.reference_length_mm is None:
        return np.ones(T), None
    r = enc.reference_repeats
    gauge = rng.normal(0.0, enc.reference_uncertainty_mm, (T, 1))  # true − certified
    nest_b = np.tile([0.0, 1.0], r)
    physical = NEST_A_MM + (enc.reference_length_mm + gauge) * nest_b
    t = OPERATOR_SEAT_S * np.arange(2 * r)
    reading = physical * encoder.read_factor(t, total_s) + encoder.drift_mm(t)
    counts = np.floor((reading + rng.normal(0.0, noise_mm, reading.shape)) / enc.mm_per_count + 0.5)
    pairs = (counts[:, 1::2] - counts[:, 0::2]) * enc.mm_per_count
    sigma = float(np.sqrt(noise_mm**2 + enc.mm_per_count**2 / 12))
    std = float(np.sqrt(2 * sigma**2 / r + enc.reference_uncertainty_mm**2)) / (
        enc.reference_length_mm
    )
    return enc.reference_length_mm / pairs.mean(axis=1), std
