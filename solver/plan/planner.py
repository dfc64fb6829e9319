"""Design of experiments (paper §2.2–2.3, §3.4): the planner's entry point and θ0 search.

Design of experiments (paper §2.2–2.3, §3.4): θ0, the identification order and one point
set per parameter, for any 6R arm. :func:`design` chooses θ0 when not given (the search
here) and designs around it (:func:`~wirecal.solver.plan.design.design_at`). The parts:

* :mod:`~wirecal.solver.plan.options` — the planner's settings;
* :mod:`~wirecal.solver.plan.candidates` — candidate configurations around θ0 and their
  screening;
* :mod:`~wirecal.solver.plan.moves` — the moves' checks: the arm and the wire clear;
* :mod:`~wirecal.solver.plan.steps` — the order of §3.4 and each step's points;
* :mod:`~wirecal.solver.plan.joint` — the joint method's further points;
* :mod:`~wirecal.solver.plan.tour` — the visiting order of a step's points;
* :mod:`~wirecal.solver.plan.predict` — a plan's predicted accuracy and robot time;
* :mod:`~wirecal.solver.plan.design` — the design at one θ0 and its figures.
"""

from __future__ import annotations

import re
from collections.abc import Callable

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.candidates import Screened
from wirecal.solver.plan.design import Design, Steps, design_at, design_steps, finish, score
from wirecal.solver.plan.options import DEFAULT_OPTIONS, PlanOptions, Progress, part_progress
from wirecal.solver.plan.steps import most_informative
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity


def design(
    robot: Robot,
    theta0: np.ndarray | None = None,
    opt: PlanOptions = DEFAULT_OPTIONS,
    progress: Progress | None = None,
) -> Design:
    """Return a plan for the robot file's parameters (θ0 chosen when not given).

    θ0 chosen: the best plan (fewest parameters unplanned, then the smallest predicted
    error) of the first :data:`THETA0_TRIES` θ0 drawn clear of the cell, each designed up
    to its steps' first points and the :data:`THETA0_FINISHED` ranked first by those
    (and any within :data:`THETA0_CLOSE` of the first) finished (:func:`_best_finished`);
    when it leaves
    parameters unplanned (but unobservable or redundant ones, which no θ0 plans), up to
    :data:`MORE_THETA0_DESIGNED` more θ0, the best of
    :data:`MORE_THETA0_CHECKED` further draws by a quick check (:func:`_isolated_count`),
    until one gives a complete plan (:func:`_search_further`). A θ0 given is the only one
    tried. ``progress`` is called with the fraction of the work done (0…1) as it advances.
    """
    _check_room(robot, opt)
    if theta0 is not None:
        return design_at(robot, np.asarray(theta0, dtype=float), opt, progress)
    draws = _theta0_draws(robot, opt)
    first = draws[:THETA0_TRIES]
    parts = 2 * len(first) + MORE_THETA0_DESIGNED  # staged, finished (at most all), further
    problems: list[WirecalError] = []  # why each θ0 gave no plan, worked out if shown
    staged: list[Steps] = []
    for k, t0 in enumerate(first):
        try:
            staged.append(design_steps(robot, t0, opt, part_progress(progress, k, parts)))
        except WirecalError as exc:
            problems.append(exc)
    best = _best_finished(
        staged, problems, lambda k: part_progress(progress, len(first) + k, parts)
    )
    if best is not None:
        best.theta0_tried = len(first)
    if best is None or best.isolation_failed():
        more = draws[THETA0_TRIES : THETA0_TRIES + MORE_THETA0_CHECKED]
        best = _search_further(
            robot,
            more,
            (best, problems),
            opt,
            lambda k: part_progress(progress, 2 * len(first) + k, parts),
        )
    if best is None:
        raise WirecalError(
            [
                f"{robot.source}: no θ0 tried gives a plan ({len(problems)} tried; each "
                "θ0's reasons follow)",
                *(exc.problems[0] for exc in problems),
            ]
        )
    return best


THETA0_TRIES = 6
"""θ0 designed first, all of them up to their steps' first points; the best plan of those
finished is kept when it is complete."""


THETA0_FINISHED = 2
"""Of the first θ0s, those finished (the joint design's further points, the tours, the
predictions: a third of a design), the best ranked by their steps' first points first
(:attr:`~wirecal.solver.plan.design.Steps.rank`)."""


THETA0_CLOSE = 1.25
"""Beyond the :data:`THETA0_FINISHED`, a θ0 whose staged rank is within this factor of the
first's is finished too: over 40 searches (four arms, seeds 0–9) the θ0 a full search keeps
was always among them; with two alone, the IRB 120 at seed 6 kept a plan predicting
0.051 mm step-by-step instead of 0.035."""


MORE_THETA0_CHECKED = 60
"""Further θ0 drawn when the first leave parameters unplanned, each given the quick check
of :func:`_isolated_count` (0.1–0.7 s on the UR5, a tenth of a design)."""


MORE_THETA0_DESIGNED = 4
"""Of those, designed at most, best checked first; the first complete plan is kept."""


def _score(d: Design) -> tuple[int, float]:
    """Return a plan's rank among θ0s: parameters unplanned, then the predicted errors."""
    return score(len(d.excluded), d.predicted)


def _best_finished(
    staged: list[Steps], problems: list[WirecalError], part: Callable[[int], Progress | None]
) -> Design | None:
    """Return the best plan of the first θ0s, finishing the :data:`THETA0_FINISHED` ranked first.

    And any further whose rank is within :data:`THETA0_CLOSE` of the first's. In the order
    of their steps' rank (:attr:`~wirecal.solver.plan.design.Steps.rank`, ties in the order
    drawn); one whose finish fails adds its reason to ``problems`` and the next is finished
    instead. ``part(k)``: the progress callback of the k-th finish.
    """
    best: Design | None = None
    finished = 0
    ranked = sorted(staged, key=lambda s: s.rank)
    for s in ranked:
        if finished >= THETA0_FINISHED and not _close(s.rank, ranked[0].rank):
            break
        try:
            d = finish(s, part(finished))
        except WirecalError as exc:
            problems.append(exc)
            continue
        finished += 1
        if best is None or _score(d) < _score(best):
            best = d
    return best


def _close(rank: tuple[int, float], first: tuple[int, float]) -> bool:
    """Return whether a θ0's staged ``rank`` is within :data:`THETA0_CLOSE` of the first's."""
    return rank[0] == first[0] and rank[1] <= THETA0_CLOSE * first[1]


def _search_further(
    robot: Robot,
    more: np.ndarray,
    so_far: tuple[Design | None, list[WirecalError]],
    opt: PlanOptions,
    part: Callable[[int], Progress | None],
) -> Design | None:
    """Return the first complete plan at the θ0s ``more``, else the best plan of all.

    Each θ0 in the order drawn gets the quick check of :func:`_isolated_count`; one
    around which every parameter of [calibration] (but the unidentifiable) is isolated is
    designed at once, and the search stops at its plan if complete (every parameter
    planned but the unidentifiable). Otherwise, after all are checked, the θ0s
    isolating the most parameters (ties in the order drawn) are designed. At most
    :data:`MORE_THETA0_DESIGNED` designs in all. ``so_far``: the best plan of the first
    θ0s (None: none) and why the others gave none, a list this extends; ``part(k)`` is
    the progress callback of the k-th design. The plan returned says how many θ0s were
    designed (``theta0_tried``) and, in ``search_line``, how the search went.
    """
    search = _Search(robot, opt, part, *so_far)
    counts: list[int] = []
    for t0 in more:
        if search.spent:
            return search.result(len(counts))
        counts.append(_isolated_count(robot, t0, opt))
        if counts[-1] >= search.target and search.attempt(len(counts) - 1, t0):
            return search.result(len(counts))
    for i in np.argsort(-np.array(counts, dtype=int), kind="stable"):
        if search.spent or (i not in search.designed and search.attempt(int(i), more[i])):
            break
    return search.result(len(counts))


class _Search:
    """The θ0s designed after the first ones: the best plan so far and why others failed.

    ``attempt`` designs one θ0 and keeps the plan if it ranks better (:func:`_score`);
    ``spent`` once :data:`MORE_THETA0_DESIGNED` are designed.
    """

    def __init__(
        self,
        robot: Robot,
        opt: PlanOptions,
        part: Callable[[int], Progress | None],
        best: Design | None,
        problems: list[WirecalError],
    ) -> None:
        self.robot, self.opt, self.part = robot, opt, part
        self.best, self.problems = best, problems
        self.before = len(problems) if best is None else best.theta0_tried
        self.designed: list[int] = []
        # the quick check's count that calls for a design at once
        self.target = len(robot.parameters) - (len(best.unidentifiable) if best else 0)

    @property
    def spent(self) -> bool:
        """Whether :data:`MORE_THETA0_DESIGNED` θ0s are designed (no more may be)."""
        return len(self.designed) >= MORE_THETA0_DESIGNED

    def attempt(self, i: int, theta0: np.ndarray) -> bool:
        """Design at θ0 (draw ``i``); return whether its plan is complete."""
        self.designed.append(i)
        try:
            d = design_at(self.robot, theta0, self.opt, self.part(len(self.designed) - 1))
        except WirecalError as exc:
            self.problems.append(exc)
            return False
        if self.best is None or _score(d) < _score(self.best):
            self.best = d
        return not d.isolation_failed()

    def result(self, checked: int) -> Design | None:
        """Return the best plan, saying how many θ0s were checked and designed."""
        tried = len(self.designed)
        if self.best is not None and tried:
            self.best.theta0_tried = self.before + tried
            self.best.search_line = (
                f"theta0 search: the first {self.before} theta0 drawn left parameters "
                f"unplanned; {checked} more checked quickly (how many parameters each "
                f"isolates), {tried} designed: {self.before + tried} theta0 tried in all."
            )
        return self.best


def _isolated_count(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> int:
    """Return how many parameters the order of §3.4 isolates around θ0: a quick check.

    The candidates of :func:`~wirecal.solver.plan.design.design_at`, screened only where
    the order asks (:class:`Screened`), so a fraction of a design's time; no points, via
    points or tours are chosen. The order stops where the design's does when no parameter
    is unidentifiable.
    """
    cands = Screened(robot, theta0, opt)
    names = list(robot.parameters)
    col = {n: k for k, n in enumerate(names)}
    psi = sensitivity(robot.nominal, cands.q, theta0, names).psi
    remaining = names
    while (best := most_informative(psi, col, remaining, opt, cands.first_usable)) is not None:
        remaining = [t for t in remaining if t != best[0]]
    return len(names) - len(remaining)


def _check_room(robot: Robot, opt: PlanOptions) -> None:
    """Raise when a joint's body limits leave no room for points inside the margin."""
    body_lo, body_hi = robot.limits_deg()
    lo, hi = robot.limits_deg(opt.margin_deg)
    span = body_hi - body_lo
    narrow = np.flatnonzero(lo >= hi)
    if narrow.size:
        raise WirecalError(
            [
                f"{robot.source}: joint {j + 1}: range {span[j]:g} deg leaves no room for "
                f"points {opt.margin_deg:g} deg inside both limits; check joint_min_deg, "
                "joint_max_deg and [cell] body_min_deg, body_max_deg (degrees)"
                for j in narrow
            ]
        )


THETA0_DRAWS = 1000
"""θ0 candidates drawn at once; those clear of the arm and the cell are tried in order
(the first :data:`THETA0_TRIES`, then :data:`MORE_THETA0_CHECKED` more if need be)."""


def _theta0_draws(robot: Robot, opt: PlanOptions) -> np.ndarray:
    """Return the θ0 (deg, whole degrees) drawn clear of the arm's body and the cell.

    Drawn 20 deg inside the body limits (less on a joint with a narrow range); raise,
    naming what blocked them, when none of :data:`THETA0_DRAWS` is clear.
    """
    rng = np.random.default_rng([opt.seed, 99])
    lo, hi = robot.limits_deg()
    inset = np.clip((hi - lo) / 4, opt.margin_deg, 20.0)
    t0 = np.round(rng.uniform(*robot.limits_deg(inset), (THETA0_DRAWS, robot.n_joints)), 0)
    p0 = tool_position(robot.nominal, np.radians(t0))
    gaps = robot.cell_gaps(t0, p0)
    clear = gaps.smallest() >= 0
    if not clear.any():
        # "link 2 (a2) and the floor: 2249 mm into each other, …" → "link 2 and the floor"
        causes = sorted(
            {re.sub(r" \(.*?\)", "", gaps.cause(k)).split(":")[0] for k in range(len(t0))}
        )
        raise WirecalError(
            f"{robot.source}: all {THETA0_DRAWS} θ0 drawn collide (cell) — "
            + "; ".join(causes[:5])
            + ": check [cell] floor_z_mm and its boxes, or give --theta0"
        )
    return t0[clear]
