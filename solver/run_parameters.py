"""How a calibration run moves and reads, in one place.

How a calibration run moves and reads, in one place: the program's speed and
acceleration, the settle time and the counter readings per stop (written into the
generated programs), and the time model of a run that the planner's robot-time estimate
and the digital twin's clock share.

A move takes the slowest joint's travel at the program speed (each joint's maximum speed
from the robot file × ``speed_pct`` %) plus ``MOVE_OVERHEAD_S`` for accelerating,
decelerating and the controller's motion start; a stop takes ``settle_s`` plus one
``READING_INTERVAL_S`` per counter reading. :func:`run_timeline` lays a plan's run out
in time: the ``t_s`` of each reading of the log.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.plan import Plan

MOVE_OVERHEAD_S = 0.5
"""Time added to every move for its acceleration and deceleration ramps and the start of
the motion (an estimate, not measured on a controller: at ACCEL 20 % the ramps of a joint
move take a few tenths of a second)."""

READING_INTERVAL_S = 0.02
"""Wait between two counter readings of one stop (the generated program's
``WAIT.EVENT , 0.02`` in templates/vplus/measure.v2.j2)."""


def move_time_s(
    joint_speed_deg_s: np.ndarray, a_deg: np.ndarray, b_deg: np.ndarray, speed_pct: float
) -> float:
    """Return the duration (s) of a joint-interpolated move.

    Duration (s) of a joint-interpolated move from ``a_deg`` to ``b_deg`` at
    ``speed_pct`` % of the joints' maximum speeds, overhead included.
    """
    rate = joint_speed_deg_s * speed_pct / 100
    return float(np.max(np.abs(np.asarray(b_deg) - np.asarray(a_deg)) / rate)) + MOVE_OVERHEAD_S


@dataclass(frozen=True)
class RunParameters:
    """The run's motion and reading parameters (``wirecal gen`` options)."""

    speed_pct: float = 20.0  # % of full speed (SPEED … ALWAYS)
    accel_pct: float = 20.0  # % of full acceleration and deceleration (ACCEL)
    settle_s: float = 3.0  # wait after each stop before reading (paper: 3 s)
    readings: int = 10  # counter readings averaged per point

    def move_s(self, joint_speed_deg_s: np.ndarray, a_deg: np.ndarray, b_deg: np.ndarray) -> float:
        """Duration (s) of a move at the program speed (:func:`move_time_s`)."""
        return move_time_s(joint_speed_deg_s, a_deg, b_deg, self.speed_pct)

    @property
    def stop_s(self) -> float:
        """Duration (s) of a stop: the settle time and the readings."""
        return self.settle_s + READING_INTERVAL_S * self.readings

    def problems(self) -> list[str]:
        """Return what is out of range, as ``wirecal gen``'s options name it."""
        out = []
        if not 0 < self.speed_pct <= 100:
            out.append(f"--speed {self.speed_pct:g}: give a percentage in (0, 100]")
        if not 0 < self.accel_pct <= 100:
            out.append(f"--accel {self.accel_pct:g}: give a percentage in (0, 100]")
        if not 0 <= self.settle_s <= 60:
            out.append(f"--settle-s {self.settle_s:g}: give 0–60 s")
        if not 1 <= self.readings <= 1000:
            out.append(f"--samples {self.readings}: give 1–1000")
        return out


DEFAULT_RUN = RunParameters()
"""The defaults of ``wirecal gen`` and of the planner's robot-time estimate."""


@dataclass(frozen=True)
class Timeline:
    """When a run of a plan reads: its time model, as the log's ``t_s`` column."""

    reading_s: np.ndarray  # s from the start of the run to the sampling of each reading
    total_s: float  # the whole run, to the end of the closing zero reading


def run_timeline(joint_speed_deg_s: np.ndarray, plan: Plan, run: RunParameters) -> Timeline:
    """Lay out a run of ``plan`` in time, in the generated program's order.

    Each step moves to θ0 (zero reading), through its via points (blended, no stop) and to
    each point (settle, read); last a move to θ0 for the closing zero reading. The run
    starts at θ0 with the timer at zero; a reading's time is when its sampling begins.
    """
    here = np.asarray(plan.theta0_deg, dtype=float)
    t = 0.0
    times: list[float] = []

    def visit(target: np.ndarray, reads: bool) -> None:
        nonlocal here, t
        t += run.move_s(joint_speed_deg_s, here, target)
        here = np.asarray(target, dtype=float)
        if reads:
            t += run.settle_s
            times.append(t)
            t += READING_INTERVAL_S * run.readings

    for step in plan.steps:
        visit(plan.theta0_deg, True)
        for via in step.via_deg:
            visit(via, False)
        for point in step.points_deg:
            visit(point, True)
    visit(plan.theta0_deg, True)
    return Timeline(np.array(times), t)
