"""The planner's settings (:class:`PlanOptions`) and its progress callback."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    RunParameters,
)

Method = Literal["joint", "stepwise"]
"""The estimator a plan's points are chosen for."""

Progress = Callable[[float], None]
"""Called with the fraction of the work done (0…1) as the planner advances."""


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


DEFAULT_OPTIONS = PlanOptions()
"""The planner's default settings (``wirecal plan`` without options)."""


def part_progress(progress: Progress | None, k: int, parts: int) -> Progress | None:
    """Return the progress callback of part ``k`` of ``parts`` (its fraction → the whole)."""
    if progress is None:
        return None
    whole = progress
    return lambda fraction: whole((k + fraction) / parts)
