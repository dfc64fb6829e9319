"""Accuracy of a calibration: estimator covariances, tool-point errors.

How accurate a calibration is: covariances of the estimators and their effect on the
tool point over the workspace.

* Cramér–Rao bound: for wire lengths with noise covariance C, no unbiased estimator does
  better than (Jᵀ C⁻¹ J)⁻¹ (J the wire-length Jacobian).
* The stepwise estimator, linearised, is a linear map A of the measured lengths: step j
  takes g_jᵀ(ỹ_{S_j} − Ψ_{S_j,<j}·ê_{<j}) with g_j = Ψ_{S_j,j}/‖Ψ_{S_j,j}‖², so its
  covariance is A C Aᵀ (bias from later parameters leaking in is not included).
* A covariance Σ of the parameters becomes the tool-point error e(q) = J_p(q)·Δe,
  Δe ~ N(0, Σ), over random configurations within the joint limits.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from wirecal.solver.kinematics import Model, tool_jacobian, tool_position
from wirecal.solver.robot import Robot

WORKSPACE_SAMPLES = 1000
WORKSPACE_SEED = 20261121


def workspace(robot: Robot, n: int = WORKSPACE_SAMPLES, seed: int = WORKSPACE_SEED) -> np.ndarray:
    """N configurations uniform within the joint limits (radians), the same every call."""
    rng = np.random.default_rng(seed)
    return np.radians(rng.uniform(robot.joint_min_deg, robot.joint_max_deg, (n, robot.n_joints)))


def noise_covariance(n: int, sigma_mm: float, sigma_zero_mm: float = 0.0) -> np.ndarray:
    """Return the covariance of n wire lengths.

    Independent σ per point, plus the error of the zero reading that every length is
    measured from (common to all).
    """
    return sigma_mm**2 * np.eye(n) + sigma_zero_mm**2 * np.ones((n, n))


def crb(J: np.ndarray, C: np.ndarray) -> np.ndarray:
    """Cramér–Rao bound (Jᵀ C⁻¹ J)⁻¹ of the parameters (units of J's columns)."""
    return np.linalg.pinv(J.T @ np.linalg.solve(C, J))


def stepwise_map(psi: np.ndarray, step: np.ndarray) -> np.ndarray:
    """Return the linearised stepwise estimator as a matrix A (m, N): ê = A·ỹ (see module doc)."""
    N, m = psi.shape
    A = np.zeros((m, N))
    for j in range(m):
        sel = step == j + 1
        pj = psi[sel, j]
        denom = float(pj @ pj)
        if denom == 0:
            continue
        E = np.zeros((int(sel.sum()), N))
        E[np.arange(E.shape[0]), np.flatnonzero(sel)] = 1.0
        A[j] = (pj / denom) @ (E - psi[sel, :j] @ A[:j])
    return A


@dataclass(frozen=True)
class ToolError:
    """Tool-point error over workspace configurations (mm)."""

    mean_mm: float  # mean over configurations of the RMS error
    max_mm: float  # worst configuration's RMS error

    def as_dict(self) -> dict[str, float]:
        """Return the mean and max (mm) by name."""
        return {"mean": self.mean_mm, "max": self.max_mm}


def tool_error(model: Model, names: Sequence[str], cov: np.ndarray, q: np.ndarray) -> ToolError:
    """Return the RMS tool-point error at each configuration.

    RMS tool-point error sqrt(trace(J_p Σ J_pᵀ)) at each configuration q (radians);
    ``cov`` in internal units (rad, mm).
    """
    return rms_tool_error(tool_jacobian(model, q, names)[1], cov)


def rms_tool_error(Jp: np.ndarray, cov: np.ndarray) -> ToolError:
    """Return the RMS tool-point error for the tool-point Jacobian ``Jp`` (Q, 3, m) over Q."""
    rows = Jp.reshape(-1, Jp.shape[2])  # one row per configuration and axis
    rms = np.sqrt(np.sum((rows @ cov) * rows, axis=1).reshape(-1, 3).sum(axis=1))
    return ToolError(float(rms.mean()), float(rms.max()))


def error_vs_truth_mm(
    robot: Robot, truth: dict[str, float], believed: dict[str, float], q: np.ndarray
) -> float:
    """Return the tool-point error against the truth: mean over ``q`` of ‖p_true − p_believed‖.

    The quantity the error budget's bound bounds (:mod:`wirecal.solver.bound`); ``truth``
    and ``believed`` are offsets (deg, mm) by name, ``q`` configurations (radians).
    """
    d = tool_position(robot.model(believed), q) - tool_position(robot.model(truth), q)
    return float(np.linalg.norm(d, axis=1).mean())
