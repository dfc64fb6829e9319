"""A measurement log's records as the solver takes them: its readings and header fields.

The file format (the CSV the controller program writes, its versions and its strict reader)
is :mod:`~wirecal.formats.log`, which returns these; the solver checks them against
the plan (:mod:`~wirecal.solver.log.measurements`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REFERENCE_STEP = 0
"""The step number of the reference rows (before the plan's step 1)."""


@dataclass(frozen=True)
class Reading:
    """One data line of a log: a zero reading or a plan point's reading."""

    kind: str
    step: int
    index: int
    joints_deg: np.ndarray
    counts: float
    samples: int
    spread: float
    line: int
    t_s: float | None = None  # the controller's timer at the sampling (version 2 on)
    settle_s: float | None = None  # the wait before the sampling (version 2 on)


@dataclass(frozen=True)
class Log:
    """A log as written: header fields and readings, checked for format only.

    ``version``: the log format's (1: no times; 2: ``t_s``, ``settle_s``, reference rows).
    """

    source: str
    robot: str
    plan: str
    mm_per_count: float
    readings: tuple[Reading, ...]
    sha256: str
    version: int
    notes: tuple[str, ...] = ()
    payload_kg: float | None = None  # the payload step's mass, as the log's header says
