"""The RAPID twin adapter (registry_api ``TwinAdapter``): run WIRECAL.mod in the twin.

:meth:`RapidAdapter.measure` runs ``wc_mount`` then ``wc_run`` of the generated module on
:class:`~wirecal.twin.rapid.controller.IrcController` over the twin's cell; the log the PC
reads is the file wc_run wrote in ``HOME:``. :meth:`RapidAdapter.controller_solve` runs
``wc_solve`` alone on given wire lengths: the twin appends a routine ``wc_twin_load`` to
the module (the readings as wc_meas would have kept them, zero readings at θ0 on a counter
about to wrap, the points at their plan joints) that opens a result file, calls wc_solve
and closes it; the result is read from that file's ``# controller:`` lines.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.lang.rapid.module import (
    LOG_DIR,
    LOG_FILE,
    MODULE_FILE,
    dnum_literal,
    num_literal,
    signal_name,
)
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.controller_result import parse_result, result_in_log
from wirecal.solver.measurements import Measurements
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.cell import Cell, Faults
from wirecal.twin.machine import Outcome
from wirecal.twin.rapid.controller import GROUP_RANGE, IrcController
from wirecal.twin.rapid.interp import run_module

SOLVE_FILE = "WCSOLVE.LOG"
"""The file controller_solve's wc_twin_load has wc_solve write to."""

HALF_RANGE = GROUP_RANGE // 2
"""The signed count's bound: the log holds counts in [-2^31, 2^31)."""

SOLVE_BASE_COUNTS = HALF_RANGE - 20_000
"""The zero readings' count in controller_solve: the points' counts wrap past 2^31."""


@dataclass
class RapidRun:
    """A measurement run of the RAPID module in the twin (the fields of ``TwinRun``)."""

    log: Path  # the log wc_run wrote (what the PC reads)
    complete: bool  # wc_run completed
    stopped: str | None  # why not (None when complete)
    world: Cell
    mount: Outcome
    run: Outcome | None
    controller: IrcController


class RapidAdapter:
    """The RAPID twin adapter (module docstring)."""

    key = "rapid"

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
        unmodelled=None,
    ) -> RapidRun:
        """Run wc_mount, then wc_run, on a true robot with ``truth`` offsets."""
        folder.mkdir(parents=True, exist_ok=True)
        world = Cell(
            robot,
            truth,
            plan.theta0_deg,
            folder,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=0.0 if counter_start is None else counter_start,
            faults=faults or Faults(),
            unmodelled=unmodelled,
        )
        text = programs[MODULE_FILE]
        controller = IrcController(world, signal_name(robot))
        mount = run_module(text, MODULE_FILE, controller, entry="wc_mount")
        run = None
        if mount.status == "completed":
            run = run_module(text, MODULE_FILE, controller, entry="wc_run")
        last = run or mount
        complete = run is not None and run.status == "completed"
        stopped = None if complete else f"{last.status} at line {last.line}: {last.message}"
        log = folder / LOG_FILE
        return RapidRun(log, complete, stopped, world, mount, run, controller)

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        measured: Measurements | np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Run wc_solve on a checked log's readings, or on wire lengths (mm, plan order).

        Checked readings keep their logged joints; bare lengths stand at the plan's.
        """
        if isinstance(measured, Measurements):
            readings = (measured.distance_mm, measured.theta0_deg, measured.joints_deg)
        else:
            readings = (np.asarray(measured), plan.theta0_deg, plan.all_points()[0])
        text = programs[MODULE_FILE]
        end = text.rindex("ENDMODULE")
        module = text[:end] + load_routine(robot, plan, *readings) + text[end:]
        folder.mkdir(parents=True, exist_ok=True)
        world = Cell(robot, {}, plan.theta0_deg, folder)
        controller = IrcController(world, signal_name(robot))
        outcome = run_module(module, MODULE_FILE, controller, entry="wc_twin_load")
        if outcome.status != "completed":
            raise WirecalError(
                f"the controller solver stopped: {outcome.message} ({MODULE_FILE}, line "
                f"{outcome.line})"
            )
        result = result_in_log((folder / SOLVE_FILE).read_text(encoding="ascii"))
        if result is None:
            raise WirecalError("wc_solve wrote no result lines")
        return {"stepwise": parse_result(result, f"{SOLVE_FILE} (wc_solve)")}


def load_routine(
    robot: Robot, plan: Plan, lengths_mm: np.ndarray, theta0_deg: np.ndarray, q: np.ndarray
) -> str:
    """Return the twin's routine wc_twin_load: the readings, then wc_solve (docstring).

    ``lengths_mm`` and the joints ``q`` (deg) of the plan's points, ``theta0_deg`` of the
    zero readings.
    """
    mpc = robot.encoder.mm_per_count
    lines = ["  PROC wc_twin_load()"]

    def keep(slot: int, counts: float, joints: np.ndarray) -> None:
        lines.append(f"    wc_rc{{{slot}}} := {dnum_literal(counts)};")
        for k, x in enumerate(joints, 1):
            lines.append(f"    wc_rj{{{slot}, {k}}} := {num_literal(x)};")

    steps = len(plan.steps)
    for s in range(1, steps + 1):
        keep(s, SOLVE_BASE_COUNTS, theta0_deg)
    for p, (length, joints) in enumerate(zip(lengths_mm, q, strict=True), 1):
        counts = (SOLVE_BASE_COUNTS + float(length) / mpc + HALF_RANGE) % GROUP_RANGE - HALF_RANGE
        keep(steps + p, counts, joints)
    lines += [
        f'    Open "{LOG_DIR}" \\File:="{SOLVE_FILE}", wc_log \\Write;',
        "    wc_solve;",
        "    Close wc_log;",
        "  ENDPROC",
        "",
    ]
    return "\n".join(lines) + "\n"


ADAPTER = RapidAdapter()
