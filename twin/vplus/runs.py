"""The V+ module's programs run in the twin, and V+'s twin adapter.

A measurement run (wc.mount answered 1, then wc.run), the validation programs (wc.vcfg,
wc.vpln) and :data:`ADAPTER` (:class:`~wirecal.twin.adapters.TwinAdapter`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, run_timeline
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    EncoderTruth,
    Unmodelled,
    reference_duration_s,
)
from wirecal.twin.adapters import AdapterCapabilities, TwinAdapter
from wirecal.twin.controller_run import ControllerRun, readings_for_lengths
from wirecal.twin.machine import Outcome
from wirecal.twin.vplus.controller import VplusController
from wirecal.twin.vplus.interp import Interpreter
from wirecal.twin.vplus.solver_run import controller_solve
from wirecal.twin.world import (
    DEFAULT_UNMODELLED,
    Faults,
    Plate,
    TwinRun,
    World,
    measurement_world,
    mount_then_run,
    payload_prompts,
    stop_reason,
)


def module_of(programs: dict[str, str]) -> tuple[str, str]:
    """Return the module's file name and text: the one program file of a V+ generation."""
    if len(programs) != 1:
        raise WirecalError(
            f"V+ programs: expected the one module file, got {sorted(programs) or 'none'}"
        )
    ((name, text),) = programs.items()
    return name, text


def run_measurement(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    disk: Path,
    programs: dict[str, str],
    *,
    log_file: str | None = None,
    seed: int = 0,
    noise_mm: float = 0.01,
    counter_start: float | None = None,
    faults: Faults | None = None,
    unmodelled: Unmodelled | None = None,
    proceed_on_pause: bool = False,
    encoder_truth: EncoderTruth = IDEAL_ENCODER,
) -> TwinRun:
    """Run a module's wc.mount (answered 1) and wc.run in the twin.

    The log is ``log_file`` on the disk (the name the module was generated with; by
    default the first file wc.run opens for writing). ``proceed_on_pause``: the operator
    continues after each PAUSE (having steadied the arm: a vibration stops), else the run
    ends there. The operator confirms every prompt of the reference step and of the payload
    step (1: mounting and removing the plan's mass, :meth:`World.handle_mass`), seating the
    wire tip as asked; the encoder is ``encoder_truth``.
    """
    world = measurement_world(
        robot,
        plan,
        truth,
        disk,
        robot.encoder.counter,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=counter_start,
        faults=faults,
        unmodelled=unmodelled,
        proceed_on_pause=proceed_on_pause,
        answers=["1"] * (1 + _reference_prompts(robot) + payload_prompts(plan)),
        encoder_truth=encoder_truth,
        run_s=run_timeline(robot, plan, DEFAULT_RUN).total_s + reference_duration_s(robot.encoder),
    )
    controller = VplusController(world)
    name, text = module_of(programs)
    interp = Interpreter(parse_module(text, name), controller)
    opened: list[int] = []

    def run() -> Outcome:
        opened.append(len(controller.written))
        return interp.execute("wc.run")

    mount, ran = mount_then_run(world, lambda: interp.execute("wc.mount"), run)
    written = controller.written[opened[0] :] if opened else []
    log = disk / log_file if log_file else (written[0] if written else disk / "no log")
    stopped = stop_reason(mount, ran)
    return TwinRun(log, stopped is None, stopped, world, mount, ran, controller)


def _reference_prompts(robot: Robot) -> int:
    """Return the prompts of wc.ref: each seating and the reattachment (none without)."""
    enc = robot.encoder
    return 0 if enc.reference_length_mm is None else 2 * enc.reference_repeats + 1


@dataclass
class ValidationRun:
    """Both validation programs' outcomes in the twin, their logs and the controller."""

    configuration: Outcome
    plane: Outcome
    configuration_log: Path
    plane_log: Path
    controller: VplusController


def run_validation(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    setup,
    disk: Path,
    text: str,
    *,
    controller: dict[str, float],
    run: int,
    seed: int = 0,
    unmodelled: Unmodelled | None = DEFAULT_UNMODELLED,
    noise_mm: float = 0.01,
) -> ValidationRun:
    """Run both validation programs (wc.vcfg, wc.vpln) in the twin.

    ``controller`` is the model the controller believes: {} before calibration, the
    identified offsets after.
    """
    disk.mkdir(parents=True, exist_ok=True)
    world = World(
        robot,
        truth,
        plan.theta0_deg,
        disk,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=robot.encoder.counter.random_start(
            np.random.default_rng([seed, 5]), within=0.5
        ),
        answers=["1", str(run), "1", str(run)],
        plate=Plate(tuple(setup.plate_origin_mm)),
        probe_mm=tuple(setup.probe_mm),
        encoder_point_mm=tuple(setup.encoder_mm),
        unmodelled=unmodelled,
    )
    ctl = VplusController(world, controller, probe_signal=setup.signal)
    interp = Interpreter(parse_module(text, "WIRECAL.V2"), ctl)
    cfg = interp.execute("wc.vcfg")
    pln = interp.execute("wc.vpln")
    return ValidationRun(cfg, pln, disk / f"WCVCFG{run}.CSV", disk / f"WCVPLN{run}.CSV", ctl)


class VplusAdapter(TwinAdapter):
    """V+'s twin adapter: the module's programs on the twin's world."""

    key = "vplus"
    capabilities = AdapterCapabilities(
        encoder_truth=True, controller_runs=True, paper_validation=True
    )

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
        encoder_truth: EncoderTruth = IDEAL_ENCODER,
    ) -> TwinRun:
        """Run wc.mount and wc.run (:func:`run_measurement`) on the encoder ``encoder_truth``."""
        return run_measurement(
            robot,
            plan,
            truth,
            folder,
            programs,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=counter_start,
            faults=faults,
            unmodelled=unmodelled,
            encoder_truth=encoder_truth,
        )

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        lengths_mm: np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Run wc.solve (stepwise) and wc.solve2 (joint) on the plan points' wire lengths.

        ``lengths_mm``: mm from the zero reading at θ0, plan order; the readings as wc.run
        would keep them (:func:`~wirecal.twin.controller_run.readings_for_lengths`, on the
        robot file's counter).
        """
        _, text = module_of(programs)
        readings = readings_for_lengths(robot, plan, lengths_mm, robot.encoder.counter)
        return {
            method: controller_solve(
                robot, plan, readings, folder / method, polish=polish, text=text
            ).offsets
            for method, polish in SOLVERS
        }

    def controller_runs(
        self,
        robot: Robot,
        plan: Plan,
        measured: Measurements,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, ControllerRun]:
        """Run wc.solve (stepwise) and wc.solve2 (joint) on a checked log's own readings.

        Each run with its operation counts (``wirecal solve --method controller``).
        """
        _, text = module_of(programs)
        return {
            method: controller_solve(
                robot,
                plan,
                measured.log.readings,
                folder / method,
                polish=polish,
                text=text,
                closed=measured.closed,
            )
            for method, polish in SOLVERS
        }

    def paper_validation(
        self,
        robot: Robot,
        plan: Plan,
        truth: dict[str, float],
        setup,
        folder: Path,
        programs: dict[str, str],
        *,
        controller: dict[str, float],
        run: int,
        seed: int = 0,
    ) -> ValidationRun:
        """Run the paper's two validation procedures, wc.vcfg and wc.vpln (§3.6.1, §3.6.2).

        The module generated with the validation ``setup`` (:func:`run_validation`);
        ``controller``: the offsets the controller believes ({} before calibration).
        """
        _, text = module_of(programs)
        return run_validation(
            robot, plan, truth, setup, folder, text, controller=controller, run=run, seed=seed
        )


SOLVERS = (("stepwise", False), ("joint", True))
"""The module's controller solvers: method → polish (wc.solve, wc.solve2)."""

ADAPTER = VplusAdapter()
