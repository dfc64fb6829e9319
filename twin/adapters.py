"""The twin adapter of each controller language: run its programs in the twin.

Each ``wirecal.twin.<key>`` package defines ``ADAPTER`` (a :class:`TwinAdapter`); the key
is the robot file's ``[controller] language``. What an adapter offers beyond running the
programs and the controller solver it declares (:class:`AdapterCapabilities`): nobody
probes it.
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled
from wirecal.solver.validation.design import Setup
from wirecal.twin.controller_run import ControllerRun
from wirecal.twin.world import Faults, TwinRun


@dataclass(frozen=True)
class AdapterCapabilities:
    """What a twin adapter offers beyond running the programs and the controller solver."""

    encoder_truth: bool = False  # measure() takes encoder_truth (the true scale, temperature)
    controller_runs: bool = False  # controller_runs(): its solver on a checked log's readings
    paper_validation: bool = False  # paper_validation(): the paper's validation programs


class TwinAdapter(ABC):
    """Run a language's generated programs in the twin; its capabilities declared."""

    key: ClassVar[str]
    capabilities: ClassVar[AdapterCapabilities] = AdapterCapabilities()

    @abstractmethod
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

    @abstractmethod
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

    def controller_runs(
        self,
        robot: Robot,
        plan: Plan,
        measured: Measurements,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, ControllerRun]:
        """Run the controller solver on a checked log's own readings: method → its run.

        Offered where ``capabilities.controller_runs``; elsewhere a WirecalError.
        """
        raise WirecalError(
            f"the {self.key} twin does not run its controller solver on a log's readings"
        )

    def paper_validation(
        self,
        robot: Robot,
        plan: Plan,
        truth: dict[str, float],
        setup: Setup,
        folder: Path,
        programs: dict[str, str],
        *,
        controller: dict[str, float],
        run: int,
        seed: int = 0,
    ) -> Any:
        """Run the paper's validation programs (§3.6); offered where ``capabilities`` says."""
        raise WirecalError(f"the {self.key} twin does not run the paper's validation programs")


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
