"""The twin adapter of each controller language: run its generated programs in the twin.

Interface only on this branch: each ``wirecal.twin.<key>`` package defines ``ADAPTER`` (a
:class:`TwinAdapter`, written with the split of the cell into the language-free world and
per-language controllers); :func:`adapter` finds it by the robot file's ``[controller]
language``, so adding a language adds ``twin/<key>/`` and never edits a list.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled

if TYPE_CHECKING:  # the cell and the readings only when an adapter runs
    import numpy as np

    from wirecal.twin.cell import Faults


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
    ) -> Any:
        """Run the mounting and measurement programs on a twin robot with offsets ``truth``.

        Returns the run (``TwinRun``: ``log`` the PC reads, ``complete``, ``stopped``).
        """
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


def adapter(key: str) -> TwinAdapter:
    """Return the twin adapter of language ``key`` (``ADAPTER`` in ``wirecal.twin.<key>``)."""
    try:
        found: TwinAdapter = importlib.import_module(f"wirecal.twin.{key}").ADAPTER
    except (ImportError, AttributeError):
        raise WirecalError(f"no twin adapter for controller language {key!r}") from None
    return found
