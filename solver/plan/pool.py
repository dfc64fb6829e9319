"""Plan from what the robot can reach: θ0 and at most N poses out of a pool of configurations.

``wirecal plan --pool TABLE``: the pool is a table of configurations the robot is known to
reach (a tracker data set, a recorded program's points). The wire's fixed end is the tool
point at θ0 (the paper's eq. 7: a = p(θ0)), so choosing θ0 from the pool chooses the
anchor among reachable tool points. The wire's fit is :mod:`~wirecal.solver.wire_prior`'s:
the anchor, one length offset, the attachment, every DH error of rows 2…n with a prior
where the readings are weak, and the compliances the robot file asks
(``[calibration] compliances``) with theirs.

What is planned for is what a tracker replay scores: the tool point's error over the whole
pool after a rigid registration (:func:`registered_weight`), predicted from the posterior
covariance P = (JᵀJ/σ² + Λ)⁻¹ (σ the reading noise ``sigma_mm``, Λ the prior's
precision), √trace(W·P) — the Cramér–Rao bound where the readings carry a parameter, its
prior where they do not, so a pool that cannot excite the geometry says so before any
measurement. For each of :data:`THETA0_TRIED` candidate θ0s, spread over the pool's
nominal tool points (farthest-point order from the pool's centre):

1. the rows whose wire length lies within the encoder's range less its margin, and
   beyond the shortest wire, are eligible (:class:`~wirecal.solver.plan.options.PlanOptions`:
   ``range_margin_mm``, ``min_wire_mm``);
2. N rows are chosen greedily, each the one that lowers the predicted error most
   (:func:`greedy_rows`: A-optimal on the registered tool point, compliance columns
   included when compliances are fitted);
3. the plan's figure is the predicted error with those rows.

The θ0 of the least figure wins.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.fit.model import Layout, lengths_and_jacobian
from wirecal.solver.kinematics import Model, tool_jacobian
from wirecal.solver.params import TOOL_NAMES
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot
from wirecal.solver.wire_prior import check_exit, prior_sigma, wire_layout

THETA0_TRIED = 24
"""Candidate θ0s, spread over the pool's tool points."""

RIDGE = 1e-6
"""ε of the greedy choice for the parameters without a prior (the attachment, the anchor,
the offset), relative to the mean squared (scaled) column norm."""


@dataclass(frozen=True)
class PoolPlan:
    """θ0 and the poses chosen from a pool, with the plan's predicted tool-point error."""

    theta0_row: int  # 0-based row of the pool
    rows: np.ndarray  # (≤ N,) 0-based rows of the pool, in the order chosen
    names: tuple[str, ...]  # the parameters the wire fit estimates (attachment, DH errors, c)
    anchor_mm: np.ndarray  # (3,) the nominal tool point at θ0, base frame
    predicted_mm: float  # RMS tool-point error over the pool after a rigid registration
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


def registered_weight(p_mm: np.ndarray, jp: np.ndarray) -> np.ndarray:
    """Return W (k, k): a parameter error δ moves the registered tool points by δᵀWδ (mean).

    ``p_mm`` (N, 3) the pool's tool points, ``jp`` (N, 3, k) their Jacobian. What is scored
    is the error left after the model's tool points are rigidly registered onto the
    measured ones (:func:`~wirecal.solver.tracker.fit.registered_rms_mm`): the part of
    J_p·δ that a small rotation and a translation of all the points reproduce, t + ω × p_i,
    is projected out.
    """
    c = p_mm - p_mm.mean(axis=0)
    g = np.zeros((len(c), 3, 6))
    g[:, :, :3] = np.eye(3)
    g[:, 0, 4], g[:, 0, 5] = c[:, 2], -c[:, 1]
    g[:, 1, 3], g[:, 1, 5] = -c[:, 2], c[:, 0]
    g[:, 2, 3], g[:, 2, 4] = c[:, 1], -c[:, 0]
    basis = np.linalg.qr(g.reshape(-1, 6))[0]
    j = jp.reshape(-1, jp.shape[2])
    left = j - basis @ (basis.T @ j)
    return left.T @ left / len(c)


def greedy_rows(
    J: np.ndarray, W: np.ndarray, n: int, prior_var: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Return ``n`` rows of ``J`` (M, k) chosen one by one for the least tool-point error.

    The error is trace(W·P), P = (JᵀJ + Λ)⁻¹ the posterior covariance (rows in units of
    the reading noise), Λ = diag(1 / ``prior_var``) (inf or None: ε, no prior); a row j
    lowers it by vᵀWv / (1 + jᵀv), v = P·j, and P follows by the Sherman–Morrison update.
    Returns the rows and P (internal units).
    """
    norm = np.maximum(np.linalg.norm(J, axis=0), 1e-12)
    A, W = J / norm, W / np.outer(norm, norm)
    var = np.full(A.shape[1], np.inf) if prior_var is None else prior_var * norm**2
    var = np.minimum(var, 1.0 / (RIDGE * np.mean(np.sum(A**2, axis=0))))
    inv = np.diag(var)
    chosen: list[int] = []
    free = np.ones(len(A), dtype=bool)
    for _ in range(min(n, len(A))):
        V = A @ inv
        i = _best_row(V, W, 1.0 + np.sum(A * V, axis=1), free)
        inv -= np.outer(V[i], V[i]) / (1.0 + A[i] @ V[i])
        free[i] = False
        chosen.append(i)
    return np.array(chosen), inv / np.outer(norm, norm)


def _best_row(V: np.ndarray, W: np.ndarray, denom: np.ndarray, free: np.ndarray) -> int:
    """Return the free row of the largest gain vᵀWv / ``denom`` (:func:`greedy_rows`).

    The gain's numerator is ``np.einsum("ij,jk,ik->i", V, W, V)``: per row, k² products
    summed in order, slow beside matrix products. Both it and the matrix products' sum r
    are within (k² + 2k + 3)·ε/2·S ≤ 3·k²·ε·S of the exact sum, S the sum of the products'
    magnitudes; the bounds r ± ``GAIN_ROUNDING``·k²·ε·S, over ``denom``, hold einsum's
    gain with room for their own rounding. A row whose upper bound is under the best lower
    bound cannot be the largest; einsum's numbers are computed for the others alone (row
    by row the same), and the first largest of them is the first largest over all rows.
    Without finite bounds and positive denominators (never in a plan) einsum takes all rows.
    """
    with np.errstate(all="ignore"):  # not finite: einsum's numbers below, and its warnings
        rough = np.sum((V @ W) * V, axis=1)
        slack = np.sum((np.abs(V) @ np.abs(W)) * np.abs(V), axis=1)
        slack *= GAIN_ROUNDING * W.shape[0] ** 2 * np.finfo(float).eps
        hi, lo = (rough + slack) / denom, (rough - slack) / denom
    sure = np.all(np.isfinite(hi[free]) & np.isfinite(lo[free]) & (denom[free] > 0))
    if not sure:
        gain = np.einsum("ij,jk,ik->i", V, W, V) / denom
        return int(np.argmax(np.where(free, gain, -np.inf)))
    near = np.flatnonzero(free & (hi >= np.max(lo[free])))
    gain = np.einsum("ij,jk,ik->i", V[near], W, V[near]) / denom[near]
    return int(near[np.argmax(gain)])


GAIN_ROUNDING = 16.0
"""The factor of k²·ε·S in :func:`_best_row`'s bounds: over five times the 3·k²·ε·S the
two sums can differ by."""


@dataclass(frozen=True)
class Pool:
    """What every θ0 shares: the wire's parameters, the pool and its registered weight W."""

    base: Model
    layout: Layout
    q_rad: np.ndarray  # (N, n)
    p_mm: np.ndarray  # (N, 3) nominal tool points
    weight: np.ndarray  # (k, k) W of :func:`registered_weight`, zero beyond the geometry
    prior_var: np.ndarray  # (k,) internal units; inf: no prior


def eligible_rows(p_mm: np.ndarray, row: int, wire_mm: tuple[float, float]) -> np.ndarray:
    """Return the rows of ``p_mm`` (N, 3) whose wire from row ``row`` lies within ``wire_mm``."""
    length = np.linalg.norm(p_mm - p_mm[row], axis=1)
    return np.flatnonzero((length >= wire_mm[0]) & (length <= wire_mm[1]))


def _at_anchor(
    pool: Pool, row: int, n: int, sigma_mm: float, wire_mm: tuple[float, float]
) -> PoolPlan | None:
    """Return the best plan with θ0 at pool row ``row``; None when too few rows are eligible."""
    eligible = eligible_rows(pool.p_mm, row, wire_mm)
    if len(eligible) < n_fixed(pool.layout):
        return None
    x = np.zeros(len(pool.layout.names))
    g = len(pool.layout.geometry)
    x[g : g + 3] = pool.p_mm[row]
    session = np.zeros(len(eligible), dtype=int)
    q = pool.q_rad[eligible]
    J = lengths_and_jacobian(pool.base, pool.layout, x, q, session)[1] / sigma_mm
    picked, post = greedy_rows(J, pool.weight, n, pool.prior_var)
    predicted = float(np.sqrt(max(np.trace(pool.weight @ post), 0.0)))
    return PoolPlan(row, eligible[picked], pool.layout.geometry, pool.p_mm[row], predicted, 0)


def n_fixed(layout: Layout) -> int:
    """Return the readings one wire needs beyond its unknowns without a prior, plus one."""
    return len(TOOL_NAMES) + len(layout.names) - len(layout.geometry) + 1


def wire_pool(robot: Robot, q_rad: np.ndarray, prior: float) -> Pool:
    """Return the pool's shared part; with the compliances the robot file asks, if any."""
    base = point_model(robot)  # with the masses when the file asks compliances
    layout = wire_layout(base, robot.compliances)
    g = len(layout.geometry)
    p, jp = tool_jacobian(base, q_rad, layout.geometry)
    weight = np.zeros((len(layout.names), len(layout.names)))
    weight[:g, :g] = registered_weight(p, jp)
    return Pool(base, layout, q_rad, p, weight, prior_sigma(base, layout, prior) ** 2)


def anchor_plans(
    robot: Robot, q_deg: np.ndarray, n_points: int, opt: PlanOptions
) -> list[PoolPlan]:
    """Return the plan at each θ0 tried that leaves enough poses (module docstring, 1–3).

    Rows are the pool's (``q_deg``). Rows beyond the robot file's joint limits are left out
    (counted in ``outside``); the others are taken as reachable without collision, as the
    moves that recorded them.
    """
    check_exit(robot)
    lo, hi = robot.limits_deg(0.0)
    inside = np.flatnonzero(np.all((q_deg >= lo) & (q_deg <= hi), axis=1))
    if len(inside) == 0:
        raise WirecalError(
            f"none of the pool's {len(q_deg)} configurations is within the robot file's joint "
            "limits: give a pool of this robot's configurations, in its joint convention"
        )
    pool = wire_pool(robot, np.radians(q_deg[inside]), opt.prior)
    wire_mm = pool_wire_mm(robot, opt)
    tried = spread(pool.p_mm, THETA0_TRIED)
    plans = [_at_anchor(pool, int(r), n_points, opt.sigma_mm, wire_mm) for r in tried]
    found = [pl for pl in plans if pl is not None]
    if not found:
        raise WirecalError(
            f"no θ0 of the {len(tried)} tried leaves enough poses of the pool within the "
            f"encoder's range ({wire_mm[0]:g}–{wire_mm[1]:g} mm of wire) and the joint limits: "
            "give a pool that moves the tool around more, or an encoder of a longer range"
        )
    outside = len(q_deg) - len(inside)
    return [
        PoolPlan(
            int(inside[pl.theta0_row]),
            inside[pl.rows],
            pl.names,
            pl.anchor_mm,
            pl.predicted_mm,
            len(tried),
            outside,
        )
        for pl in found
    ]


def pool_wire_mm(robot: Robot, opt: PlanOptions) -> tuple[float, float]:
    """Return the wire lengths (mm) a pose may ask: the shortest, the range less its margin."""
    return opt.min_wire_mm, robot.encoder.range_mm - opt.range_margin_mm


def plan_pool(robot: Robot, q_deg: np.ndarray, n_points: int, opt: PlanOptions) -> PoolPlan:
    """Choose θ0 and at most ``n_points`` poses of the pool ``q_deg`` (module docstring).

    The plan of the least predicted error of :func:`anchor_plans`.
    """
    return min(anchor_plans(robot, q_deg, n_points, opt), key=lambda pl: pl.predicted_mm)
