"""A generated controller solver run in the twin, whatever the language.

Its result, and the readings it is given when only wire lengths are (the adapters'
``controller_solve``).
"""

from __future__ import annotations

from collections import Counter as Tally
from dataclasses import dataclass

import numpy as np

from wirecal.formats.log import Reading
from wirecal.solver.counter import Counter
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot

BELOW_WRAP_COUNTS = 20_000
"""The zero readings' count below the counter's wrap: the points' counts wrap past it."""


@dataclass(frozen=True)
class ControllerRun:
    """One run of the generated controller solver in the twin."""

    program: str  # "wc.solve", "wc.solve2" or "wc_solve"
    offsets: dict[str, float]  # identified offsets (deg, mm), read from its result
    operations: Tally[str]  # arithmetic executed: add (+ −), mul, div, sqrt
    console: tuple[str, ...]
    syncs: int = 0  # URScript: sync() calls (one 2 ms frame each)
    most_between_syncs: int = 0  # URScript: most operations between two sync() calls

    @property
    def total_operations(self) -> int:
        """Return the number of operations counted, all kinds together."""
        return sum(self.operations.values())


def readings_for_lengths(
    robot: Robot, plan: Plan, lengths_mm: np.ndarray, counter: Counter
) -> tuple[Reading, ...]:
    """Return the readings a run logs for wire lengths ``lengths_mm``.

    ``lengths_mm``: each plan point's wire length from the zero reading at θ0 (mm, plan
    order). Every step's zero reading (and the closing one) at θ0 on a count
    :data:`BELOW_WRAP_COUNTS` below ``counter``'s wrap; the points at their plan joints,
    their counts as ``counter`` holds them (so they wrap).
    """
    q, step_no, index_no = plan.all_points()
    base = float(counter.half - BELOW_WRAP_COUNTS)
    counts = counter.wrap(base + np.asarray(lengths_mm, float) / robot.encoder.mm_per_count)

    def zero(step: int) -> Reading:
        return Reading("zero", step, 0, plan.theta0_deg, base, 1, 0.0, 0)

    points = [
        Reading("point", int(s), int(i), joints, float(c), 1, 0.0, 0)
        for s, i, joints, c in zip(step_no, index_no, q, counts, strict=True)
    ]
    steps = range(1, len(plan.steps) + 1)
    by_step = [r for s in steps for r in (zero(s), *(p for p in points if p.step == s))]
    return (*by_step, zero(len(plan.steps) + 1))
