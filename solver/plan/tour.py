"""The visiting order of a step's points and the robot time a point adds.

Per step, the visiting order from θ0 and back is the shortest-time tour (nearest
neighbour, then 2-opt) over clear moves (:func:`tour`); the time is the run's time model
(:mod:`~wirecal.solver.run_parameters`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from wirecal.solver.plan.moves import move_ok
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    MOVE_OVERHEAD_S,
    READING_INTERVAL_S,
    RunParameters,
    cruise_per_pct,
    move_durations_s,
    move_profiles,
    move_speeds_pct,
    settle_time_s,
)


def visit_s(
    robot: Robot, run: RunParameters, p0: np.ndarray, start_deg: np.ndarray, ends_deg: np.ndarray
) -> np.ndarray:
    """Return the robot time (s) a point adds when visited from ``start_deg``.

    The move at the SPEED the wire allows, the predicted settle and the readings (the
    run's time model). ``start_deg``: one configuration (n,) or one per point (M, n).
    """
    if not len(ends_deg):
        return np.zeros(0)
    starts = np.broadcast_to(np.asarray(start_deg, dtype=float), np.shape(ends_deg))
    moves = move_profiles(robot, robot.nominal, p0, starts, ends_deg)
    pct = move_speeds_pct(robot, moves, run.speed_pct)
    settle = settle_time_s(moves.vibration_mm(pct), robot.encoder.mm_per_count, run)
    return moves.duration_s(pct) + settle + READING_INTERVAL_S * (run.readings - 1)


def visit_floor_s(
    robot: Robot, run: RunParameters, start_deg: np.ndarray, ends_deg: np.ndarray
) -> np.ndarray:
    """Return a lower bound (s) of :func:`visit_s`, from the joint motions alone.

    The move at ``run.speed_pct`` (the wire may only ask for less), the settle of a stop
    without vibration and the readings: each term at most its value in :func:`visit_s`.
    """
    dq = np.asarray(ends_deg, dtype=float) - np.asarray(start_deg, dtype=float)
    with np.errstate(divide="ignore"):
        move = 1.0 / (cruise_per_pct(robot, dq) * run.speed_pct) + MOVE_OVERHEAD_S
    settle = settle_time_s(np.zeros(len(dq)), robot.encoder.mm_per_count, run)
    return move + settle + READING_INTERVAL_S * (run.readings - 1)


def tour(
    robot: Robot,
    model,
    p0,
    theta0,
    pts,
    vias,
    opt: PlanOptions,
    clear: np.ndarray | None = None,
) -> np.ndarray | None:
    """Return the visiting order from θ0 and back, or None.

    The visiting order from θ0 and back (nearest neighbour, improved by 2-opt) over
    moves that keep the arm and the wire clear (``move_ok``; ``clear``: whether each move
    between the points is, (n, n), when the caller knows); a point reached through a via
    point can only come first, and last only when it is the step's only point and its
    direct move back to θ0 is clear. Returns the order, or None when no order keeps every
    move clear.
    """
    n = len(pts)
    a, b = np.repeat(pts, n, axis=0), np.tile(pts, (n, 1))
    has_via = ~np.isnan(vias[:, 0])
    t0 = np.broadcast_to(theta0, pts.shape)
    # the way back to θ0 is the way there reversed, except from a point reached via
    home = np.ones(n, bool)
    if clear is None:
        ok = move_ok(
            robot, model, p0, np.vstack([a, pts[has_via]]), np.vstack([b, t0[has_via]]), opt
        )
        clear, home[has_via] = ok[: n * n].reshape(n, n), ok[n * n :]
    elif has_via.any():
        home[has_via] = move_ok(robot, model, p0, pts[has_via], t0[has_via], opt)
    first = np.where(has_via[:, None], vias, pts)  # through its via point, if it has one
    # the legs between points, from θ0 (to the via point, on to the point) and back: one call
    times = move_durations_s(
        robot, opt.run, np.vstack([a, t0, first, pts]), np.vstack([b, first, pts, t0]), model, p0
    )
    leg = times[: n * n].reshape(n, n)
    to_first, on, back = times[n * n :].reshape(3, n)
    bad = 1e4
    last_bad = np.where(has_via & (n > 1), bad, 0.0) + np.where(home, 0.0, bad)
    # Python floats in lists (the same sums in the same order): the 2-opt below sums
    # thousands of short paths
    start = (to_first + np.where(has_via, on, 0.0)).tolist()
    back_, last_ = back.tolist(), last_bad.tolist()
    legs = (leg + bad * (~clear | has_via[None, :])).tolist()

    def total(path):
        t = start[path[0]] + back_[path[-1]] + last_[path[-1]]
        for x, y in itertools.pairwise(path):
            t += legs[x][y]
        return t

    path = _shortest_path(n, total)
    return np.array(path) if total(path) < bad else None


def _shortest_path(n: int, total: Callable[[list[int]], float]) -> list[int]:
    """Return an order of ``n`` points of low ``total``: nearest neighbour, then 2-opt."""
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
    return path
