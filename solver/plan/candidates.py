"""The planner's candidate configurations around θ0 and their screening.

Candidates are configurations that move one to three joints away from θ0 (as the paper's
points do) or all of them (:func:`candidates`); each is checked at once (vectorised,
:func:`point_checks`) for the joint limits with a margin, the wire length (above a minimum,
within the encoder's range), the exit angle (a wire leaving an eyelet stays within its
cone, :mod:`~wirecal.solver.exit_geometry`), the wrist singularity and the arm clear of its
own body and the cell (floor, keep-out volumes, body limits: :mod:`~wirecal.solver.cell.model`);
the wire's clearance from the links and the cell along the joint-interpolated move from θ0
(:mod:`~wirecal.solver.plan.moves`) is screened when a choice asks about a candidate
(:class:`Screened`). :func:`blocked` says what blocked them.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from wirecal.solver.cell.model import SURE_GAP_MM
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import wire_path, within_cone
from wirecal.solver.ik import solutions as ik
from wirecal.solver.kinematics import frames, tool_position
from wirecal.solver.plan.moves import move_clearance, move_ok, reach_ok
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot


def _subsets(n: int):
    for size in (1, 2, 3):
        yield from itertools.combinations(range(n), size)
    yield tuple(range(n))


def candidates(robot: Robot, theta0: np.ndarray, opt: PlanOptions, rng) -> np.ndarray:
    """Return configurations (deg) moving a few joints away from θ0.

    Within the margin of the body limits (the joint limits narrowed by ``[cell]``).
    """
    lo, hi = robot.limits_deg(opt.margin_deg)
    out = []
    for subset in _subsets(robot.n_joints):
        q = np.tile(theta0, (opt.samples, 1))
        idx = list(subset)
        q[:, idx] = rng.uniform(lo[idx], hi[idx], (opt.samples, len(idx)))
        out.append(q)
        # the mirror image about θ0: a pair θ0 ± Δ cancels the odd part of a leak, as the
        # paper's symmetric points do
        mirror = 2 * theta0 - q
        inside = np.all((mirror >= lo) & (mirror <= hi), axis=1)
        out.append(mirror[inside])
    return np.round(np.concatenate(out), 2)


class Screened:
    """The candidates around θ0 that pass their own checks, their moves screened on demand.

    ``q`` (deg): the candidates (:func:`candidates`) that pass :func:`point_checks`;
    ``via``: their via points (NaN rows: none, or not screened yet). :meth:`usable`
    screens the moves from θ0 (:func:`_screen_moves`) of the candidates a choice asks
    about, each once. Whether a candidate is usable is a property of it alone, so a choice
    among the usable candidates that screens only those it can take (for the order of
    §3.4, those isolating a parameter still unknown: few) makes the choice screening all
    of them would.
    """

    def __init__(self, robot: Robot, theta0: np.ndarray, opt: PlanOptions):
        self.robot, self.theta0, self.opt = robot, theta0, opt
        self.p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
        q = candidates(robot, theta0, opt, np.random.default_rng(opt.seed))
        self.q = q[point_checks(robot, robot.nominal, self.p0, q, opt)]
        self.via = np.full(self.q.shape, np.nan)
        self.state = np.zeros(len(self.q), np.int8)  # 0 not screened yet, 1 usable, 2 not

    def usable(self, which: np.ndarray) -> np.ndarray:
        """Return which of the candidates ``which`` (a mask) are usable, screening them."""
        todo = which & (self.state == 0)
        if todo.any():
            ok, via = _screen_moves(
                self.robot, self.robot.nominal, self.p0, self.theta0, self.q[todo], self.opt
            )
            self.state[todo] = np.where(ok, 1, 2)
            self.via[todo] = via
        return which & (self.state == 1)

    def first_usable(self, orders: list[np.ndarray], counts: list[int]) -> list[np.ndarray]:
        """Return the first ``counts[i]`` usable candidates of each ranking ``orders[i]``.

        The answer's candidates and every candidate ranked before them are screened, no
        others but a round's margin: each round screens, all rankings in one call, the
        candidates not screened yet of the head of each ranking expected to hold its
        count (:meth:`_expected_head`), until the head that holds it for certain
        (:meth:`_head`) has none.
        """
        while True:
            heads = [order[self._head(order, n)] for order, n in zip(orders, counts, strict=True)]
            todo = np.zeros(len(self.q), bool)
            for head in heads:
                todo[head] = True
            if not (todo & (self.state == 0)).any():
                return [head[self.state[head] == 1] for head in heads]
            for order, n in zip(orders, counts, strict=True):
                todo[order[self._expected_head(order, n)]] = True
            self.usable(todo)

    def _head(self, order: np.ndarray, n: int) -> slice:
        """Return the head of ``order`` holding its first ``n`` candidates not unusable."""
        maybe = np.cumsum(self.state[order] != 2)
        return slice(0, int(np.searchsorted(maybe, n)) + 1 if n else 0)

    def _expected_head(self, order: np.ndarray, n: int) -> slice:
        """Return the head of ``order`` expected to hold ``n`` usable candidates, and a margin.

        Candidates not screened yet count as usable at the share of those screened so far
        that are (one half before any): a round that screens them seldom falls short, so a
        choice takes few rounds (each costs the sweeps' fixed cost).
        """
        screened = np.count_nonzero(self.state)
        share = np.count_nonzero(self.state == 1) / screened if screened else 0.5
        weight = np.array([max(share, 0.1), 1.0, 0.0])[self.state[order]]
        want = n * (1 + MARGIN_SHARE) + MARGIN_COUNT
        return slice(0, int(np.searchsorted(np.cumsum(weight), want)) + 1 if n else 0)


MARGIN_SHARE, MARGIN_COUNT = 0.05, 3
"""A round of :meth:`Screened.first_usable` screens for 5 % and 3 candidates more than it
needs: what screening a few more costs against another round's fixed cost."""


def _screen_moves(
    robot: Robot, model, p0: np.ndarray, theta0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> tuple[np.ndarray, np.ndarray]:
    """Return which candidates (passing :func:`point_checks`) are usable, and their via points.

    Usable: a clear move from θ0, directly or, for those whose direct move is not clear,
    through a via point that makes it clear (the arm joints first, or the wrist first);
    NaN rows where the direct move is clear. The moves are sampled coarsely here;
    ``reach_ok`` checks the points chosen from finely.
    """
    coarse = 10.0

    def length_ok(x):
        d = wire_path(model.pulley, tool_position(model, np.radians(x)) - p0)[0]
        return (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm)

    via = np.full(q.shape, np.nan)
    # the direct moves, and each candidate alone (a move to itself: its one sample) in
    # the same sweep: where the wire or the arm is not clear at the candidate itself (the
    # last sample of every move to it), no via point reaches it, so only the others try
    # them (half of the Viper's blocked candidates, a quarter of the UR5e's, end so)
    direct, alone = move_ok(
        robot,
        model,
        p0,
        np.vstack([np.broadcast_to(theta0, q.shape), q]),
        np.vstack([q, q]),
        opt,
        coarse,
    ).reshape(2, len(q))
    need = np.flatnonzero(~direct & alone)
    # the two via points of each: the arm's joints moved first, or the wrist's; both tried
    # in one sweep (few make a move clear, so trying the wrist's where the arm's does
    # costs little)
    arm, wrist = np.tile(theta0, (len(need), 1)), np.tile(theta0, (len(need), 1))
    arm[:, :3], wrist[:, 3:] = q[need, :3], q[need, 3:]
    v = np.vstack([arm, wrist])
    ends = np.vstack([q[need], q[need]])
    # a via point at the candidate or at θ0 makes the direct move again: not clear
    good = length_ok(v) & np.any(v != ends, axis=1) & np.any(v != theta0, axis=1)
    good[good] = reach_ok(robot, model, p0, theta0, ends[good], v[good], opt, coarse)
    by_arm, by_wrist = good.reshape(2, len(need))
    via[need[by_wrist]] = wrist[by_wrist]
    via[need[by_arm]] = arm[by_arm]  # the arm's first where both make it clear
    return direct | ~np.isnan(via[:, 0]), via


def point_checks(
    robot: Robot, model, p0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> np.ndarray:
    """Return which candidate points pass every check of their own (:data:`BLOCKED_WHY`)."""
    return np.all(list(_point_failures(robot, model, p0, q, opt).values()), axis=0)


def _point_failures(
    robot: Robot, model, p0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> dict[str, np.ndarray]:
    """Return, per check of :data:`BLOCKED_WHY`, which candidate points pass it.

    The wire length (above ``min_wire_mm``, within the encoder's range less the margin),
    an eyelet's exit cone (the points read the encoder), the wrist singularity of an
    analytic wrist (|sin θ5| ≥ sin 8°) and the arm clear of itself and the cell.
    """
    f = frames(model, np.radians(q))  # one evaluation of the chain for the tool and the cell
    p = tool_position(model, np.radians(q), f)
    d = wire_path(model.pulley, p - p0)[0]
    wrist = np.ones(len(q), bool)
    if ik.analytic_structure(model):
        wrist = np.abs(np.sin(np.radians(q[:, 4]) + model.dh[4, 2])) >= np.sin(np.radians(8))
    return {
        "range": (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm),
        "cone": within_cone(robot.encoder.exit, p - p0),
        "wrist": wrist,
        "cell": robot.cell_gaps(q, p0, model, f, SURE_GAP_MM).smallest() >= 0,
    }


BLOCKED_WHY = {
    "range": "the wire's length out of the encoder range",
    "cone": "the wire outside the exit's cone",
    "wrist": "at the wrist singularity",
    "cell": "the arm in itself or the cell",
}
"""The checks of a candidate point itself (:func:`_point_failures`) and what each
blocks, in words (:func:`blocked`)."""


class Blocked(WirecalError):
    """No plan around a θ0, for a reason that says what blocked its candidates (:func:`blocked`).

    The reason is worked out when first read (``problems``, ``str``): it sweeps every
    candidate's move from θ0, which the θ0 search spares for a θ0 it passes over.
    """

    def __init__(self, reason: Callable[[], str]):
        Exception.__init__(self)
        self._reason = reason
        self._problems: list[str] | None = None

    @property
    def problems(self) -> list[str]:
        """Return the one problem: the reason, worked out once."""
        if self._problems is None:
            self._problems = [self._reason()]
        return self._problems

    @problems.setter
    def problems(self, value: list[str]) -> None:
        self._problems = list(value)

    def __str__(self) -> str:
        """Return the reason (worked out now if not yet)."""
        return "\n".join(self.problems)


def no_usable_error(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> Blocked:
    """Return the error of a θ0 around which fewer than a step's candidates are usable."""
    return Blocked(
        lambda: (
            f"{robot.source}: almost no usable configuration around θ0 "
            f"{theta0.tolist()}: {blocked(robot, theta0, opt)}"
        )
    )


def blocked(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> str:
    """Say which constraints blocked the candidates around θ0, with counts.

    Per check of the points themselves (a candidate may fail several), then the moves
    from θ0 of the candidates that pass them: through the arm or the cell (where the wire
    is clear), or with the wire closer than ``clearance_mm`` to a link.
    """
    model = robot.nominal
    q = candidates(robot, theta0, opt, np.random.default_rng(opt.seed))
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    fails = _point_failures(robot, model, p0, q, opt)
    counts = [f"{int(np.sum(~v))} {k} ({BLOCKED_WHY[k]})" for k, v in fails.items() if not v.all()]
    left = q[np.all(list(fails.values()), axis=0)]
    if len(left):
        sweep = move_clearance(robot, model, p0, theta0, left, 10.0, 1, np.inf)
        counts.append(f"{int(np.sum(sweep == -np.inf))} cell on the move from theta0")
        counts.append(
            f"{int(np.sum((sweep > -np.inf) & (sweep < opt.clearance_mm)))} clearance (the "
            "wire too close to a link on the move from theta0)"
        )
    return f"of {len(q)} candidates, blocked: " + ", ".join(counts)
