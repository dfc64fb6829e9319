"""Run Monte Carlo calibrations against known truth.

Many simulated calibrations, their errors, and the Cramér–Rao bound of the plan measured
by the same statistic.

Each trial draws readings (noise, quantisation, zero readings, as :mod:`simulate`) on a
true robot, identifies the parameters, and compares the identified model with the true
one: parameter errors, and the tool-point error ‖p_true(q) − p_est(q)‖ over workspace
configurations q (per trial: mean and max over q; reported: averages over trials). The
bound's figure is the same statistic for Gaussian parameter errors with the CRB covariance.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from wirecal.solver.accuracy import crb, noise_covariance, workspace
from wirecal.solver.distance import wire_jacobian
from wirecal.solver.identify import Problem, joint, omega_vector, stepwise
from wirecal.solver.kinematics import repeat, tool_jacobian, tool_position, with_errors
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import measured_lengths


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
) -> MonteCarlo:
    """Calibrate T simulated robots; ``truths`` (T, m) in deg/mm, the plan's order."""
    rng = np.random.default_rng(seed)
    names = plan.order
    n = robot.n_joints
    errors = ErrorSet(names, n)
    truth = errors.to_internal(np.atleast_2d(truths))
    T = truth.shape[0]
    base = robot.nominal
    d = measured_lengths(
        with_errors(base, names, truth), plan, robot.encoder.mm_per_count, noise_mm, rng
    )
    q, step, _ = plan.all_points()
    problem = Problem(base, names, np.radians(q), np.radians(plan.theta0_deg), d, step)
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
        est_j = np.array(
            [
                errors.to_internal(
                    joint(Problem(base, names, problem.q, problem.q0, d[t], step), est_sw[t]).values
                )
                for t in range(T)
            ]
        )
        t_j = time.perf_counter() - t0 + t_sw  # the joint method starts from stepwise
        out["joint"] = _figures(
            est_j - truth, tool_errors(robot, names, est_j, truth, q_ws), errors, t_j
        )

    # The bound at the mean truth, for the noise model of the readings: per-point σ and
    # quantisation, plus the mean zero reading's error common to every length.
    sigma2 = noise_mm**2 + robot.encoder.mm_per_count**2 / 12
    J = wire_jacobian(with_errors(base, names, truth.mean(axis=0)), problem.q, problem.q0, names)[1]
    cov = crb(J, noise_covariance(len(q), np.sqrt(sigma2), np.sqrt(sigma2 / len(plan.steps))))
    draws = rng.multivariate_normal(np.zeros(len(names)), cov, size=max(T, 200))
    _, Jp = tool_jacobian(base, q_ws, names)
    tool_crb = np.linalg.norm(np.einsum("qim,tm->tqi", Jp, draws), axis=2)
    before = tool_errors(robot, names, np.zeros_like(truth), truth, q_ws).mean()
    return MonteCarlo(T, out, _figures(draws, tool_crb, errors, 0.0), float(before))
