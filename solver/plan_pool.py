"""Plan from what the robot can reach: θ0 and at most N poses out of a pool of configurations.

``wirecal plan --pool TABLE``: the pool is a table of configurations the robot is known to
reach (a tracker data set, a recorded program's points). The wire's fixed end is the tool
point at θ0 (the paper's eq. 7: a = p(θ0)), so choosing θ0 from the pool chooses the
anchor among reachable tool points; the wire model is ``wirecal fit``'s
(:mod:`~wirecal.solver.fit_model`: the anchor, one length offset, the attachment and the
identifiable DH errors).

For each of :data:`THETA0_TRIED` candidate θ0s, spread over the pool's nominal tool points
(farthest-point order from the pool's centre):

1. the rows whose wire length lies within the encoder's range less its margin, and
   beyond the shortest wire, are eligible (:class:`~wirecal.solver.plan_options.PlanOptions`:
   ``range_margin_mm``, ``min_wire_mm``);
2. the parameters are the fit's own choice over them (:func:`~wirecal.solver.fit.choose`),
   less any that moves no length there (θ_n with the attachment on its axis);
3. N rows are chosen greedily, each the one that lowers the predicted tool-point error
   over the pool most (:func:`greedy_rows`);
4. the plan's figure is the Cramér–Rao tool-point error over the pool,
   √trace(J_p Σ J_pᵀ) with Σ = σ²(JᵀJ)⁻¹, σ the reading noise ``sigma_mm``
   (:func:`~wirecal.solver.accuracy.tool_error`).

The θ0 of the least figure wins.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.accuracy import tool_error
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit import Data, choose, point_model
from wirecal.solver.fit_model import Layout, lengths_and_jacobian, model_of
from wirecal.solver.identifiability import covariance
from wirecal.solver.kinematics import Model, tool_jacobian, tool_position
from wirecal.solver.params import TOOL_NAMES
from wirecal.solver.plan_options import PlanOptions
from wirecal.solver.robot import Robot

THETA0_TRIED = 24
"""Candidate θ0s, spread over the pool's tool points."""

UNSEEN = 1e-9
"""A parameter whose column is this small against the largest moves no length: left out."""

RIDGE = 1e-6
"""ε of the greedy choice, relative to the mean squared (scaled) column norm."""


@dataclass(frozen=True)
class PoolPlan:
    """θ0 and the poses chosen from a pool, with the plan's predicted tool-point error."""

    theta0_row: int  # 0-based row of the pool
    rows: np.ndarray  # (≤ N,) 0-based rows of the pool, in the order chosen
    names: tuple[str, ...]  # the geometry the wire identifies there (attachment, DH errors)
    anchor_mm: np.ndarray  # (3,) the nominal tool point at θ0, base frame
    predicted_mm: float  # mean Cramér–Rao tool-point error over the pool
    theta0_tried: int
    outside: int = 0  # pool rows left out: beyond the robot file's joint limits


def spread(points: np.ndarray, k: int) -> np.ndarray:
    """Return ``k`` rows of ``points`` (N, 3) in farthest-point order from their centre."""
    d = np.linalg.norm(points - points.mean(axis=0), axis=1)
    chosen = [int(np.argmin(d))]
    d = np.linalg.norm(points - points[chosen[0]], axis=1)
    while len(chosen) < min(k, len(points)):
        chosen.append(int(np.argmax(d)))
        d = np.minimum(d, np.linalg.norm(points - points[chosen[-1]], axis=1))
    return np.array(chosen)


def greedy_rows(J: np.ndarray, W: np.ndarray, n: int) -> np.ndarray:
    """Return ``n`` rows of ``J`` (M, k) chosen one by one for the least tool-point error.

    The error is trace(W·(JᵀJ + εI)⁻¹), W = Σ J_pᵀJ_p over the pool (k, k; zero for the
    anchor and offset); a row j lowers it by vᵀWv / (1 + jᵀv), v = (JᵀJ + εI)⁻¹j, and the
    inverse follows by the Sherman–Morrison update.
    """
    norm = np.maximum(np.linalg.norm(J, axis=0), 1e-12)
    A, W = J / norm, W / np.outer(norm, norm)
    inv = np.eye(A.shape[1]) / (RIDGE * np.mean(np.sum(A**2, axis=0)))
    chosen: list[int] = []
    free = np.ones(len(A), dtype=bool)
    for _ in range(min(n, len(A))):
        V = A @ inv
        gain = np.einsum("ij,jk,ik->i", V, W, V) / (1.0 + np.sum(A * V, axis=1))
        i = int(np.argmax(np.where(free, gain, -np.inf)))
        inv -= np.outer(V[i], V[i]) / (1.0 + A[i] @ V[i])
        free[i] = False
        chosen.append(i)
    return np.array(chosen)


def _at_anchor(
    base: Model, q_rad: np.ndarray, row: int, n: int, sigma_mm: float, wire_mm: tuple[float, float]
) -> PoolPlan | None:
    """Return the best plan with θ0 at pool row ``row``; None when too few rows are eligible."""
    p = tool_position(base, q_rad)
    length = np.linalg.norm(p - p[row], axis=1)
    eligible = np.flatnonzero((length >= wire_mm[0]) & (length <= wire_mm[1]))
    layout = Layout(TOOL_NAMES, base.n_joints, 1, False)
    x = np.zeros(len(layout.names))
    x[3:6] = p[row]
    session = np.zeros(len(eligible), dtype=int)
    data = Data(q_rad[eligible], length[eligible], session, sigma_mm)
    layout, x, _ = choose(base, layout, x, data, np.arange(len(eligible)), sigma_mm)
    _, J = lengths_and_jacobian(base, layout, x, data.q_rad, session)
    norm = np.linalg.norm(J, axis=0)
    seen = norm > UNSEEN * norm.max()  # θ_n with the attachment on its axis moves nothing
    layout = replace(
        layout, geometry=tuple(np.array(layout.geometry)[seen[: len(layout.geometry)]])
    )
    x, J = x[seen], J[:, seen]
    if len(eligible) < len(layout.names) + 1:
        return None
    g = len(layout.geometry)
    model = model_of(base, layout, x)
    jp = tool_jacobian(model, q_rad, layout.geometry)[1].reshape(-1, g)
    W = np.zeros((J.shape[1], J.shape[1]))
    W[:g, :g] = jp.T @ jp
    picked = greedy_rows(J, W, n)
    cov, ok = covariance(J[picked], sigma_mm**2)
    if not ok.all():
        return None
    err = tool_error(model, layout.geometry, cov[:g, :g], q_rad)
    return PoolPlan(row, eligible[picked], layout.geometry, p[row], err.mean_mm, 0)


def plan_pool(robot: Robot, q_deg: np.ndarray, n_points: int, opt: PlanOptions) -> PoolPlan:
    """Choose θ0 and at most ``n_points`` poses of the pool ``q_deg`` (module docstring).

    Rows beyond the robot file's joint limits are left out (counted in ``outside``); the
    others are taken as reachable without collision, as the moves that recorded them.
    """
    base = point_model(robot)
    lo, hi = robot.limits_deg(0.0)
    inside = np.flatnonzero(np.all((q_deg >= lo) & (q_deg <= hi), axis=1))
    q_rad = np.radians(q_deg[inside])
    wire_mm = (opt.min_wire_mm, robot.encoder.range_mm - opt.range_margin_mm)
    tried = spread(tool_position(base, q_rad), THETA0_TRIED)
    plans = [_at_anchor(base, q_rad, int(r), n_points, opt.sigma_mm, wire_mm) for r in tried]
    found = [pl for pl in plans if pl is not None]
    if not found:
        raise WirecalError(
            f"no θ0 of the {len(tried)} tried leaves enough poses of the pool within the "
            f"encoder's range ({wire_mm[0]:g}–{wire_mm[1]:g} mm of wire) and the joint limits: "
            "give a pool that moves the tool around more, or an encoder of a longer range"
        )
    best = min(found, key=lambda pl: pl.predicted_mm)
    return PoolPlan(
        int(inside[best.theta0_row]),
        inside[best.rows],
        best.names,
        best.anchor_mm,
        best.predicted_mm,
        len(tried),
        len(q_deg) - len(inside),
    )
