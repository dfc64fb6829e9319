"""The RAPID twin adapter (registry_api ``TwinAdapter``): run WIRECAL.mod in the twin.

:meth:`RapidAdapter.measure` runs ``wc_mount`` then ``wc_run`` of the generated module on
:class:`~wirecal.twin.rapid.controller.IrcController` over the twin's
:class:`~wirecal.twin.world.World`; the log the PC reads is the file wc_run wrote in
``HOME:``. :meth:`RapidAdapter.controller_solve` runs ``wc_solve`` alone on given wire
lengths (the readings as wc_meas would have kept them:
:func:`~wirecal.twin.controller_run.readings_for_lengths`),
:meth:`RapidAdapter.controller_runs` on a checked log's readings
(:mod:`wirecal.twin.rapid.solver_run`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wirecal.lang.rapid.module import LOG_FILE, MODULE_FILE, signal_name
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled
from wirecal.twin.adapters import AdapterCapabilities, TwinAdapter, program_text
from wirecal.twin.controller_run import ControllerRun, readings_for_lengths
from wirecal.twin.rapid.controller import IrcController
from wirecal.twin.rapid.interp import run_module
from wirecal.twin.rapid.solver_run import controller_solve
from wirecal.twin.world import (
    Faults,
    TwinRun,
    measurement_world,
    mount_then_run,
    payload_prompts,
    stop_reason,
)


def module_of(programs: dict[str, str]) -> str:
    """Return the module's text: the one file of a RAPID generation (WirecalError if absent)."""
    return program_text(programs, MODULE_FILE, "RAPID")


class RapidAdapter(TwinAdapter):
    """The RAPID twin adapter (module docstring)."""

    key = "rapid"
    capabilities = AdapterCapabilities(controller_runs=True)

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
        """Run wc_mount, then wc_run, on a true robot with ``truth`` offsets.

        ``counter_start``: the group input's count at zero wire length (default: drawn
        over the 32-bit counter's range); the wire's speed limits are enforced. The operator
        answers 1 to wc_mount and to the payload step's two prompts (mounting and removing
        the plan's mass, :meth:`~wirecal.twin.world.World.handle_mass`).
        """
        text = module_of(programs)
        world = measurement_world(
            robot,
            plan,
            truth,
            folder,
            robot.encoder.counter,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=counter_start,
            faults=faults,
            unmodelled=unmodelled,
            answers=["1"] * (1 + payload_prompts(plan)),
        )
        controller = IrcController(world, signal_name(robot))
        mount, run = mount_then_run(
            world,
            lambda: run_module(text, MODULE_FILE, controller, entry="wc_mount"),
            lambda: run_module(text, MODULE_FILE, controller, entry="wc_run"),
        )
        stopped = stop_reason(mount, run)
        return TwinRun(folder / LOG_FILE, stopped is None, stopped, world, mount, run, controller)

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        lengths_mm: np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Run wc_solve (step by step: RAPID has no polish) on the plan points' wire lengths.

        ``lengths_mm``: mm from the zero reading at θ0, plan order; the readings as wc_run
        would keep them on the signed 32-bit count
        (:func:`~wirecal.twin.controller_run.readings_for_lengths`).
        """
        text = module_of(programs)
        readings = readings_for_lengths(robot, plan, lengths_mm, robot.encoder.counter)
        run = controller_solve(robot, plan, readings, folder, text)
        return {"stepwise": run.offsets}

    def controller_runs(
        self,
        robot: Robot,
        plan: Plan,
        measured: Measurements,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, ControllerRun]:
        """Run wc_solve on a checked log's own readings, with its operation counts.

        ``wirecal solve --method controller``; step by step only (RAPID has no polish).
        """
        text = module_of(programs)
        return {
            "stepwise": controller_solve(
                robot, plan, measured.log.readings, folder / "stepwise", text
            )
        }


ADAPTER = RapidAdapter()
