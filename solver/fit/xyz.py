"""The controller's nominal x, y, z beside the joints: a cross-check, and refined joints.

A controller computes the TCP position it shows from its *unrounded* joints through its
nominal model. Against the robot file's forward kinematics at the logged joints:

* **cross-check** — the TCP in the flange frame t (unknown to wirecal) is fitted linearly,
  x_i − o_i = R_i t over the rows (o, R: the flange frame); a row whose disagreement
  ‖x_i − o_i − R_i t‖ exceeds what rounding can make — Σ_j ‖∂p/∂q_j‖·Δq/2 + √3·Δx/2, a
  hard bound for joints rounded to Δq and coordinates to Δx — and :data:`XYZ_REJECT`
  times the median disagreement (a controller whose model is not the robot file's) is
  flagged: a typo in its joints or its x, y, z; the TCP is fitted again without them;
* **refined joints** — each row's joints q, rounded to Δq, carry a uniform error of
  variance (Δq/√12)²; the three coordinates measure J_q·δq (the positional Jacobian at
  the TCP), with the coordinates' own rounding (Δx/√12)². The Gauss–Newton MAP estimate
  δq = K(e + J δq), K = σ_q²Jᵀ(σ_q²JJᵀ + σ_x²I)⁻¹, iterated twice and kept within ±Δq/2
  (the rounding cell), and its covariance σ_q²(I − KJ), which the quantisation floor of
  the refined fit uses.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.kinematics import Model, bends, frames, joint_jacobian, rigid_frames

XYZ_REJECT = 5.0
"""A row is flagged beyond this many times the median disagreement (and its rounding bound)."""


@dataclass(frozen=True)
class XyzCheck:
    """The controller's x, y, z against the nominal forward kinematics at the logged joints."""

    tcp_mm: np.ndarray  # (3,) the controller's TCP in the flange frame (fitted)
    disagreement_mm: np.ndarray  # (N,) ‖x_i − FK_i‖
    tolerance_mm: np.ndarray  # (N,) each row's limit (module docstring)
    flagged: tuple[int, ...]  # 0-based rows beyond their limit

    @property
    def agreement_rms_mm(self) -> float:
        """Return the RMS disagreement of the rows not flagged."""
        ok = np.ones(len(self.disagreement_mm), dtype=bool)
        ok[list(self.flagged)] = False
        return float(np.sqrt(np.mean(self.disagreement_mm[ok] ** 2))) if ok.any() else 0.0


def _tcp(o: np.ndarray, R: np.ndarray, xyz: np.ndarray, rows: np.ndarray) -> np.ndarray:
    A = R[rows].reshape(-1, 3)
    b = (xyz[rows] - o[rows]).reshape(-1)
    return np.linalg.lstsq(A, b, rcond=None)[0]


def check_xyz(
    base: Model,
    q_deg: np.ndarray,
    xyz_mm: np.ndarray,
    joint_resolution_deg: float,
    xyz_resolution_mm: float,
) -> XyzCheck:
    """Fit the controller's TCP and flag the rows that disagree (module docstring)."""
    q_rad = np.radians(q_deg)
    f = frames(base, q_rad)
    rigid = rigid_frames(base, q_rad) if bends(base) else f  # joint_jacobian's, any TCP
    o, R = f.o[:, -1], f.R_last
    rows = np.arange(len(q_deg))
    for _ in range(2):
        t = _tcp(o, R, xyz_mm, rows)
        dist = np.linalg.norm(xyz_mm - o - np.einsum("nij,j->ni", R, t), axis=1)
        _, J = joint_jacobian(Model(base.dh, t), q_rad, rigid)
        bound = np.linalg.norm(J, axis=1).sum(axis=1) * np.radians(joint_resolution_deg) / 2
        bound += np.sqrt(3) * xyz_resolution_mm / 2
        tol = np.maximum(bound, XYZ_REJECT * np.median(dist[rows]))
        rows = np.flatnonzero(dist <= tol)
    return XyzCheck(t, dist, tol, tuple(int(k) for k in np.flatnonzero(dist > tol)))


def refine_joints(
    base: Model,
    check: XyzCheck,
    q_deg: np.ndarray,
    xyz_mm: np.ndarray,
    joint_resolution_deg: float,
    xyz_resolution_mm: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Return joints refined from x, y, z (deg, (N, n)) and their covariance (rad², (N, n, n)).

    Flagged rows keep their logged joints and the rounding's covariance.
    """
    n = q_deg.shape[1]
    var_q = (np.radians(joint_resolution_deg) ** 2) / 12
    var_x = xyz_resolution_mm**2 / 12
    q0 = np.radians(q_deg)
    q = q0.copy()
    tcp = Model(base.dh, check.tcp_mm)
    half = np.radians(joint_resolution_deg) / 2
    for _ in range(2):
        p, J = joint_jacobian(tcp, q)
        S = var_q * J @ J.transpose(0, 2, 1) + var_x * np.eye(3)
        K = var_q * J.transpose(0, 2, 1) @ np.linalg.inv(S)  # (N, n, 3)
        innovation = xyz_mm - p + np.einsum("nij,nj->ni", J, q - q0)
        q = q0 + np.clip(np.einsum("nij,nj->ni", K, innovation), -half, half)
    cov = var_q * (np.eye(n) - K @ J)
    keep = list(check.flagged)
    q[keep] = q0[keep]
    cov[keep] = var_q * np.eye(n)
    return np.degrees(q), cov
