"""The joint method's points: added to the steps where they lower the tool-point error most.

Greedy I-optimal design per second of robot time (:func:`joint_choice`), each point
joining the step whose parameter it isolates, so the step-by-step method still runs.
"""

from __future__ import annotations

import itertools

import numpy as np

from wirecal.solver.accuracy import workspace
from wirecal.solver.kinematics import tool_jacobian, tool_position
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.steps import StepPool, step_errors
from wirecal.solver.plan.tour import visit_floor_s, visit_s
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
    (:func:`~wirecal.solver.plan.steps.step_error`): the stepwise method stays as good as
    with the first points alone.
    """
    order = [p.parameter for p in pools]
    errors = ErrorSet(tuple(order), robot.n_joints)
    x_all = errors.per_internal(psi[:, [names.index(t) for t in order]])  # mm/rad, mm/mm
    _, jp = tool_jacobian(robot.nominal, workspace(robot, 500), order)
    w = np.einsum("nim,nik->mk", jp, jp) / len(jp)
    s2 = opt.sigma_mm**2
    info = np.diag(1 / errors.to_internal(np.full(len(order), opt.prior)) ** 2)
    for p in pools:
        rows = x_all[p.iso[p.picks]]
        info = info + rows.T @ rows / s2
    sigma = np.linalg.inv(info)
    c = _Candidates(robot, theta0, q_all, via_all, pools, opt)
    x = x_all[c.cand]
    budget = opt.points if opt.points is not None else opt.points_per_step * len(pools)
    while sum(len(p.picks) for p in pools) < budget:
        a = x @ sigma
        gain = np.einsum("nm,mk,nk->n", a, w, a) / (s2 + np.einsum("nm,nm->n", a, x))
        best = _first_linked(c, gain)
        if best is None:
            break
        k = int(c.step[best])
        pools[k].picks.append(int(c.local[best]))
        sx = sigma @ x[best]
        sigma = sigma - np.outer(sx, sx) / (s2 + x[best] @ sx)
        c.update(k, 1)


class _Candidates:
    """Every step's candidates in the joint design: which may join, and the time each adds.

    ``cand`` (screened candidates), ``step`` (the step's index) and ``local`` (the index
    in the step's pool) per candidate of all steps; ``allowed`` whether it may join its
    step now (:meth:`update`). The robot time a candidate would add is the least
    :func:`~wirecal.solver.plan.tour.visit_s` from the configurations counted for it
    (θ0 and its step's points while it was allowed: :meth:`update`); it is worked out
    only for candidates at the head of the ranking (:meth:`head`), the others ranked by
    a lower bound of it (:func:`~wirecal.solver.plan.tour.visit_floor_s`), which gives
    the ranking that working out every candidate's would.
    """

    def __init__(
        self,
        robot: Robot,
        theta0: np.ndarray,
        q_all: np.ndarray,
        via_all: np.ndarray,
        pools: list[StepPool],
        opt: PlanOptions,
    ):
        self.robot, self.theta0, self.pools, self.opt = robot, theta0, pools, opt
        self.cand, self.step, self.local = pooled_candidates(pools)
        self.q = q_all[self.cand]
        self.p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
        self.has_via = ~np.isnan(via_all[self.cand, 0])
        self.allowed = np.ones(len(self.cand), bool)
        # per step, the configurations counted and for which candidates; per candidate
        # the robot time from those counted so far (`counted` of them) and the bound
        self.starts: list[list[tuple[np.ndarray, np.ndarray]]] = [[] for _ in pools]
        self.cost = np.full(len(self.cand), np.inf)
        self.counted = np.zeros(len(self.cand), int)
        self.floor = np.full(len(self.cand), np.inf)
        for k in range(len(pools)):
            self.update(k, 0)

    def update(self, k: int, added: int) -> None:
        """Recompute step k's admissible candidates; count θ0 and its points for them.

        All of the step's points, or only the ``added`` last ones (the others counted).
        """
        opt = self.opt
        mine = np.flatnonzero(self.step == k)
        pool, q = self.pools[k], self.q[mine]
        here = q[pool.picks]
        ok = may_join(q, self.has_via[mine], pool, opt)
        self.allowed[mine] = ok
        for a in here[len(here) - added :] if added else (self.theta0, *here):
            self.starts[k].append((a, mine[ok]))
            floor = visit_floor_s(self.robot, opt.run, a, q[ok])
            self.floor[mine[ok]] = np.minimum(self.floor[mine[ok]], floor)

    def _count(self, idx: np.ndarray) -> None:
        """Work out the robot time of candidates ``idx`` from every configuration counted.

        The moves from the configurations not yet counted for them, all in one evaluation.
        """
        starts, ends = [np.zeros((0, self.q.shape[1]))], [np.zeros(0, int)]
        for k in np.unique(self.step[idx]):
            mine = idx[self.step[idx] == k]
            for n, (a, members) in enumerate(self.starts[k]):
                new = mine[(self.counted[mine] <= n) & np.isin(mine, members)]
                starts.append(np.broadcast_to(a, (len(new), len(a))))
                ends.append(new)
        end = np.concatenate(ends)
        t = visit_s(self.robot, self.opt.run, self.p0, np.concatenate(starts), self.q[end])
        np.minimum.at(self.cost, end, t)
        self.counted[idx] = [len(self.starts[k]) for k in self.step[idx]]

    def head(self, gain: np.ndarray, n: int) -> np.ndarray:
        """Return the first ``n`` allowed candidates by ``gain`` per second of robot time.

        The order of a stable sort of them all by gain per second; where a candidate's
        time is not worked out, its bound ranks it no lower, so the candidates ranked
        above the first ``n`` by bounds are worked out until those ``n`` are exact.
        """
        ranked = np.flatnonzero(self.allowed)
        while True:
            stale = (
                self.counted[ranked] < np.array([len(s) for s in self.starts])[self.step[ranked]]
            )
            per_s = -gain[ranked] / np.where(stale, self.floor[ranked], self.cost[ranked])
            order = ranked[np.argsort(per_s, kind="stable")]
            if not stale[np.isin(ranked, order[:n])].any():
                return order[:n]
            ahead = order[: 4 * n]
            self._count(ahead[np.isin(ahead, ranked[stale])])


def may_join(q: np.ndarray, has_via: np.ndarray, pool: StepPool, opt: PlanOptions) -> np.ndarray:
    """Return which of a step's pool ``q`` (deg, in the pool's order) may join the step.

    The joint design's rules: ``spread_deg`` from each of its points, no via point when
    one of its points has one, and no rise of its step-by-step error
    (:func:`~wirecal.solver.plan.steps.step_errors`). ``has_via``: per candidate.
    """
    points = q[pool.picks]
    ok = np.ones(len(q), bool)
    if len(points):
        gap = np.max(np.abs(q[:, None] - points[None]), axis=2)
        ok = np.min(gap, axis=1) >= opt.spread_deg
    if has_via[pool.picks].any():
        ok &= ~has_via
    args = (pool.pj, pool.pprev, pool.cov_prev, pool.pnext)
    now = step_errors(*args, pool.picks[:-1], pool.picks[-1:], opt)[0]
    ok[ok] = step_errors(*args, pool.picks, np.flatnonzero(ok), opt) <= now
    return ok


def pooled_candidates(pools: list[StepPool]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return every step's candidates in one row: their indices, their step, their place in it.

    The layout the joint design and the compliances' points rank candidates over.
    """
    cand = np.concatenate([p.iso for p in pools])
    step = np.concatenate([np.full(len(p.iso), k) for k, p in enumerate(pools)])
    local = np.concatenate([np.arange(len(p.iso)) for p in pools])
    return cand, step, local


def _first_linked(c: _Candidates, gain: np.ndarray) -> int | None:
    """Return the first ranked candidate with clear moves from its step's points, or None.

    Ranked by ``gain`` per second of robot time (:meth:`_Candidates.head`); checked in
    blocks of eight (:func:`linked_in_block`).
    """
    for end in itertools.count(8, 8):
        block = c.head(gain, end)[end - 8 :]
        if not len(block):
            return None
        best = linked_in_block(block, c.step, c.local, c.pools)
        if best is not None:
            return best
    return None


def linked_in_block(
    block: np.ndarray, step: np.ndarray, local: np.ndarray, pools: list[StepPool]
) -> int | None:
    """Return the first candidate of ``block`` with clear moves from its step's points, or None.

    One sweep per step: ``step`` and ``local`` give each candidate's step and its index in
    that step's pool.
    """
    linked = np.zeros(len(block), bool)
    for k in np.unique(step[block]):
        mine = step[block] == k
        pool = pools[k]
        linked[mine] = pool.links.ok(pool.picks, local[block[mine]])
    return int(block[np.argmax(linked)]) if linked.any() else None
