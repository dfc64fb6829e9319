"""A plan's predictions: the mean tool-point error of both estimators and the robot time."""

from __future__ import annotations

import numpy as np

from wirecal.solver.accuracy import noise_covariance, stepwise_map, tool_error, workspace
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    RunParameters,
    run_timeline,
)
from wirecal.solver.sensitivity import sensitivity


def robot_time(robot: Robot, plan: Plan, run: RunParameters = DEFAULT_RUN) -> float:
    """Estimate the run time (s) of a plan: :func:`~wirecal.solver.run_parameters.run_timeline`.

    Moves at the SPEED the wire allows, the settle rule and the readings per stop, the
    closing zero included: the time model the twin's clock and the simulated log's ``t_s`` share.
    """
    return run_timeline(robot, plan, run).total_s


def predicted_accuracy(
    robot: Robot,
    plan: Plan,
    sigma_mm: float = 0.01,
    prior: float = PlanOptions.prior,
    unplanned: tuple[str, ...] = (),
) -> dict[str, float]:
    """Return the mean tool-point error over the workspace (mm) of both estimators.

    Mean tool-point error over the workspace: for the joint estimate the Cramér–Rao bound
    (σ per reading plus the count's quantisation); for the stepwise estimate its linearised
    map A, noise A·C·Aᵀ plus the bias of parameters leaking into steps before their own,
    (A·J − I)·P·(A·J − I)ᵀ with true offsets of size ``prior`` (deg, mm). Parameters
    ``unplanned`` stay at their prior: each adds its own error of size ``prior`` to both.
    """
    model = robot.nominal
    q, step, _ = plan.all_points()
    names = plan.order
    errors = ErrorSet(names, robot.n_joints)
    J = errors.per_internal(sensitivity(model, q, plan.theta0_deg, names).psi)
    s2 = sigma_mm**2 + robot.encoder.mm_per_count**2 / 12
    C = noise_covariance(len(q), np.sqrt(s2), np.sqrt(s2 / len(plan.steps)))
    cov_joint = np.linalg.pinv(J.T @ np.linalg.solve(C, J))
    A = stepwise_map(J, step)
    E = A @ J - np.eye(len(names))
    P = np.diag(errors.to_internal(np.full(len(names), prior)) ** 2)
    ws = workspace(robot, 500)
    every = (*names, *unplanned)
    left = np.diag(
        ErrorSet(tuple(unplanned), robot.n_joints).to_internal(np.full(len(unplanned), prior)) ** 2
    )

    def with_unplanned(cov: np.ndarray) -> np.ndarray:
        out = np.zeros((len(every), len(every)))
        out[: len(names), : len(names)] = cov
        out[len(names) :, len(names) :] = left
        return out

    return {
        "joint": tool_error(model, every, with_unplanned(cov_joint), ws).mean_mm,
        "stepwise": tool_error(model, every, with_unplanned(A @ C @ A.T + E @ P @ E.T), ws).mean_mm,
    }
