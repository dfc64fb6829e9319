"""The planner's steps (paper §3.4): the identification order and each step's points.

* **Order** (§3.4): among the parameters not yet identified, the next is the one that the
  most informative isolating points single out: points where |Ψ_t| ≤ tol·|Ψ_j| for every
  other parameter t still unknown (eq. 18–19; :func:`isolating`, :func:`most_informative`).
* **Points**: from the isolating candidates, greedily the set minimising the step's
  linearised variance *including what earlier estimates leak into it* (their errors reach
  the step through Ψ_{i,<j}; :func:`step_errors`); the paper's criterion (largest |Ψ_j|
  only) is computed beside it and the reduction reported. Points are kept at least
  ``spread_deg`` apart, each joined to the others by a clear move (:class:`Links`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.accuracy import stepwise_map
from wirecal.solver.plan.candidates import Blocked, Screened, blocked, no_usable_error
from wirecal.solver.plan.moves import move_ok, reach_and_move_ok
from wirecal.solver.plan.options import PlanOptions, Progress
from wirecal.solver.plan.tour import tour
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity, within_tolerance


def isolating(
    psi: np.ndarray, col: dict[str, int], j: str, remaining: list[str], opt
) -> np.ndarray:
    """Return which candidates isolate parameter j from the others still unknown (eq. 18–19).

    |Ψ_t| ≤ tol·|Ψ_j| (or below :data:`~wirecal.solver.sensitivity.PSI_FLOOR`) for every
    other parameter t of ``remaining`` (the one rule,
    :func:`~wirecal.solver.sensitivity.within_tolerance`), and |Ψ_j| ≥ 0.05.
    """
    return isolating_each(psi, col, remaining, opt)[remaining.index(j)]


def isolating_each(psi: np.ndarray, col: dict[str, int], remaining: list[str], opt) -> np.ndarray:
    """Return :func:`isolating` for every parameter of ``remaining`` at once, (m, N).

    Every other |Ψ_t| within the tolerance is the largest of them within it: per
    candidate the largest |Ψ| of the parameters before j and after j in ``remaining``
    (running maxima), one comparison per parameter instead of one per pair.
    """
    a = np.ascontiguousarray(np.abs(psi[:, [col[t] for t in remaining]]).T)  # (m, N)
    before = np.zeros_like(a)  # |Ψ| ≥ 0: zero stands for no other parameter
    after = np.zeros_like(a)
    for k in range(1, len(a)):  # a row at a time: numpy's accumulate along rows is slow
        before[k] = np.maximum(before[k - 1], a[k - 1])
        after[-1 - k] = np.maximum(after[-k], a[-k])
    iso = within_tolerance(a, np.maximum(before, after)[..., None], opt.tol)[..., 0]
    return iso & (a >= 0.05)


FirstUsable = Callable[[list[np.ndarray], list[int]], list[np.ndarray]]
"""Given rankings of candidates and counts, each ranking's first usable candidates
(:meth:`~wirecal.solver.plan.candidates.Screened.first_usable`)."""


def every_row(orders: list[np.ndarray], counts: list[int]) -> list[np.ndarray]:
    """Return each ranking's first ones: the :data:`FirstUsable` of candidates all usable."""
    return [order[:n] for order, n in zip(orders, counts, strict=True)]


def ranked_isolating(
    psi: np.ndarray, col: dict[str, int], j: str, remaining: list[str], opt: PlanOptions
) -> np.ndarray:
    """Return the candidates isolating j (:func:`isolating`), most sensitive first.

    By decreasing |Ψ_j|, ties in the order of the candidates.
    """
    return ranked(psi, col, j, isolating(psi, col, j, remaining, opt))


def ranked(psi: np.ndarray, col: dict[str, int], j: str, iso: np.ndarray) -> np.ndarray:
    """Return the candidates of the mask ``iso`` by decreasing |Ψ_j|, ties in their order."""
    idx = np.flatnonzero(iso)
    return idx[np.argsort(-np.abs(psi[idx, col[j]]), kind="stable")]


def most_informative(
    psi: np.ndarray,
    col: dict[str, int],
    remaining: list[str],
    opt: PlanOptions,
    first_usable: FirstUsable = every_row,
) -> tuple[str, np.ndarray] | None:
    """Choose the next parameter to isolate and its isolating candidates.

    The parameter whose ``points_per_step`` most sensitive usable isolating candidates
    (:func:`ranked_isolating`, ``first_usable``) carry the most information (Σψ²);
    None when no parameter has that many. Returns it and its isolating candidates,
    most sensitive first (not all of them screened).
    """
    k = opt.points_per_step
    each = isolating_each(psi, col, remaining, opt)
    orders = [ranked(psi, col, j, each[k]) for k, j in enumerate(remaining)]
    best: tuple[float, str, np.ndarray] | None = None
    tops = first_usable(orders, [k] * len(orders))
    for j, order, top in zip(remaining, orders, tops, strict=True):
        if len(top) < k:
            continue
        info = float(np.sort(psi[top, col[j]] ** 2).sum())
        if best is None or info > best[0]:
            best = (info, j, order)
    return None if best is None else (best[1], best[2])


def step_errors(psi_j, psi_prev, cov_prev, psi_next, base, cand, opt: PlanOptions) -> np.ndarray:
    """Return the mean squared error of a step's estimate with points base + [i], per i.

    Mean squared error of a step's estimate (linearised) for each set of points ``base``
    and one candidate i of ``cand`` (indices into the rows of the Ψ arrays): the reading
    noise, the error of the earlier estimates leaking in through Ψ_{i,<j} (covariance
    ``cov_prev``), and the still-unknown later parameters leaking in through Ψ_{i,>j}
    (each of size ``prior``). Infinite where the points do not see the parameter.
    """
    b, c = list(base), np.asarray(cand, int)
    pb, pc = psi_j[b], psi_j[c]
    s = pb @ pb + pc * pc
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = np.where(s > 0, 1 / np.where(s > 0, s, 1), np.inf)
    lead = (pb @ psi_prev[b] + pc[:, None] * psi_prev[c]) * inv[:, None]
    lag = (pb @ psi_next[b] + pc[:, None] * psi_next[c]) * inv[:, None]
    earlier = np.einsum("ni,ik,nk->n", lead, cov_prev, lead) if lead.shape[1] else 0.0
    out = opt.sigma_mm**2 * inv + earlier + opt.prior**2 * np.einsum("ni,ni->n", lag, lag)
    return np.where(s > 0, out, np.inf)


def step_error(psi_j, psi_prev, cov_prev, psi_next, opt: PlanOptions) -> float:
    """Return the mean squared error of a step with all its points (:func:`step_errors`)."""
    n = len(psi_j)
    return float(step_errors(psi_j, psi_prev, cov_prev, psi_next, range(n - 1), [n - 1], opt)[0])


class Links:
    """Which of a step's candidates are reached, and which moves between them are clear.

    ``ok(sources, js)``: whether each of the candidates ``js`` is reached from θ0 with the
    wire clear (:func:`~wirecal.solver.plan.moves.reach_ok`, through its via point if it
    has one) and the moves from every one of the candidates ``sources`` to it are safe
    (:func:`~wirecal.solver.plan.moves.move_ok`); ``between(js)``: the moves between
    them, both ways (the tour's). Both are properties of the candidates
    alone, so asking only about the head of a ranking gives the choice a check of every
    candidate first would; each is worked out on demand and once, however often the greedy
    choices of a step ask about it.
    """

    def __init__(
        self,
        robot: Robot,
        model,
        p0: np.ndarray,
        theta0: np.ndarray,
        q: np.ndarray,
        via: np.ndarray,
        opt: PlanOptions,
    ):
        self.robot, self.model, self.p0, self.opt = robot, model, p0, opt
        self.theta0, self.q, self.via = theta0, q, via
        self.reached = np.zeros(len(q), np.int8)  # 0 unknown, 1 reached, 2 not
        self.known = np.zeros((len(q), len(q)), np.int8)  # 0 unknown, 1 clear, 2 not

    def ok(self, sources: list[int], js: np.ndarray) -> np.ndarray:
        """Return whether each of ``js`` is reached and linked to every one of ``sources``."""
        js = np.asarray(js, int)
        self._work_out(sources, js)
        out = self.reached[js] == 1
        near = js[out]
        i = np.repeat(np.asarray(sources, int), len(near))
        j = np.tile(near, len(sources))
        out[out] = np.all((self.known[i, j] == 1).reshape(len(sources), len(near)), axis=0)
        return out

    def between(self, js: list[int]) -> np.ndarray:
        """Return whether each move between the candidates ``js`` is safe, (n, n).

        The moves not known yet worked out in one sweep; the diagonal (no move) is True.
        """
        js_ = np.asarray(js, int)
        i, j = np.repeat(js_, len(js_)), np.tile(js_, len(js_))
        todo = (self.known[i, j] == 0) & (i != j)
        if todo.any():
            q = self.q
            clear = move_ok(self.robot, self.model, self.p0, q[i[todo]], q[j[todo]], self.opt)
            self.known[i[todo], j[todo]] = np.where(clear, 1, 2)
        return ((self.known[i, j] == 1) | (i == j)).reshape(len(js_), len(js_))

    def _work_out(self, sources: list[int], js: np.ndarray) -> None:
        """Work out what :meth:`ok` asks and is not known yet, in one sweep.

        Whether the candidates ``js`` are reached, and the moves to them from ``sources``
        (also for those whose reach is not known yet: one sweep costs less than two).
        """
        new = np.unique(js[self.reached[js] == 0])
        maybe = js[self.reached[js] != 2]
        i = np.repeat(np.asarray(sources, int), len(maybe))
        j = np.tile(maybe, len(sources))
        todo = self.known[i, j] == 0
        i, j = i[todo], j[todo]
        if not len(new) and not len(i):
            return
        q, via = self.q, self.via
        reach, clear = reach_and_move_ok(
            self.robot, self.model, self.p0, self.theta0, q[new], via[new], q[i], q[j], self.opt
        )
        self.reached[new] = np.where(reach, 1, 2)
        self.known[i, j] = np.where(clear, 1, 2)


def choose_points(
    psi_j, psi_prev, cov_prev, psi_next, q, has_via, links: Links, opt: PlanOptions, criterion
):
    """Choose a step's K points by the ``criterion`` given.

    K points by greedy minimum error ("ours") or by largest |Ψ_j| ("paper"), at least
    ``spread_deg`` apart, each joined by a clear move from every point chosen before it
    (``links``), at most one needing a via point (it will be visited first).
    """
    pool = np.ones(len(q), bool)
    for _ in range(20):  # a dead end (no k linked points): start elsewhere
        chosen = _greedy(
            psi_j, psi_prev, cov_prev, psi_next, q, has_via, links, pool, opt, criterion
        )
        if len(chosen) == opt.points_per_step:
            return chosen
        if not chosen:
            break
        pool[chosen[0]] = False
    return None


def _greedy(
    psi_j, psi_prev, cov_prev, psi_next, q, has_via, links: Links, allowed, opt, criterion
) -> list[int]:
    """Pick up to K points one at a time (see :func:`choose_points`).

    Each pick ranks the allowed candidates (spread apart, via rule) by the criterion,
    ties in order of decreasing |Ψ_j|, and takes the first whose moves from every point
    chosen so far are clear; the moves are checked in blocks, best-ranked first, so only
    the head of the ranking costs clearance sweeps.
    """
    allowed = allowed.copy()
    chosen: list[int] = []
    for _ in range(opt.points_per_step):
        cand = np.flatnonzero(allowed)
        cand = cand[np.argsort(-np.abs(psi_j[cand]), kind="stable")]
        if criterion != "paper":
            val = step_errors(psi_j, psi_prev, cov_prev, psi_next, chosen, cand, opt)
            finite = val < np.inf
            cand = cand[finite][np.argsort(val[finite], kind="stable")]
        best = None
        for start in range(0, len(cand), 8):
            block = cand[start : start + 8]
            linked = links.ok(chosen, block)
            if linked.any():
                best = int(block[np.argmax(linked)])
                break
        if best is None:
            return chosen
        chosen.append(best)
        allowed &= np.max(np.abs(q - q[best]), axis=1) >= opt.spread_deg
        if has_via[best]:
            allowed &= ~has_via
    return chosen


@dataclass
class StepPool:
    """One step: its isolating candidates and the points chosen among them.

    ``iso`` indexes the screened candidates; ``pj``, ``pprev``, ``pnext`` are their Ψ
    columns (the step's parameter, the earlier ones, the later ones); ``cov_prev`` the
    earlier estimates' error covariance; ``picks`` index ``iso``.
    """

    parameter: str
    iso: np.ndarray
    links: Links
    pj: np.ndarray
    pprev: np.ndarray
    pnext: np.ndarray
    cov_prev: np.ndarray
    picks: list[int]
    leak_paper: float | None = None


def _stepwise_cov(model, theta0, order, chosen_q, opt: PlanOptions) -> np.ndarray:
    """Return the error covariance of the estimates of the steps planned so far.

    Error covariance (boundary units) of the estimates of the steps planned so far,
    with the parameters not planned yet left out (their leak is added step by step).
    """
    q = np.concatenate(chosen_q)
    step = np.concatenate([np.full(len(c), s + 1) for s, c in enumerate(chosen_q)])
    J = sensitivity(model, q, theta0, order).psi
    A = stepwise_map(J, step)
    E = A @ J - np.eye(len(order))
    return opt.sigma_mm**2 * A @ A.T + opt.prior**2 * E @ E.T


def step_by_step(
    robot: Robot,
    theta0: np.ndarray,
    cands: Screened,
    psi: np.ndarray,
    remaining: list[str],
    excluded: dict[str, str],
    opt: PlanOptions,
    tick: Progress,
) -> list[StepPool]:
    """Return the steps in the order they isolate their parameters, with their points.

    The order of §3.4 (:func:`most_informative`) among the usable candidates (``cands``,
    ``psi`` their Ψ: only isolating ones are screened); per step the leak-aware greedy
    choice (:func:`choose_points`) of ``points_per_step`` points (``min_points`` for the joint
    design), its error covariance taking the earlier steps' choices into account, and
    for the stepwise design the paper's choice for comparison. Parameters that cannot be
    isolated go into ``excluded``.
    """
    p0, q_all, via_all = cands.p0, cands.q, cands.via
    col = {n: k for k, n in enumerate(remaining)}
    n_params = len(remaining)
    remaining = list(remaining)
    pools: list[StepPool] = []
    while remaining:
        best = most_informative(psi, col, remaining, opt, cands.first_usable)
        if best is None:
            excluded.update(_not_isolated(remaining, opt))
            break
        j, iso = best
        remaining.remove(j)
        pool = _step_pool(robot, cands, (psi, col), j, iso, pools, remaining, opt)
        if not _choose_step_points(robot, p0, theta0, q_all, via_all, pool, opt):
            excluded[j] = f"too few isolating points {opt.spread_deg:g} deg apart"
            continue
        pools.append(pool)
        tick(0.5 + 0.4 * len(pools) / n_params)
    if not pools:
        raise Blocked(lambda: _none_isolated(robot, cands, opt))
    return pools


def _none_isolated(robot: Robot, cands: Screened, opt: PlanOptions) -> str:
    """Return why no parameter is isolated around θ0, with what blocked the candidates."""
    usable = int(cands.usable(np.ones(len(cands.q), bool)).sum())
    if usable < opt.points_per_step:
        return no_usable_error(robot, cands.theta0, opt).problems[0]
    return (
        f"{robot.source}: no parameter can be isolated around θ0 {cands.theta0.tolist()} "
        f"by the {usable} usable candidates ({blocked(robot, cands.theta0, opt)}); try "
        "another --theta0"
    )


def _not_isolated(remaining: list[str], opt: PlanOptions) -> dict[str, str]:
    """Return why each parameter of ``remaining`` is not planned: none can be isolated."""
    return {
        j: f"cannot be isolated: no {opt.points_per_step} points leave it alone "
        f"among {', '.join(t for t in remaining if t != j)}"
        for j in remaining
    }


def _step_pool(
    robot: Robot,
    cands: Screened,
    sens: tuple[np.ndarray, dict[str, int]],
    j: str,
    iso: np.ndarray,
    pools: list[StepPool],
    later: list[str],
    opt: PlanOptions,
) -> StepPool:
    """Return step j's :class:`StepPool`, no points chosen yet.

    ``cands``: the candidates; ``sens``: their Ψ and Ψ's column per parameter; ``iso``
    the candidates isolating j, most sensitive first, of which the first
    :data:`POOL_SIZE` usable are kept; ``pools`` the steps before (their points give the
    earlier estimates' error covariance), ``later`` the parameters after j.
    """
    psi, col = sens
    theta0, q_all, via_all = cands.theta0, cands.q, cands.via
    # the most sensitive usable isolating points; their moves from θ0 are checked finely
    # when a choice comes to them (Links)
    iso = cands.first_usable([iso], [POOL_SIZE])[0]
    order = [p.parameter for p in pools]
    prev = np.array([col[t] for t in order], int)
    nxt = np.array([col[t] for t in later], int)
    # error covariance of the earlier estimates (linearised stepwise map)
    cov_prev = (
        _stepwise_cov(robot.nominal, theta0, order, [q_all[p.iso[p.picks]] for p in pools], opt)
        if order
        else np.zeros((0, 0))
    )
    return StepPool(
        j,
        iso,
        Links(robot, robot.nominal, cands.p0, theta0, q_all[iso], via_all[iso], opt),
        psi[iso, col[j]],
        psi[np.ix_(iso, prev)] if len(prev) else np.zeros((len(iso), 0)),
        psi[np.ix_(iso, nxt)] if len(nxt) else np.zeros((len(iso), 0)),
        cov_prev,
        [],
    )


POOL_SIZE = 600
"""A step's candidates: its most sensitive usable isolating ones (:func:`_step_pool`)."""


def _choose_step_points(
    robot: Robot,
    p0: np.ndarray,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    pool: StepPool,
    opt: PlanOptions,
) -> bool:
    """Choose a step's points into ``pool.picks``, in visiting order; False: too few.

    The leak-aware choice (:func:`choose_points`) of ``points_per_step`` points
    (``min_points`` for the joint design); for the stepwise design the paper's choice
    beside it (``pool.leak_paper``).
    """
    k_first = opt.points_per_step if opt.method == "stepwise" else opt.min_points
    has_via = ~np.isnan(via_all[pool.iso, 0])
    args = (pool.pj, pool.pprev, pool.cov_prev, pool.pnext, q_all[pool.iso], has_via, pool.links)
    ours = choose_points(*args, replace(opt, points_per_step=k_first), "ours")
    if ours is None:
        return False
    if opt.method == "stepwise":
        paper = choose_points(*args, opt, "paper")
        pool.leak_paper = (
            step_error(pool.pj[paper], pool.pprev[paper], pool.cov_prev, pool.pnext[paper], opt)
            if paper is not None
            else np.inf
        )
    pts = pool.iso[ours]
    clear = pool.links.between(ours)
    path = tour(robot, robot.nominal, p0, theta0, q_all[pts], via_all[pts], opt, clear)
    pool.picks = [ours[i] for i in path] if path is not None else ours
    return True
