"""The twin adapter of each controller language: run its programs in the twin.

Each ``wirecal.twin.<key>`` package defines ``ADAPTER`` (a :class:`TwinAdapter`); the key
is the robot file's ``[controller] language``.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Protocol

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled
from wirecal.twin.world import Faults, TwinRun


class TwinAdapter(Protocol):
    """Run a language's generated programs in the twin."""

    key: str

    def measure(
        self,
        robot: Robot,
        plan: Plan,
        truth: dict[str, float],
        folder: Path,
        programs: dict[str, str],
        *,
        seed: int = 0,
        noise_mm: float = 0.01,
        counter_start: float | None = None,
        faults: Faults | None = None,
        unmodelled: Unmodelled | None = None,
    ) -> TwinRun:
        """Run the mounting and measurement programs on a twin robot with offsets ``truth``."""
        ...

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        lengths_mm: np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Run the controller solver on wire lengths: method → offsets by name.

        ``lengths_mm``: each plan point's wire length from the zero reading at θ0 (mm,
        plan order), the points at their plan joints.
        """
        ...


def program_text(programs: dict[str, str], name: str, language: str) -> str:
    """Return the program file ``name`` of a generation; a WirecalError naming what came."""
    if name not in programs:
        raise WirecalError(f"{language} programs: {name} is missing (got {sorted(programs)})")
    return programs[name]


def adapter(key: str) -> TwinAdapter:
    """Return the twin adapter of language ``key`` (``ADAPTER`` in ``wirecal.twin.<key>``)."""
    try:
        module = importlib.import_module(f"wirecal.twin.{key}")
        return module.ADAPTER
    except (ImportError, AttributeError):
        raise WirecalError(f"no twin adapter for controller language {key!r}") from None
