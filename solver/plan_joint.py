"""The joint method's points: added to the steps where they lower the tool-point error most.

Greedy I-optimal design per second of robot time (:func:`joint_choice`), each point
joining the step whose parameter it isolates, so the step-by-step method still runs.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.accuracy import workspace
from wirecal.solver.kinematics import tool_jacobian, tool_position
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan_options import PlanOptions
from wirecal.solver.plan_steps import StepPool, step_errors
from wirecal.solver.plan_tour import visit_s
from wirecal.solver.robot import Robot


def joint_choice(
    robot: Robot,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    psi: np.ndarray,
    names: list[str],
    pools: list[StepPool],
    opt: PlanOptions,
) -> None:
    """Add points to the steps for the joint method, up to ``points`` in all.

    Greedy I-optimal design: the criterion is the joint estimate's tool-point variance
    integrated over the workspace, φ = tr(W·Σ), W the mean over the workspace of J_pᵀJ_p and
    Σ = (P⁻¹ + JᵀJ/σ²)⁻¹ (P: the prior of size ``prior``; it hardly matters once every step
    has its first points). A point with sensitivity row x lowers φ by xᵀΣWΣx / (σ² + xᵀΣx)
    (Sherman–Morrison); each pick takes the candidate with the largest decrease per second
    of robot time it adds (its stop, and the move to it from θ0 or from the nearest point
    already in its step: :class:`~wirecal.solver.run_parameters.RunParameters`' time model).
    A point joins only the step whose parameter it isolates, under the stepwise design's
    rules (``spread_deg`` from the step's points, a clear move from each, at most one via
    point per step) and only if it does not raise the step's stepwise error
    (:func:`~wirecal.solver.plan_steps.step_error`): the stepwise method stays as good as
    with the first points alone.
    """
    order = [p.parameter for p in pools]
    col = [names.index(t) for t in order]
    errors = ErrorSet(tuple(order), robot.n_joints)
    x_all = errors.per_internal(psi[:, col])  # (N, m) mm per rad, mm per mm
    _, jp = tool_jacobian(robot.nominal, workspace(robot, 500), order)
    w = np.einsum("nim,nik->mk", jp, jp) / len(jp)
    s2 = opt.sigma_mm**2
    info = np.diag(1 / errors.to_internal(np.full(len(order), opt.prior)) ** 2)
    for p in pools:
        rows = x_all[p.iso[p.picks]]
        info = info + rows.T @ rows / s2
    sigma = np.linalg.inv(info)
    cand = np.concatenate([p.iso for p in pools])
    step = np.concatenate([np.full(len(p.iso), k) for k, p in enumerate(pools)])
    local = np.concatenate([np.arange(len(p.iso)) for p in pools])
    x = x_all[cand]
    p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
    has_via = ~np.isnan(via_all[cand, 0])
    cost = np.full(len(cand), np.inf)
    allowed = np.ones(len(cand), bool)

    def update(k: int, added: int) -> None:
        """Recompute step k's admissible candidates and their costs.

        The costs from all of the step's points, or only from the ``added`` last ones
        (the others already counted).
        """
        mine = np.flatnonzero(step == k)
        pool, q = pools[k], q_all[cand[mine]]
        here = q_all[pool.iso[pool.picks]]
        spread = np.min(np.max(np.abs(q[:, None] - here[None]), axis=2), axis=1)
        ok = spread >= opt.spread_deg
        if has_via[mine][pool.picks].any():
            ok &= ~has_via[mine]
        args = (pool.pj, pool.pprev, pool.cov_prev, pool.pnext)
        now = step_errors(*args, pool.picks[:-1], pool.picks[-1:], opt)[0]
        ok[ok] = step_errors(*args, pool.picks, np.flatnonzero(ok), opt) <= now
        allowed[mine] = ok
        for a in here[len(here) - added :] if added else (theta0, *here):
            cost[mine[ok]] = np.minimum(cost[mine[ok]], visit_s(robot, opt.run, p0, a, q[ok]))

    for k in range(len(pools)):
        update(k, 0)
    budget = opt.points if opt.points is not None else opt.points_per_step * len(pools)
    while sum(len(p.picks) for p in pools) < budget:
        a = x @ sigma
        gain = np.einsum("nm,mk,nk->n", a, w, a) / (s2 + np.einsum("nm,nm->n", a, x))
        ranked = np.flatnonzero(allowed)
        ranked = ranked[np.argsort(-gain[ranked] / cost[ranked], kind="stable")]
        best = _first_linked(ranked, step, local, pools)
        if best is None:
            break
        k = int(step[best])
        pools[k].picks.append(int(local[best]))
        sx = sigma @ x[best]
        sigma = sigma - np.outer(sx, sx) / (s2 + x[best] @ sx)
        update(k, 1)


def _first_linked(ranked: np.ndarray, step: np.ndarray, local: np.ndarray, pools) -> int | None:
    """Return the first ranked candidate with clear moves from its step's points, or None.

    Checked in blocks of eight, one sweep per step and block.
    """
    for start in range(0, len(ranked), 8):
        block = ranked[start : start + 8]
        linked = np.zeros(len(block), bool)
        for k in np.unique(step[block]):
            mine = step[block] == k
            linked[mine] = pools[k].links.ok(pools[k].picks, local[block[mine]])
        if linked.any():
            return int(block[np.argmax(linked)])
    return None
