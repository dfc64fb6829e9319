"""Design of experiments (paper §2.2–2.3, §3.4).

Design of experiments (paper §2.2–2.3, §3.4): θ0, the identification order and one point
set per parameter, for any 6R arm.

Candidates are configurations that move one to three joints away from θ0 (as the paper's
points do) or all of them; each is screened at once (vectorised) for the joint limits with a
margin, the wire length (above a minimum, within the encoder's range), the exit angle (a
wire leaving an eyelet stays within its cone, :mod:`~wirecal.solver.exit_geometry`), the
wrist singularity, the arm clear of its own body and the cell (floor, keep-out volumes,
body limits: :mod:`~wirecal.solver.cell`) and the wire's clearance from the links along the
joint-interpolated move from θ0.

* **Order** (§3.4): among the parameters not yet identified, the next is the one that the
  most informative isolating points single out: points where |Ψ_t| ≤ tol·|Ψ_j| for every
  other parameter t still unknown (eq. 18–19).
* **Points**: from the isolating candidates, greedily the set minimising the step's
  linearised variance *including what earlier estimates leak into it* (their errors reach
  the step through Ψ_{i,<j}); the paper's criterion (largest |Ψ_j| only) is computed beside
  it and the reduction reported. Points are kept at least ``spread_deg`` apart.
* **Motion**: a candidate whose direct move from θ0 would sweep the wire through a link
  or wrap it around the flange (joint 6 turning more than 180°) is kept if a via point
  (the arm joints first, or the wrist first) makes the move clear; the via is recorded in
  the plan. Per step, the visiting order from θ0 and back is the shortest-time tour
  (nearest neighbour, then 2-opt) over clear moves.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from wirecal.solver import ik
from wirecal.solver.accuracy import noise_covariance, stepwise_map, tool_error, workspace
from wirecal.solver.clearance import wire_clearance, wire_trim_mm
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import describe, wire_path, within_cone
from wirecal.solver.plan_exit import largest_exit_deg
from wirecal.solver.identifiability import analyse
from wirecal.solver.kinematics import frames, tool_jacobian, tool_position
from wirecal.solver.params import ErrorSet
from wirecal.solver.plan import Plan, Step
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    READING_INTERVAL_S,
    RunParameters,
    move_durations_s,
    move_profiles,
    move_speeds_pct,
    run_timeline,
    settle_time_s,
)
from wirecal.solver.sensitivity import PSI_FLOOR, sensitivity

Method = Literal["joint", "stepwise"]
Progress = Callable[[float], None]


@dataclass(frozen=True)
class PlanOptions:
    """The planner's settings."""

    points_per_step: int = 5
    tol: float = 0.05  # isolation while designing (stricter than psi's verdict)
    margin_deg: float = 5.0  # from every joint limit
    min_wire_mm: float = 40.0
    range_margin_mm: float = 50.0
    clearance_mm: float = 10.0  # wire to link capsules
    spread_deg: float = 4.0  # between the points of one step
    samples: int = 400  # candidates per joint subset
    run: RunParameters = DEFAULT_RUN  # for the robot-time estimate (as wirecal gen)
    seed: int = 0
    prior: float = 0.5  # typical |offset| (deg, mm) of a still-unknown parameter
    sigma_mm: float = 0.011  # reading noise, quantisation included
    method: Method = "joint"  # the estimator the points are chosen for
    points: int | None = None  # joint design: points in all (None: points_per_step each)
    min_points: int = 2  # joint design: points of every step, at least


@dataclass
class StepDesign:
    """One designed step and its figures of merit."""

    parameter: str
    points_deg: np.ndarray
    strength: float  # RMS |Ψ_j| of the points
    leak_ours: float  # variance factor with our choice
    leak_paper: float | None  # … with the paper's criterion (largest |Ψ_j|); None: joint
    via_deg: np.ndarray  # (0 or 1, n): passed on the way to the first point


@dataclass
class Design:
    """A designed plan with its per-step figures, exclusions and predictions."""

    plan: Plan
    steps: list[StepDesign]
    excluded: dict[str, str] = field(default_factory=dict)  # parameter → reason
    predicted: dict[str, float] = field(default_factory=dict)
    robot_time_s: float = 0.0
    exit_line: str = ""  # the wire exit and the plan's largest exit angle, in words
    cell_line: str = ""  # the cell the plan keeps clear of, in words
    method: Method = "stepwise"  # the estimator the points were chosen for
    theta0_tried: int = 1  # θ0s designed to find this plan (1: the θ0 given)
    search_line: str = ""  # the θ0 search in words, when it went past the first θ0s
    unidentifiable: tuple[str, ...] = ()  # excluded as unobservable or redundant

    def isolation_failed(self) -> list[str]:
        """Return the parameters excluded as not isolated (another θ0 may isolate them)."""
        return [n for n in self.excluded if n not in self.unidentifiable]

    def header(self) -> str:
        """Return the plan file's header comment: the design's figures in words."""
        lines = [
            "Designed by 'wirecal plan' (Boschetti & Sinico's method, see the README).",
            f"theta0 {np.round(self.plan.theta0_deg, 2).tolist()} deg; order "
            + " ".join(self.plan.order)
            + ".",
            *([self.search_line] if self.search_line else []),
            "Predicted tool-point error (sigma 0.01 mm, mean over the workspace"
            + (
                f"; the {len(self.excluded)} parameters not planned at their prior"
                if self.excluded
                else ""
            )
            + f"): joint {self.predicted['joint']:.4f} mm, step-by-step "
            f"{self.predicted['stepwise']:.4f} mm.",
            f"Estimated robot time {self.robot_time_s / 60:.1f} min "
            f"({self.plan.n_points} points, "
            f"{sum(len(s.via_deg) for s in self.plan.steps)} via points).",
            self.exit_line,
            self.cell_line,
        ]
        if self.method == "joint":
            lines.append(
                "Points chosen for the joint method (least tool-point variance over the "
                "workspace per second of robot time), each step's points isolating its "
                "parameter so the step-by-step method runs too. Per step: its points, "
                "RMS |Psi| (mm/deg or mm/mm), the noise gain (sigma of the estimate per "
                "mm of reading noise) and the step-by-step expected squared error."
            )
        else:
            lines.append(
                "Per step: RMS |Psi| of its points (mm/deg or mm/mm), the noise gain "
                "(sigma of the estimate per mm of reading noise) and the leak-aware "
                "choice against the paper's."
            )
        for j, s in enumerate(self.steps, 1):
            gain = 1 / (s.strength * np.sqrt(len(s.points_deg)))
            head = f"step {j} {s.parameter}: "
            if s.leak_paper is None:
                lines.append(
                    f"{head}{len(s.points_deg)} points, RMS |Psi| {s.strength:.2f}, noise "
                    f"gain {gain:.2f}; expected squared error with noise and leaks "
                    f"{s.leak_ours:.3g}"
                )
                continue
            cut = 100 * (1 - s.leak_ours / s.leak_paper) if s.leak_paper > 0 else 0.0
            lines.append(
                f"{head}RMS |Psi| {s.strength:.2f}, noise gain "
                f"{gain:.2f}; expected squared error with noise and leaks "
                f"{s.leak_ours:.3g} ({cut:.0f} % below the largest-|Psi| choice's "
                f"{s.leak_paper:.3g})"
            )
        for name, why in self.excluded.items():
            lines.append(f"not planned: {name}: {why}")
        return "\n".join(lines)


def _subsets(n: int):
    for size in (1, 2, 3):
        yield from itertools.combinations(range(n), size)
    yield tuple(range(n))


def candidates(robot: Robot, theta0: np.ndarray, opt: PlanOptions, rng) -> np.ndarray:
    """Return configurations (deg) moving a few joints away from θ0.

    Within the margin of the body limits (the joint limits narrowed by ``[cell]``).
    """
    lo, hi = robot.body_limits_deg
    lo, hi = lo + opt.margin_deg, hi - opt.margin_deg
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


def move_samples(
    a: np.ndarray, b: np.ndarray, step_deg: float = 2.0
) -> tuple[np.ndarray, np.ndarray]:
    """Return the configurations along moves a → b and each move's first sample.

    Configurations (deg) along the joint-interpolated moves a → b (rows broadcast),
    every ``step_deg`` of the largest joint motion, b included and a not; and the index of
    each move's first sample (for ``np.minimum.reduceat`` and the like).
    """
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    count = np.maximum(1, np.ceil(np.max(np.abs(b - a), axis=1) / step_deg)).astype(int)
    move = np.repeat(np.arange(len(a)), count)
    first = np.cumsum(count) - count
    t = (np.arange(len(move)) - first[move] + 1) / count[move]
    return a[move] + t[:, None] * (b[move] - a[move]), first


CHUNK_SAMPLES = 16384
"""Configurations evaluated per batch along moves: memory stays bounded (a few MiB per
batch) and the batch's arrays stay in the processor's cache, which is faster than one
batch of millions."""


def move_clearance(
    robot: Robot,
    model,
    p0: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    step_deg: float = 2.0,
    every: int = 1,
    longest_mm: float = np.inf,
) -> np.ndarray:
    """Return the smallest wire gap (mm) to the links along moves a → b.

    The smallest wire gap (mm) to the links along the joint-interpolated moves a → b
    (deg, rows broadcast), sampled every ``step_deg`` of the largest joint motion
    (:func:`move_samples`), in batches of about ``CHUNK_SAMPLES`` configurations. With
    ``every`` > 1 only every ``every``-th of those samples and each move's end are
    evaluated: a subset, so a gap found there is a gap of the full sampling too. A sample
    where the modelled wire is longer than ``longest_mm`` counts as no gap at all (−inf):
    the encoder's range, checked along the move as ``wirecal gen`` checks it; so does a
    sample where the arm meets itself or the cell (:mod:`~wirecal.solver.cell`).
    """
    if robot.link_radius_mm is None:
        raise WirecalError(f"{robot.source}: the wire clearance needs the link radii")
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    count = np.maximum(1, np.ceil(np.max(np.abs(b - a), axis=1) / step_deg))
    # batch k holds the moves whose samples start in [k·CHUNK, (k+1)·CHUNK)
    batch = ((np.cumsum(count) - count) // CHUNK_SAMPLES).astype(int)
    edges = np.searchsorted(batch, np.arange(batch[-1] + 2)) if len(a) else [0]
    trim = wire_trim_mm(robot)
    out = np.empty(len(a))
    for lo, hi in itertools.pairwise(edges):
        q, first = move_samples(a[lo:hi], b[lo:hi], step_deg)
        if every > 1:
            k = np.arange(len(q)) - np.repeat(first, np.diff(np.r_[first, len(q)]))
            last = np.zeros(len(q), bool)
            last[np.r_[first[1:], len(q)] - 1] = True
            keep = (k % every == every - 1) | last
            first = np.cumsum(keep)[first] - keep[first]  # each move keeps its end
            q = q[keep]
        q_rad = np.radians(q)
        f = frames(model, q_rad)  # one evaluation of the chain for both checks
        gap = wire_clearance(model, q_rad, p0, robot.link_radius_mm, trim, f)
        gap = np.where(robot.cell_gaps(q, p0, model, f).smallest() < 0, -np.inf, gap)
        if np.isfinite(longest_mm):
            d = wire_path(model.pulley, tool_position(model, q_rad, f) - p0)[0]
            gap = np.where(np.nan_to_num(d) > longest_mm, -np.inf, gap)
        out[lo:hi] = np.minimum.reduceat(gap, first)
    return out


def move_ok(robot: Robot, model, p0, a, b, opt: PlanOptions, step_deg: float = 2.0) -> np.ndarray:
    """Return which moves a → b are safe for the arm and the wire.

    Moves a → b that keep the arm out of itself and the cell, the wire clear of the
    links, within the encoder's range less ``range_margin_mm`` all along, and do not turn
    joint 6 by more than 180° (which would wrap the wire around the flange).
    """
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    ok = np.abs(b[:, -1] - a[:, -1]) <= 180
    # a quick pass over every fourth sample rejects most blocked moves (a gap there is a
    # gap of the full sampling); the moves it passes then get every sample
    for every in (4, 1):
        idx = np.flatnonzero(ok)
        longest = robot.encoder.range_mm - opt.range_margin_mm
        gap = move_clearance(robot, model, p0, a[idx], b[idx], step_deg, every, longest)
        ok[idx] = gap >= opt.clearance_mm
    return ok


def reach_ok(
    robot: Robot, model, p0, theta0, q, via, opt: PlanOptions, step_deg: float = 2.0
) -> np.ndarray:
    """Return whether each point q is reached from θ0 with the wire clear.

    Directly, or through its via point (NaN row: none).
    """
    direct = np.isnan(via[:, 0])
    ok = np.zeros(len(q), bool)
    ok[direct] = move_ok(robot, model, p0, theta0, q[direct], opt, step_deg)
    viaed = np.flatnonzero(~direct)
    ok[viaed] = move_ok(robot, model, p0, theta0, via[viaed], opt, step_deg)
    viaed = viaed[ok[viaed]]  # the second leg only where the first is clear
    ok[viaed] = move_ok(robot, model, p0, via[viaed], q[viaed], opt, step_deg)
    return ok


def screen(
    robot: Robot, model, p0: np.ndarray, theta0: np.ndarray, q: np.ndarray, opt: PlanOptions
) -> tuple[np.ndarray, np.ndarray]:
    """Return which candidates are usable, and their via points.

    Which candidates are usable (wire length, an eyelet's exit cone, wrist singularity,
    the arm clear of itself and the cell, a clear move from θ0)
    and, for those whose direct move is not clear, a via point that makes it clear (the
    arm joints first, or the wrist first); NaN rows where the direct move is clear. The
    moves are sampled coarsely here; ``reach_ok`` checks the points chosen from finely.
    """
    coarse = 10.0

    def length_ok(x):
        d = wire_path(model.pulley, tool_position(model, np.radians(x)) - p0)[0]
        return (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm)

    ok = _point_checks(robot, model, p0, q, opt)
    via = np.full(q.shape, np.nan)
    direct = np.zeros(len(q), bool)
    direct[ok] = move_ok(robot, model, p0, theta0, q[ok], opt, coarse)
    arm = slice(0, 3)
    for first in ("arm", "wrist"):
        need = np.flatnonzero(ok & ~direct & np.isnan(via[:, 0]))
        if not len(need):
            break
        v = np.tile(theta0, (len(need), 1))
        if first == "arm":
            v[:, arm] = q[need, arm]
        else:
            v[:, 3:] = q[need, 3:]
        good = length_ok(v)
        good[good] = reach_ok(robot, model, p0, theta0, q[need[good]], v[good], opt, coarse)
        via[need[good]] = v[good]
    return ok & (direct | ~np.isnan(via[:, 0])), via


def _point_checks(
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
    p = tool_position(model, np.radians(q))
    d = wire_path(model.pulley, p - p0)[0]
    wrist = np.ones(len(q), bool)
    if ik.analytic_structure(model):
        wrist = np.abs(np.sin(np.radians(q[:, 4]) + model.dh[4, 2])) >= np.sin(np.radians(8))
    return {
        "range": (d >= opt.min_wire_mm) & (d <= robot.encoder.range_mm - opt.range_margin_mm),
        "cone": within_cone(robot.encoder.exit, p - p0),
        "wrist": wrist,
        "cell": robot.cell_gaps(q, p0, model).smallest() >= 0,
    }


BLOCKED_WHY = {
    "range": "the wire's length out of the encoder range",
    "cone": "the wire outside the exit's cone",
    "wrist": "at the wrist singularity",
    "cell": "the arm in itself or the cell",
}
"""The checks of a candidate point itself (:func:`_point_failures`) and what each
blocks, in words (:func:`_blocked`)."""


def _blocked(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> str:
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


def _errors(psi_j, psi_prev, cov_prev, psi_next, base, cand, opt: PlanOptions) -> np.ndarray:
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


def _error(psi_j, psi_prev, cov_prev, psi_next, opt: PlanOptions) -> float:
    """Return the mean squared error of a step's estimate with all its points (:func:`_errors`)."""
    n = len(psi_j)
    return float(_errors(psi_j, psi_prev, cov_prev, psi_next, range(n - 1), [n - 1], opt)[0])


class _Links:
    """Which moves between a step's candidates keep the wire clear, worked out on demand.

    ``ok(sources, js)``: whether the moves from each of the candidates ``sources`` to
    each of the candidates ``js`` are safe (:func:`move_ok`); every move is checked once,
    however often the greedy choices of a step ask about it.
    """

    def __init__(self, robot: Robot, model, p0: np.ndarray, q: np.ndarray, opt: PlanOptions):
        self.robot, self.model, self.p0, self.q, self.opt = robot, model, p0, q, opt
        self.known = np.zeros((len(q), len(q)), np.int8)  # 0 unknown, 1 clear, 2 not

    def ok(self, sources: list[int], js: np.ndarray) -> np.ndarray:
        """Return whether the moves from every one of ``sources`` to each of ``js`` are safe."""
        i = np.repeat(np.asarray(sources, int), len(js))
        j = np.tile(js, len(sources))
        todo = self.known[i, j] == 0
        if todo.any():
            clear = move_ok(
                self.robot, self.model, self.p0, self.q[i[todo]], self.q[j[todo]], self.opt
            )
            self.known[i[todo], j[todo]] = np.where(clear, 1, 2)
        return np.all((self.known[i, j] == 1).reshape(len(sources), len(js)), axis=0)


def _choose(
    psi_j, psi_prev, cov_prev, psi_next, q, has_via, links: _Links, opt: PlanOptions, criterion
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
    psi_j, psi_prev, cov_prev, psi_next, q, has_via, links: _Links, allowed, opt, criterion
) -> list[int]:
    """Pick up to K points one at a time (see :func:`_choose`).

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
            val = _errors(psi_j, psi_prev, cov_prev, psi_next, chosen, cand, opt)
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


def design(
    robot: Robot,
    theta0: np.ndarray | None = None,
    opt: PlanOptions = PlanOptions(),
    progress: Progress | None = None,
) -> Design:
    """Return a plan for the robot file's parameters (θ0 chosen when not given).

    θ0 chosen: the best plan (fewest parameters unplanned, then the smallest predicted
    error) of the first :data:`THETA0_TRIES` θ0 drawn clear of the cell; when it leaves
    parameters unplanned (but unobservable or redundant ones, which no θ0 plans), up to
    :data:`MORE_THETA0_DESIGNED` more θ0, the best of
    :data:`MORE_THETA0_CHECKED` further draws by a quick check (:func:`_isolated_count`),
    until one gives a complete plan (:func:`_search_further`). A θ0 given is the only one
    tried. ``progress`` is called with the fraction of the work done (0…1) as it advances.
    """
    _check_room(robot, opt)
    if theta0 is not None:
        return _design_at(robot, np.asarray(theta0, dtype=float), opt, progress)
    draws = _theta0_draws(robot, opt)
    first = draws[:THETA0_TRIES]
    parts = len(first) + MORE_THETA0_DESIGNED
    best, problems = None, []
    for k, t0 in enumerate(first):
        try:
            d = _design_at(robot, t0, opt, _part(progress, k, parts))
        except WirecalError as exc:
            problems.append(exc.problems[0])
            continue
        if best is None or _score(d) < _score(best):
            best = d
    if best is not None:
        best.theta0_tried = len(first)
    if best is None or best.isolation_failed():
        more = draws[THETA0_TRIES : THETA0_TRIES + MORE_THETA0_CHECKED]
        best = _search_further(
            robot, more, (best, problems), opt, lambda k: _part(progress, len(first) + k, parts)
        )
    if best is None:
        raise WirecalError(
            [
                f"{robot.source}: no θ0 tried gives a plan ({len(problems)} tried; each "
                "θ0's reasons follow)",
                *problems,
            ]
        )
    return best


THETA0_TRIES = 6
"""θ0 designed first, all of them; the best plan of them is kept when it is complete."""

MORE_THETA0_CHECKED = 60
"""Further θ0 drawn when the first leave parameters unplanned, each given the quick check
of :func:`_isolated_count` (0.1–0.7 s on the UR5, a tenth of a design)."""

MORE_THETA0_DESIGNED = 4
"""Of those, designed at most, best checked first; the first complete plan is kept."""


def _score(d: Design) -> tuple[int, float]:
    """Return a plan's rank among θ0s: parameters unplanned, then the predicted errors."""
    return (len(d.excluded), d.predicted["stepwise"] + d.predicted["joint"] * 5)


def _search_further(
    robot: Robot,
    more: np.ndarray,
    so_far: tuple[Design | None, list[str]],
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
        problems: list[str],
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
            d = _design_at(self.robot, theta0, self.opt, self.part(len(self.designed) - 1))
        except WirecalError as exc:
            self.problems.append(exc.problems[0])
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

    The candidates of :func:`_design_at` and its screening (:func:`screen`), applied only
    to candidates isolating a parameter still unknown (:func:`_isolating`; few do), so a
    fraction of a design's time; no points, via points or tours are chosen. The order
    stops where the design's does when no parameter is unidentifiable.
    """
    model = robot.nominal
    q = candidates(robot, theta0, opt, np.random.default_rng(opt.seed))
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    q = q[_point_checks(robot, model, p0, q, opt)]
    names = list(robot.parameters)
    col = {n: k for k, n in enumerate(names)}
    psi = sensitivity(model, q, theta0, names).psi
    state = np.zeros(len(q), np.int8)  # 0 not screened yet, 1 usable, 2 not
    remaining = names
    while remaining:
        todo = np.zeros(len(q), bool)
        for j in remaining:
            todo |= _isolating(psi, col, j, remaining, opt)
        todo &= state == 0
        if todo.any():
            state[todo] = np.where(screen(robot, model, p0, theta0, q[todo], opt)[0], 1, 2)
        best = _most_informative(psi[state == 1], col, remaining, opt)
        if best is None:
            break
        remaining = [t for t in remaining if t != best[0]]
    return len(names) - len(remaining)


def _check_room(robot: Robot, opt: PlanOptions) -> None:
    """Raise when a joint's body limits leave no room for points inside the margin."""
    body_lo, body_hi = robot.body_limits_deg
    span = body_hi - body_lo
    narrow = np.flatnonzero(span <= 2 * opt.margin_deg)
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
    lo, hi = robot.body_limits_deg
    inset = np.clip((hi - lo) / 4, opt.margin_deg, 20.0)
    t0 = np.round(rng.uniform(lo + inset, hi - inset, (THETA0_DRAWS, robot.n_joints)), 0)
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


def _check_theta0(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> None:
    """Raise when a joint of θ0 is within the margin of its body limits, or θ0 collides."""
    lo, hi = robot.body_limits_deg
    for j in np.flatnonzero((theta0 < lo + opt.margin_deg) | (theta0 > hi - opt.margin_deg)):
        raise WirecalError(
            f"theta0: joint {j + 1} = {theta0[j]:g} deg is within "
            f"{opt.margin_deg:g} deg of its limits [{lo[j]:g}, {hi[j]:g}] (the joint "
            "limits, narrowed by [cell] body limits)"
        )
    p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
    gaps = robot.cell_gaps(theta0, p0)
    if gaps.smallest()[0] < 0:
        raise WirecalError(f"theta0 {theta0.tolist()}: collides (cell): {gaps.cause(0)}")


def _unidentifiable(model, q: np.ndarray, theta0: np.ndarray, names: list[str]) -> dict[str, str]:
    """Return the parameters no plan can identify (unobservable, or redundant), with why."""
    excluded: dict[str, str] = {}
    ident = analyse(model, q, theta0, names)
    for name in ident.unobservable:
        excluded[name] = (
            "unobservable: it moves every point and the encoder alike"
            if name in ("th1", "d1", "a0", "al0")
            else "unobservable from any candidate configuration"
        )
    for combo in ident.combinations:
        last = combo[-1][0]
        excluded[last] = (
            "redundant with "
            + ", ".join(n for n, _ in combo[:-1])
            + ": no wire length separates them; keep one"
        )
    return excluded


def _isolating(
    psi: np.ndarray, col: dict[str, int], j: str, remaining: list[str], opt
) -> np.ndarray:
    """Return which candidates isolate parameter j from the others still unknown (eq. 18–19).

    |Ψ_t| ≤ tol·|Ψ_j| (or below :data:`PSI_FLOOR`) for every other parameter t of
    ``remaining``, and |Ψ_j| ≥ 0.05.
    """
    pj = psi[:, col[j]]
    others = [col[t] for t in remaining if t != j]
    limit = np.maximum(opt.tol * np.abs(pj), PSI_FLOOR)
    iso = (
        np.all(np.abs(psi[:, others]) <= limit[:, None], axis=1)
        if others
        else np.ones(len(pj), bool)
    )
    return iso & (np.abs(pj) >= 0.05)


def _most_informative(
    psi: np.ndarray, col: dict[str, int], remaining: list[str], opt: PlanOptions
) -> tuple[str, np.ndarray] | None:
    """Choose the next parameter to isolate and its isolating candidates.

    The parameter whose ``points_per_step`` most sensitive isolating candidates
    (:func:`_isolating`) carry the most information (Σψ²); None when no parameter has
    that many isolating candidates.
    """
    k = opt.points_per_step
    best: tuple[float, str, np.ndarray] | None = None
    for j in remaining:
        iso = _isolating(psi, col, j, remaining, opt)
        if iso.sum() < k:
            continue
        info = float(np.sort(psi[iso, col[j]] ** 2)[-k:].sum())
        if best is None or info > best[0]:
            best = (info, j, np.flatnonzero(iso))
    return None if best is None else (best[1], best[2])


@dataclass
class _Pool:
    """One step: its isolating candidates and the points chosen among them.

    ``iso`` indexes the screened candidates; ``pj``, ``pprev``, ``pnext`` are their Ψ
    columns (the step's parameter, the earlier ones, the later ones); ``cov_prev`` the
    earlier estimates' error covariance; ``picks`` index ``iso``.
    """

    parameter: str
    iso: np.ndarray
    links: _Links
    pj: np.ndarray
    pprev: np.ndarray
    pnext: np.ndarray
    cov_prev: np.ndarray
    picks: list[int]
    leak_paper: float | None = None


def _design_at(
    robot: Robot, theta0: np.ndarray, opt: PlanOptions, progress: Progress | None = None
) -> Design:
    """Design a plan around a given θ0 (see :func:`design`).

    Step by step (paper §3.4), each step's points chosen by the leak-aware greedy: all
    ``points_per_step`` of them for the stepwise method, the first ``min_points`` for the
    joint method, whose remaining points :func:`_joint_choice` then adds over all steps.
    """
    tick = progress or (lambda f: None)
    model = robot.nominal
    _check_theta0(robot, theta0, opt)
    q_all = candidates(robot, theta0, opt, np.random.default_rng(opt.seed))
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    usable, via_all = screen(robot, model, p0, theta0, q_all, opt)
    tick(0.5)
    q_all, via_all = q_all[usable], via_all[usable]
    if len(q_all) < opt.points_per_step:
        raise WirecalError(
            f"{robot.source}: almost no usable configuration around θ0 "
            f"{theta0.tolist()}: {_blocked(robot, theta0, opt)}"
        )
    names = list(robot.parameters)
    excluded = _unidentifiable(model, q_all[:: max(1, len(q_all) // 3000)], theta0, names)
    unidentifiable = tuple(excluded)
    remaining = [n for n in names if n not in excluded]
    psi = sensitivity(model, q_all, theta0, remaining).psi
    pools = _step_by_step(robot, theta0, q_all, via_all, psi, remaining, excluded, opt, tick)
    if opt.method == "joint":
        _joint_choice(robot, theta0, q_all, via_all, psi, remaining, pools, opt)
    steps = []
    for k, pool in enumerate(pools):
        pts = pool.iso[pool.picks]
        path = _tour(robot, model, p0, theta0, q_all[pts], via_all[pts], opt)
        if path is None:
            raise WirecalError(
                f"{robot.source}: step {k + 1} ({pool.parameter}): no visiting "
                "order keeps the wire clear of the links; try another "
                "--seed or --theta0, or check the link radii"
            )
        pool.picks = [pool.picks[i] for i in path]
        first_via = via_all[pool.iso[pool.picks[0]]]
        steps.append(
            StepDesign(
                pool.parameter,
                q_all[pts[path]],
                float(np.sqrt(np.mean(pool.pj[pool.picks] ** 2))),
                _error(
                    pool.pj[pool.picks],
                    pool.pprev[pool.picks],
                    pool.cov_prev,
                    pool.pnext[pool.picks],
                    opt,
                ),
                pool.leak_paper,
                first_via[None] if not np.isnan(first_via[0]) else np.zeros((0, len(theta0))),
            )
        )
    plan = Plan(
        theta0,
        tuple(p.parameter for p in pools),
        tuple(Step(s.parameter, s.points_deg, s.via_deg) for s in steps),
        robot=robot.name,
    )
    d = Design(plan, steps, excluded, method=opt.method, unidentifiable=unidentifiable)
    d.predicted = predicted_accuracy(robot, plan, unplanned=tuple(excluded))
    d.robot_time_s = robot_time(robot, plan, opt.run)
    d.exit_line = exit_line(robot, plan)
    d.cell_line = cell_line(robot)
    tick(1.0)
    return d


def _step_by_step(
    robot: Robot,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    psi: np.ndarray,
    remaining: list[str],
    excluded: dict[str, str],
    opt: PlanOptions,
    tick: Progress,
) -> list[_Pool]:
    """Return the steps in the order they isolate their parameters, with their points.

    The order of §3.4 (:func:`_most_informative`); per step the leak-aware greedy
    choice (:func:`_choose`) of ``points_per_step`` points (``min_points`` for the joint
    design), its error covariance taking the earlier steps' choices into account, and
    for the stepwise design the paper's choice for comparison. Parameters that cannot be
    isolated go into ``excluded``.
    """
    model = robot.nominal
    p0 = tool_position(model, np.radians(theta0)[None])[0]
    has_via = ~np.isnan(via_all[:, 0])
    col = {n: k for k, n in enumerate(remaining)}
    n_params = len(remaining)
    remaining = list(remaining)
    pools: list[_Pool] = []
    k_first = opt.points_per_step if opt.method == "stepwise" else opt.min_points
    while remaining:
        best = _most_informative(psi, col, remaining, opt)
        if best is None:
            for j in remaining:
                excluded[j] = (
                    f"cannot be isolated: no {opt.points_per_step} points leave it alone "
                    f"among {', '.join(t for t in remaining if t != j)}"
                )
            break
        j, iso = best
        # the most sensitive isolating points, their moves from θ0 checked finely
        iso = iso[np.argsort(-np.abs(psi[iso, col[j]]), kind="stable")[:600]]
        iso = iso[reach_ok(robot, model, p0, theta0, q_all[iso], via_all[iso], opt)]
        order = [p.parameter for p in pools]
        prev = [col[t] for t in order]
        nxt = [col[t] for t in remaining if t != j]
        # error covariance of the earlier estimates (linearised stepwise map)
        cov_prev = (
            _stepwise_cov(model, theta0, order, [q_all[p.iso[p.picks]] for p in pools], opt)
            if order
            else np.zeros((0, 0))
        )
        pool = _Pool(
            j,
            iso,
            _Links(robot, model, p0, q_all[iso], opt),
            psi[iso, col[j]],
            psi[np.ix_(iso, prev)] if prev else np.zeros((len(iso), 0)),
            psi[np.ix_(iso, nxt)] if nxt else np.zeros((len(iso), 0)),
            cov_prev,
            [],
        )
        args = (pool.pj, pool.pprev, cov_prev, pool.pnext, q_all[iso], has_via[iso], pool.links)
        ours = _choose(*args, replace(opt, points_per_step=k_first), "ours")
        if ours is None:
            excluded[j] = f"too few isolating points {opt.spread_deg:g} deg apart"
            remaining.remove(j)
            continue
        if opt.method == "stepwise":
            paper = _choose(*args, opt, "paper")
            pool.leak_paper = (
                _error(pool.pj[paper], pool.pprev[paper], cov_prev, pool.pnext[paper], opt)
                if paper is not None
                else np.inf
            )
        pts = iso[ours]
        path = _tour(robot, model, p0, theta0, q_all[pts], via_all[pts], opt)
        pool.picks = [ours[i] for i in path] if path is not None else ours
        pools.append(pool)
        remaining.remove(j)
        tick(0.5 + 0.4 * len(pools) / n_params)
    if not pools:
        raise WirecalError(
            f"{robot.source}: no parameter can be isolated around θ0 {theta0.tolist()} "
            f"by the {len(q_all)} usable candidates ({_blocked(robot, theta0, opt)}); try "
            "another --theta0"
        )
    return pools


def _joint_choice(
    robot: Robot,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    psi: np.ndarray,
    names: list[str],
    pools: list[_Pool],
    opt: PlanOptions,
) -> None:
    """Add points to the steps for the joint method, up to ``points`` in all.

    Greedy I-optimal design: the criterion is the joint estimate's tool-point variance
    integrated over the workspace, φ = tr(W·Σ), W the mean over the workspace of J_pᵀJ_p
    and Σ = (P⁻¹ + JᵀJ/σ²)⁻¹ (P: the prior of size ``prior``; it hardly matters once
    every step has its first points). A point with sensitivity row x lowers φ by
    xᵀΣWΣx / (σ² + xᵀΣx) (Sherman–Morrison); each pick takes the candidate with the
    largest decrease per second of robot time it adds (its stop, and the move to it from
    θ0 or from the nearest point already in its step: :class:`RunParameters`' time model).
    A point joins only the step whose parameter it isolates, under the stepwise design's
    rules (``spread_deg`` from the step's points, a clear move from each, at most one via
    point per step) and only if it does not raise the step's stepwise error
    (:func:`_error`): the stepwise method stays as good as with the first points alone.
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
        now = _errors(*args, pool.picks[:-1], pool.picks[-1:], opt)[0]
        ok[ok] = _errors(*args, pool.picks, np.flatnonzero(ok), opt) <= now
        allowed[mine] = ok
        for a in here[len(here) - added :] if added else (theta0, *here):
            cost[mine[ok]] = np.minimum(cost[mine[ok]], _visit_s(robot, opt.run, p0, a, q[ok]))

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


def exit_line(robot: Robot, plan: Plan) -> str:
    """Return the wire exit in words with the plan's largest exit angle (plan header)."""
    largest = largest_exit_deg(robot, plan)
    text = f"Wire exit: {describe(robot.encoder.exit)}"
    return text + ("." if largest is None else f"; largest exit angle {largest:.1f} deg.")


def cell_line(robot: Robot) -> str:
    """Return the robot file's cell in words (plan header): what every move keeps clear of."""
    c = robot.cell
    narrowed = np.flatnonzero(
        (robot.body_limits_deg[0] > robot.joint_min_deg)
        | (robot.body_limits_deg[1] < robot.joint_max_deg)
    )
    body = (
        "body limits on joint " + ", ".join(str(j + 1) for j in narrowed)
        if narrowed.size
        else "no body limits"
    )
    return (
        f"Cell: floor at z = {c.floor_z_mm:g} mm of frame 0, margin {c.margin_mm:g} mm, "
        f"{len(c.boxes)} boxes, {len(c.half_spaces)} half-spaces, "
        f"{'an' if c.housing else 'no'} encoder housing, {body}: theta0, every point and "
        "every move keep the arm clear of itself and the cell (docs/cell.md)."
    )


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


def _part(
    progress: Callable[[float], None] | None, k: int, parts: int
) -> Callable[[float], None] | None:
    """Return the progress callback of part ``k`` of ``parts`` (its fraction → the whole)."""
    if progress is None:
        return None
    whole = progress
    return lambda fraction: whole((k + fraction) / parts)


def _visit_s(
    robot: Robot, run: RunParameters, p0: np.ndarray, start_deg: np.ndarray, ends_deg: np.ndarray
) -> np.ndarray:
    """Return the robot time (s) a point adds when visited from ``start_deg``.

    The move at the SPEED the wire allows, the predicted settle and the readings (the
    run's time model).
    """
    if not len(ends_deg):
        return np.zeros(0)
    starts = np.repeat(np.asarray(start_deg, dtype=float)[None], len(ends_deg), axis=0)
    moves = move_profiles(robot, robot.nominal, p0, starts, ends_deg)
    pct = move_speeds_pct(robot, moves, run.speed_pct)
    settle = settle_time_s(moves.vibration_mm(pct), robot.encoder.mm_per_count, run)
    return moves.duration_s(pct) + settle + READING_INTERVAL_S * (run.readings - 1)


def _tour(robot: Robot, model, p0, theta0, pts, vias, opt: PlanOptions) -> np.ndarray | None:
    """Return the visiting order from θ0 and back, or None.

    The visiting order from θ0 and back (nearest neighbour, improved by 2-opt) over
    moves that keep the arm and the wire clear (``move_ok``); a point reached through a
    via point can only come first, and last only when it is the step's only point and its
    direct move back to θ0 is clear. Returns the order, or None when no order keeps every
    move clear.
    """
    n = len(pts)
    a, b = np.repeat(pts, n, axis=0), np.tile(pts, (n, 1))
    clear = move_ok(robot, model, p0, a, b, opt).reshape(n, n)
    has_via = ~np.isnan(vias[:, 0])

    def move_s(starts, ends):
        return move_durations_s(robot, opt.run, starts, ends, model, p0)

    leg = move_s(a, b).reshape(n, n)
    t0 = np.broadcast_to(theta0, pts.shape)
    first = np.where(has_via[:, None], vias, pts)  # through its via point, if it has one
    start = move_s(t0, first) + np.where(has_via, move_s(first, pts), 0.0)
    back = move_s(pts, t0)
    bad = 1e4
    # the way back to θ0 is the way there reversed, except from a point reached via
    home = np.ones(n, bool)
    home[has_via] = move_ok(robot, model, p0, pts[has_via], t0[has_via], opt)
    last_bad = np.where(has_via & (n > 1), bad, 0.0) + np.where(home, 0.0, bad)

    def total(path):
        t = start[path[0]] + back[path[-1]] + last_bad[path[-1]]
        for x, y in itertools.pairwise(path):
            t += leg[x, y] + bad * (not clear[x, y] or has_via[y])
        return t

    left = list(range(n))
    path: list[int] = []
    while left:
        i = min(left, key=lambda k: total([*path, k]) - (total(path) if path else 0))
        path.append(i)
        left.remove(i)
    improved = True
    while improved:
        improved = False
        for i, j in itertools.combinations(range(n), 2):
            cand = path[:i] + path[i : j + 1][::-1] + path[j + 1 :]
            if total(cand) < total(path) - 1e-9:
                path, improved = cand, True
    return np.array(path) if total(path) < bad else None


def robot_time(robot: Robot, plan: Plan, run: RunParameters = DEFAULT_RUN) -> float:
    """Estimate the run time (s) of a plan: :func:`~wirecal.solver.run_parameters.run_timeline`.

    Moves at the SPEED the wire allows, the settle rule and the readings per stop, the
    closing zero included: the time model the twin's clock and the simulated log's ``t_s`` share.
    """
    return run_timeline(robot, plan, run).total_s


def predicted_accuracy(
    robot: Robot,
    plan: Plan,
    sigma_mm: float = 0.01,
    prior: float = PlanOptions.prior,
    unplanned: tuple[str, ...] = (),
) -> dict[str, float]:
    """Return the mean tool-point error over the workspace (mm) of both estimators.

    Mean tool-point error over the workspace: for the joint estimate the Cramér–Rao bound
    (σ per reading plus the count's quantisation); for the stepwise estimate its linearised
    map A, noise A·C·Aᵀ plus the bias of parameters leaking into steps before their own,
    (A·J − I)·P·(A·J − I)ᵀ with true offsets of size ``prior`` (deg, mm). Parameters
    ``unplanned`` stay at their prior: each adds its own error of size ``prior`` to both.
    """
    model = robot.nominal
    q, step, _ = plan.all_points()
    names = plan.order
    errors = ErrorSet(names, robot.n_joints)
    J = errors.per_internal(sensitivity(model, q, plan.theta0_deg, names).psi)
    s2 = sigma_mm**2 + robot.encoder.mm_per_count**2 / 12
    C = noise_covariance(len(q), np.sqrt(s2), np.sqrt(s2 / len(plan.steps)))
    cov_joint = np.linalg.pinv(J.T @ np.linalg.solve(C, J))
    A = stepwise_map(J, step)
    E = A @ J - np.eye(len(names))
    P = np.diag(errors.to_internal(np.full(len(names), prior)) ** 2)
    ws = workspace(robot, 500)
    every = (*names, *unplanned)
    left = np.diag(
        ErrorSet(tuple(unplanned), robot.n_joints).to_internal(np.full(len(unplanned), prior)) ** 2
    )

    def with_unplanned(cov: np.ndarray) -> np.ndarray:
        out = np.zeros((len(every), len(every)))
        out[: len(names), : len(names)] = cov
        out[len(names) :, len(names) :] = left
        return out

    return {
        "joint": tool_error(model, every, with_unplanned(cov_joint), ws).mean_mm,
        "stepwise": tool_error(model, every, with_unplanned(A @ C @ A.T + E @ P @ E.T), ws).mean_mm,
    }
