"""The RAPID twin adapter (registry_api ``TwinAdapter``): run WIRECAL.mod in the twin.

:meth:`RapidAdapter.measure` runs ``wc_mount`` then ``wc_run`` of the generated module on
:class:`~wirecal.twin.rapid.controller.IrcController` over the twin's
:class:`~wirecal.twin.world.World`; the log the PC reads is the file wc_run wrote in
``HOME:``. :meth:`RapidAdapter.controller_solve` runs ``wc_solve`` alone on given wire
lengths: the twin appends a routine ``wc_twin_load`` to the module (the readings as
wc_meas would have kept them:
:func:`~wirecal.twin.controller_run.readings_for_lengths`) that opens a result file,
calls wc_solve and closes it; the result is read from that file's ``# controller:``
lines.
"""

from __future__ import annotations

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
from wirecal.solver.formats.log import Reading
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled
from wirecal.twin.controller_run import readings_for_lengths
from wirecal.twin.rapid.controller import IrcController
from wirecal.twin.rapid.interp import run_module
from wirecal.twin.world import Faults, TwinRun, World, stop_reason

SOLVE_FILE = "WCSOLVE.LOG"
"""The file controller_solve's wc_twin_load has wc_solve write to."""


def module_of(programs: dict[str, str]) -> str:
    """Return the module's text: the one file of a RAPID generation (WirecalError if absent)."""
    if MODULE_FILE not in programs:
        raise WirecalError(f"RAPID programs: {MODULE_FILE} is missing (got {sorted(programs)})")
    return programs[MODULE_FILE]


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
        unmodelled: Unmodelled | None = None,
    ) -> TwinRun:
        """Run wc_mount, then wc_run, on a true robot with ``truth`` offsets.

        ``counter_start``: the group input's count at zero wire length (default: drawn
        over the 32-bit counter's range); the wire's speed limits are enforced.
        """
        text = module_of(programs)
        folder.mkdir(parents=True, exist_ok=True)
        rng = np.random.default_rng([seed, 2])
        start = robot.encoder.counter.random_start(rng) if counter_start is None else counter_start
        world = World(
            robot,
            truth,
            plan.theta0_deg,
            folder,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=float(start),
            faults=faults or Faults(),
            unmodelled=unmodelled,
            wire_limits=True,
        )
        controller = IrcController(world, signal_name(robot))
        mount = run_module(text, MODULE_FILE, controller, entry="wc_mount")
        world.moves = 0  # fault positions count the moves of wc_run
        run = None
        if mount.status == "completed":
            run = run_module(text, MODULE_FILE, controller, entry="wc_run")
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
        end = text.rindex("ENDMODULE")
        module = text[:end] + load_routine(plan, readings) + text[end:]
        folder.mkdir(parents=True, exist_ok=True)
        world = World(robot, {}, plan.theta0_deg, folder)
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


def load_routine(plan: Plan, readings: tuple[Reading, ...]) -> str:
    """Return the twin's routine wc_twin_load: the readings, then wc_solve (docstring).

    wc_meas's slots: each step's zero reading first (slot = step), then the points in
    plan order (the closing zero reading is not kept).
    """
    steps = len(plan.steps)
    zeros = [r for r in readings if r.kind == "zero" and r.step <= steps]
    points = [r for r in readings if r.kind == "point"]
    lines = ["  PROC wc_twin_load()"]
    for slot, r in enumerate((*zeros, *points), 1):
        lines.append(f"    wc_rc{{{slot}}} := {dnum_literal(r.counts)};")
        for k, x in enumerate(r.joints_deg, 1):
            lines.append(f"    wc_rj{{{slot}, {k}}} := {num_literal(x)};")
    lines += [
        f'    Open "{LOG_DIR}" \\File:="{SOLVE_FILE}", wc_log \\Write;',
        "    wc_solve;",
        "    Close wc_log;",
        "  ENDPROC",
        "",
    ]
    return "\n".join(lines) + "\n"


ADAPTER = RapidAdapter()
