"""The planner's moves: whether a joint-interpolated move keeps the arm and the wire clear.

A move is sampled every few degrees of its largest joint motion (:func:`move_samples`,
which the wire-range and cell checks of ``wirecal gen`` share) and is safe when the arm
stays out of itself and the cell, the wire keeps ``clearance_mm`` from the links and stays
within the encoder's range, and joint 6 turns at most 180° (:func:`move_ok`). A
candidate whose direct move from θ0 would sweep the wire through a link or wrap it around
the flange is kept if a via point makes the move clear (:func:`reach_ok`).
"""

from __future__ import annotations

import itertools

import numpy as np

from wirecal.solver.cell.clearance import wire_clearance, wire_trim_mm
from wirecal.solver.cell.model import SURE_GAP_MM
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import wire_path
from wirecal.solver.kinematics import frames, tool_position
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot


def move_samples(
    a: np.ndarray, b: np.ndarray, step_deg: float = 2.0
) -> tuple[np.ndarray, np.ndarray]:
    """Return the configurations along moves a → b and each move's first sample.

    Configurations (deg) along the joint-interpolated moves a → b (rows broadcast),
    every ``step_deg`` of the largest joint motion, b included and a not; and the index of
    each move's first sample (for ``np.minimum.reduceat`` and the like).
    """
    a, b = np.atleast_2d(a), np.atleast_2d(b)
    if a.shape != b.shape:
        a, b = np.broadcast_arrays(a, b)
    d = b - a
    count = np.maximum(1, np.ceil(np.abs(d).max(axis=1) / step_deg)).astype(int)
    first = count.cumsum() - count
    if len(count) == 1:  # one move (a twin's, a check's): its rows need no repeating
        return a + (np.arange(1, count[0] + 1) / count[0])[:, None] * d, first
    t = (np.arange(count.sum()) - (first - 1).repeat(count)) / count.repeat(count)
    return a.repeat(count, axis=0) + t[:, None] * d.repeat(count, axis=0), first


CHUNK_SAMPLES = 1536
"""Configurations evaluated per batch along moves: the batch's arrays (a few capsules ×
this many configurations) stay in the processor's cache, which makes a sweep about 1.5
times faster than batches of 16,384 (and far faster than one batch of millions); the
capsule pairs' arrays (3 × 11 pairs × this many, 0.4 MB each) fit a 2 MB cache beside
the others, which makes the planner's sweeps 10–14 % faster than batches of 4,096 (the
same gaps: each configuration's is its own)."""


def _kept(count: np.ndarray, every: int, rest: bool) -> np.ndarray:
    """Return how many of each move's ``count`` samples a pass keeps (:func:`_keep`)."""
    thinned = count // every + (count % every != 0)
    return count - thinned if rest else thinned


def _keep(first: np.ndarray, n: int, every: int, rest: bool) -> np.ndarray:
    """Return which of ``n`` samples (moves starting at ``first``) a pass evaluates.

    Every ``every``-th sample of each move and its end; with ``rest``, the others.
    """
    k = np.arange(n) - np.repeat(first, np.diff(np.r_[first, n]))
    last = np.zeros(n, bool)
    last[np.r_[first[1:], n] - 1] = True
    return ((k % every == every - 1) | last) != rest


def move_clearance(
    robot: Robot,
    model,
    p0: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    step_deg: float = 2.0,
    every: int = 1,
    longest_mm: float = np.inf,
    rest: bool = False,
) -> np.ndarray:
    """Return the smallest wire gap (mm) to the links along moves a → b.

    The smallest wire gap (mm) to the links along the joint-interpolated moves a → b
    (deg, rows broadcast), sampled every ``step_deg`` of the largest joint motion
    (:func:`move_samples`), in batches of about ``CHUNK_SAMPLES`` configurations. With
    ``every`` > 1 only every ``every``-th of those samples and each move's end are
    evaluated: a subset, so a gap found there is a gap of the full sampling too; with
    ``rest`` the samples that subset leaves out instead (+inf for a move with none), so
    the two passes together evaluate each sample once. A sample where the modelled wire
    is longer than ``longest_mm`` counts as no gap at all (−inf): the encoder's range,
    checked along the move as ``wirecal gen`` checks it; so does a sample where the arm
    meets itself or the cell (:mod:`~wirecal.solver.cell.model`).
    """
    radii = robot.link_radius_mm
    if radii is None:
        raise WirecalError(f"{robot.source}: the wire clearance needs the link radii")
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    count = np.maximum(1, np.ceil(np.max(np.abs(b - a), axis=1) / step_deg)).astype(int)
    kept = _kept(count, every, rest) if every > 1 else count
    # batch k holds the moves whose evaluated samples start in [k·CHUNK, (k+1)·CHUNK)
    batch = (np.cumsum(kept) - kept) // CHUNK_SAMPLES
    edges = np.searchsorted(batch, np.arange(batch[-1] + 2)) if len(a) else [0]
    out = np.full(len(a), np.inf)
    for lo, hi in itertools.pairwise(edges):
        q, first = move_samples(a[lo:hi], b[lo:hi], step_deg)
        if every > 1:
            keep = _keep(first, len(q), every, rest)
            first = (np.cumsum(keep) - keep)[first]
            q = q[keep]
        some = kept[lo:hi] > 0
        if some.any():
            gap = _sample_gaps(robot, model, p0, q, radii, longest_mm)
            out[lo:hi][some] = np.minimum.reduceat(gap, first[some])
    return out


def _sample_gaps(
    robot: Robot, model, p0: np.ndarray, q: np.ndarray, radii: np.ndarray, longest_mm: float
) -> np.ndarray:
    """Return each configuration's wire gap (mm) to the links (``radii``); −inf where unsafe.

    Unsafe: the arm in itself or the cell, or the modelled wire longer than
    ``longest_mm`` (see :func:`move_clearance`).
    """
    q_rad = np.radians(q)
    f = frames(model, q_rad)  # one evaluation of the chain for both checks
    gap = wire_clearance(model, q_rad, p0, radii, wire_trim_mm(robot), f)
    collides = robot.cell_gaps(q, p0, model, f, SURE_GAP_MM).smallest() < 0
    gap = np.where(collides, -np.inf, gap)
    if np.isfinite(longest_mm):
        d = wire_path(model.pulley, tool_position(model, q_rad, f) - p0)[0]
        gap = np.where(np.nan_to_num(d) > longest_mm, -np.inf, gap)
    return gap


def move_ok(
    robot: Robot,
    model,
    p0,
    a,
    b,
    opt: PlanOptions,
    step_deg: float = 2.0,
    path: np.ndarray | None = None,
) -> np.ndarray:
    """Return which moves a → b are safe for the arm and the wire.

    Moves a → b that keep the arm out of itself and the cell, the wire clear of the
    links, within the encoder's range less ``range_margin_mm`` all along, and do not turn
    joint 6 by more than 180° (which would wrap the wire around the flange). ``path``:
    per move the path it is a leg of (default each its own); a move is safe only where
    every leg of its path is, and a leg found unsafe spares its path's others the passes
    left (the same answers: a path is safe when all its samples are).
    """
    a, b = np.broadcast_arrays(np.atleast_2d(a), np.atleast_2d(b))
    ok = _whole_paths(np.abs(b[:, -1] - a[:, -1]) <= 180, path)
    longest = robot.encoder.range_mm - opt.range_margin_mm
    samples = np.sum(np.ceil(np.max(np.abs(b - a), axis=1) / step_deg))
    # a quick pass over every QUICK_EVERY-th sample rejects most blocked moves (a gap
    # there is a gap of the full sampling); the moves it passes then get the other
    # samples. A few moves are swept in one pass: a pass's fixed cost outweighs what the
    # quick one saves
    quick = ((QUICK_EVERY, False), (QUICK_EVERY, True))
    passes = quick if samples > ONE_PASS_SAMPLES else ((1, False),)
    for every, rest in passes:
        idx = np.flatnonzero(ok)
        gap = move_clearance(robot, model, p0, a[idx], b[idx], step_deg, every, longest, rest)
        ok[idx] = gap >= opt.clearance_mm
        ok = _whole_paths(ok, path)
    return ok


def _whole_paths(ok: np.ndarray, path: np.ndarray | None) -> np.ndarray:
    """Return ``ok`` where every move of the same ``path`` is ok, False elsewhere."""
    if path is None:
        return ok
    blocked = np.zeros(len(ok), bool)
    blocked[path[~ok]] = True
    return ok & ~blocked[path]


ONE_PASS_SAMPLES = 1024
"""Moves with at most this many samples in all are swept in one pass (:func:`move_ok`)."""


QUICK_EVERY = 8
"""The quick pass of :func:`move_ok` samples every this many and each move's end. Of the
samples its two passes evaluate, 9 % fewer for the UR5e's plan than every 4th (a blocked
move is seldom clear at its every 8th samples but not at its every 4th), 3 % for the
Viper's; the planner's sweeps 7 % and 1 % faster (every 16th, then the rest of every
4th, then the others: 17 % and 6 % fewer samples, but as fast for the UR5e and slower
for the Viper, a pass's fixed cost)."""


def reach_ok(
    robot: Robot, model, p0, theta0, q, via, opt: PlanOptions, step_deg: float = 2.0
) -> np.ndarray:
    """Return whether each point q is reached from θ0 with the wire clear.

    Directly, or through its via point (NaN row: none): :func:`reach_and_move_ok`.
    """
    return reach_and_move_ok(robot, model, p0, theta0, q, via, q[:0], q[:0], opt, step_deg)[0]


def reach_and_move_ok(
    robot: Robot, model, p0, theta0, q, via, a, b, opt: PlanOptions, step_deg: float = 2.0
) -> tuple[np.ndarray, np.ndarray]:
    """Return whether each point q is reached from θ0, and whether each move a → b is safe.

    Reached directly, or through its via point (NaN row: none); the moves from θ0 to the
    points and to the via points, the second legs from the via points and the moves
    a → b are swept together (one sweep's fixed cost, and a second leg blocked on the
    quick pass spares its first leg the other samples: :func:`move_ok`'s ``path``).
    """
    direct = np.isnan(via[:, 0])
    viaed = np.flatnonzero(~direct)
    first = np.where(direct[:, None], q, via)
    starts = np.vstack([np.broadcast_to(theta0, first.shape), via[viaed], a])
    ends = np.vstack([first, q[viaed], b])
    path = np.r_[np.arange(len(q)), viaed, len(q) + np.arange(len(a))]
    clear = move_ok(robot, model, p0, starts, ends, opt, step_deg, path)
    return clear[: len(q)], clear[len(q) + len(viaed) :]
