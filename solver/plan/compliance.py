"""Points for the gravity compliances: the plan augmented so they are identified with the geometry.

A compliance c_j moves the wire as θ_j does scaled by the gravity torque τ_j(q)
(:mod:`~wirecal.solver.compliance`), so one wire tells it from θ_j only through the change
of τ_j over the points. When the robot file lists ``compliances``, the designed plan is
augmented (:func:`add_compliance_points`) by a greedy Ds-optimal design: each pick takes the
candidate with the largest gain of information about the targeted compliances, the
geometry being estimated with them (the joint method's Fisher information, the covariance
``solve`` reports), per second of robot time it adds, until the added time reaches
:data:`TIME_SHARE` of the plan's. A point joins the step whose parameter it isolates, under
the joint design's rules (a clear move from each of the step's points, ``spread_deg`` from
them, at most one via point per step, no rise of the step's step-by-step error: that method
stays as good). Without ``compliances`` nothing changes.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.compliance import (
    PRIOR_COMPLIANCE_URAD_PER_NM,
    SIGMA_LIMIT_URAD_PER_NM,
    compliance_observability,
)
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.calibration_plan import Plan, Step
from wirecal.solver.plan.candidates import Screened
from wirecal.solver.plan.joint import linked_in_block, may_join, pooled_candidates
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.predict import robot_time
from wirecal.solver.plan.steps import StepPool
from wirecal.solver.plan.tour import visit_s
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.verdict import READING_NOISE_MM

TIME_SHARE = 0.15
"""Robot time the compliance points may add, as a share of the plan's before them: issue
30 allows 25 %; the greedy counts each point's visit from its step's nearest point, which
the tour's insertion can exceed, so the share is set below it."""

PAYLOAD_SHARE = 0.05
"""The share of :data:`TIME_SHARE` when the robot file gives a payload step's mass: the
rest of issue 30's 25 % goes to the payload step (:mod:`~wirecal.solver.plan.payload`),
whose points identify the compliances better per second."""

SHORTLIST = 48
"""Candidates of the largest gains costed at each pick (the rest cannot win per second)."""

GAIN_FLOOR = 1e-6
"""Least gain of log det (nats) a point must bring: below it the targets are known."""


def add_compliance_points(
    robot: Robot,
    theta0: np.ndarray,
    cands: Screened,
    names: list[str],
    pools: list[StepPool],
    opt: PlanOptions,
) -> tuple[list[str], dict[str, float]]:
    """Add points to ``pools`` for the robot file's compliances; the header's lines and σ.

    ``cands``: the candidates around θ0; ``names``: the planned geometric parameters.
    Targeted are the compliances whose σ could reach
    :data:`~wirecal.solver.compliance.SIGMA_LIMIT_URAD_PER_NM` with the points the time
    allows (:func:`_reach`); no such plan identifies the others. A target the
    added points leave unidentified by the analysis ``solve`` makes
    (:func:`~wirecal.solver.compliance.compliance_observability`, at
    :data:`~wirecal.solver.verdict.READING_NOISE_MM`) is dropped and the points designed
    again for the others: points that vary a torque without identifying its compliance
    only let the unmodelled sag bend the geometry more. The lines give each compliance's
    predicted σ, with and without the points; the σ (µrad/(N·m)) with them.
    """
    comps = list(robot.compliances)
    q_all, via_all = cands.q, cands.via
    psi = sensitivity(robot.nominal, q_all, theta0, [*names, *comps]).psi  # mm/deg, µrad/(N·m)
    s2 = READING_NOISE_MM**2
    prior = np.r_[np.full(len(names), opt.prior), np.full(len(comps), PRIOR_COMPLIANCE_URAD_PER_NM)]
    first = [list(p.picks) for p in pools]
    picked = [int(p.iso[i]) for p in pools for i in p.picks]
    info = np.diag(prior**-2.0) + psi[picked].T @ psi[picked] / s2
    share = TIME_SHARE if robot.payload_kg is None else PAYLOAD_SHARE
    n_extra = int(np.ceil(share * len(picked)))
    target = [
        j for j in range(len(names), psi.shape[1]) if _reach(psi, info, j, n_extra, s2, cands)
    ]
    before = after = _sigmas(robot, q_all[picked], theta0, names)
    budget_s = share * robot_time(robot, _draft(robot, theta0, pools, q_all), opt.run)
    while target:
        _greedy(robot, theta0, q_all, via_all, psi, info, target, pools, opt, budget_s)
        picked = [int(p.iso[i]) for p in pools for i in p.picks]
        after = _sigmas(robot, q_all[picked], theta0, names)
        missed = [j for j in target if after[comps[j - len(names)]] > SIGMA_LIMIT_URAD_PER_NM]
        if not missed:
            break
        target = [j for j in target if j not in missed]
        for pool, picks in zip(pools, first, strict=True):
            pool.picks = list(picks)
        after = before
    return _lines(before, after, [comps[t - len(names)] for t in target]), after


def _sigmas(robot: Robot, q: np.ndarray, theta0: np.ndarray, names: list[str]) -> dict[str, float]:
    """Return each compliance's σ (µrad/(N·m)) at points ``q`` as ``solve`` would find it."""
    found = compliance_observability(
        robot.nominal, q, theta0, names, robot.compliances, READING_NOISE_MM
    )
    return found.sigma_urad_per_nm


def _greedy(
    robot: Robot,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    psi: np.ndarray,
    info: np.ndarray,
    target: list[int],
    pools: list[StepPool],
    opt: PlanOptions,
    budget_s: float,
) -> None:
    """Add the Ds-optimal points per second to ``pools`` until ``budget_s`` is spent.

    A point x raises log det of the information about the targets, the other parameters
    estimated with them, by log(1 + xᵀΣx/σ²) − log(1 + x_oᵀΣ_o x_o/σ²): Σ the covariance
    of all parameters, Σ_o that of the others alone (o: every column but the targets).
    Only the :data:`SHORTLIST` largest gains are costed (:class:`_Costs`).
    """
    s2 = READING_NOISE_MM**2
    others = np.setdiff1d(np.arange(psi.shape[1]), target)
    costs = _Costs(robot, theta0, q_all, via_all, pools, opt)
    x = psi[costs.cand]
    spent = 0.0
    while True:
        sig, sig_o = np.linalg.inv(info), np.linalg.inv(info[np.ix_(others, others)])
        xo = x[:, others]
        full = np.einsum("nm,mk,nk->n", x, sig, x)
        part = np.einsum("nm,mk,nk->n", xo, sig_o, xo)
        gain = np.log1p(full / s2) - np.log1p(part / s2)
        best = _best(costs, gain, budget_s - spent, pools)
        if best is None:
            return
        spent += float(costs.of(np.array([best]))[0])
        info = info + np.outer(x[best], x[best]) / s2
        costs.pick(best)


def _best(costs: _Costs, gain: np.ndarray, left_s: float, pools: list[StepPool]) -> int | None:
    """Return the linked candidate of the largest gain per second within ``left_s``, or None.

    Among the :data:`SHORTLIST` largest gains, then the next ones when none of them is
    linked to its step's points.
    """
    ranked = np.flatnonzero(costs.allowed & (gain > GAIN_FLOOR))
    ranked = ranked[np.argsort(-gain[ranked], kind="stable")]
    for start in range(0, len(ranked), SHORTLIST):
        short = ranked[start : start + SHORTLIST]
        cost = costs.of(short)
        short, cost = short[cost <= left_s], cost[cost <= left_s]
        order = short[np.argsort(-gain[short] / cost, kind="stable")]
        for block in range(0, len(order), 8):
            best = linked_in_block(order[block : block + 8], costs.step, costs.local, pools)
            if best is not None:
                return best
    return None


class _Costs:
    """The robot time (s) each candidate adds, worked out on demand and kept up to date.

    A candidate's visit from θ0 or the nearest of its step's points (the joint design's
    time model); whether it may join its step (:meth:`_allow`).
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
        self.q, self.has_via = q_all[self.cand], ~np.isnan(via_all[self.cand, 0])
        self.p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
        self.cost = np.full(len(self.cand), np.nan)  # nan: not worked out yet
        self.allowed = np.ones(len(self.cand), bool)
        for k in range(len(pools)):
            self._allow(k)

    def _picked(self, k: int) -> np.ndarray:
        """Return step k's points (deg)."""
        pool = self.pools[k]
        return self.q[np.flatnonzero(self.step == k)[pool.picks]]

    def _allow(self, k: int) -> None:
        """Work out which of step k's candidates may join it (the joint design's rules).

        :func:`~wirecal.solver.plan.joint.may_join`, as the joint design applies them.
        """
        mine = np.flatnonzero(self.step == k)
        self.allowed[mine] = may_join(self.q[mine], self.has_via[mine], self.pools[k], self.opt)

    def _visit(self, start: np.ndarray, js: np.ndarray) -> np.ndarray:
        """Return the robot time of the moves from ``start`` to candidates ``js``."""
        return visit_s(self.robot, self.opt.run, self.p0, start, self.q[js])

    def of(self, js: np.ndarray) -> np.ndarray:
        """Return the costs of candidates ``js``, working out those not known yet.

        The visits from θ0 and from every point of their steps, all in one evaluation.
        """
        new = np.unique(js[np.isnan(self.cost[js])])
        if not len(new):
            return self.cost[js]
        starts, ends = [], []
        for k in np.unique(self.step[new]):
            mine = new[self.step[new] == k]
            for a in (self.theta0, *self._picked(k)):
                starts.append(np.broadcast_to(a, (len(mine), len(a))))
                ends.append(mine)
        end = np.concatenate(ends)
        t = visit_s(self.robot, self.opt.run, self.p0, np.concatenate(starts), self.q[end])
        self.cost[new] = np.inf
        np.minimum.at(self.cost, end, t)
        return self.cost[js]

    def pick(self, j: int) -> None:
        """Add candidate ``j`` to its step: the step's allowed candidates and costs change."""
        k = int(self.step[j])
        self.pools[k].picks.append(int(self.local[j]))
        self._allow(k)
        known = np.flatnonzero((self.step == k) & ~np.isnan(self.cost))
        if len(known):
            self.cost[known] = np.minimum(self.cost[known], self._visit(self.q[j], known))


def _reach(
    psi: np.ndarray, info: np.ndarray, j: int, n_extra: int, s2: float, cands: Screened
) -> bool:
    """Whether ``n_extra`` candidates could bring parameter j's σ to the identification limit.

    The usable candidates of the largest gain for j alone (the others estimated with it),
    added together: an optimistic bound, since the greedy shares the points between the
    targets. Only the candidates ranked before the ``n_extra``-th usable are screened.
    """
    others = np.setdiff1d(np.arange(psi.shape[1]), [j])
    sig, sig_o = np.linalg.inv(info), np.linalg.inv(info[np.ix_(others, others)])
    xo = psi[:, others]
    gain = np.log1p(np.einsum("nm,mk,nk->n", psi, sig, psi) / s2) - np.log1p(
        np.einsum("nm,mk,nk->n", xo, sig_o, xo) / s2
    )
    best = psi[cands.first_usable([np.argsort(-gain, kind="stable")], [n_extra])[0]]
    sigma = np.sqrt(np.linalg.inv(info + best.T @ best / s2)[j, j])
    return bool(sigma <= SIGMA_LIMIT_URAD_PER_NM)


def _draft(robot: Robot, theta0: np.ndarray, pools: list[StepPool], q_all: np.ndarray) -> Plan:
    """Return the plan of the pools' points as picked (before the tours): its time's scale."""
    none = np.zeros((0, len(theta0)))
    steps = tuple(Step(p.parameter, q_all[p.iso[p.picks]], none) for p in pools)
    return Plan(theta0, tuple(p.parameter for p in pools), steps, robot=robot.name)


def _lines(before: dict[str, float], after: dict[str, float], target: list[str]) -> list[str]:
    """Return the header's lines: each compliance's predicted σ, with and without the points."""
    head = (
        f"Compliances (sigma {READING_NOISE_MM:g} mm per reading, as 'solve' takes it, estimated "
        "with the geometry; identified when "
        f"sigma <= {SIGMA_LIMIT_URAD_PER_NM:.2f} urad/Nm): points added for "
        + (", ".join(target) if target else "none: no points of this time identify one")
        + "."
    )
    rows = [
        f"compliance {n}: predicted sigma {s:.3g} urad/Nm "
        f"({'identified' if s <= SIGMA_LIMIT_URAD_PER_NM else 'not identified'}; "
        f"{before[n]:.3g} without the points added for the compliances)"
        for n, s in after.items()
    ]
    return [head, *rows]
