"""WIRECAL.mod's controller solver (wc_solve) run in the twin on a log's readings.

The twin appends a routine ``wc_twin_load`` to the module: it stores the readings as
wc_meas would have kept them (``wc_rc``, ``wc_rj``), opens a result file, calls wc_solve
and closes it; the result is read from that file's ``# controller:`` lines
(:func:`~wirecal.formats.controller_result.result_in_log`), the operations from
the interpreter's count (:attr:`~wirecal.twin.rapid.interp.Interpreter.ops`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from wirecal.formats.controller_result import parse_result, result_in_log
from wirecal.formats.log import Reading
from wirecal.lang.rapid.module import LOG_DIR, MODULE_FILE, dnum_literal, num_literal, signal_name
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.controller_run import ControllerRun
from wirecal.twin.rapid.controller import IrcController
from wirecal.twin.rapid.interp import load_module
from wirecal.twin.world import World

SOLVE_FILE = "WCSOLVE.LOG"
"""The file wc_twin_load has wc_solve write to."""

LOAD = "wc_twin_load"
"""The routine the twin appends to the module (module docstring)."""


def controller_solve(
    robot: Robot, plan: Plan, readings: Sequence[Reading], folder: Path, text: str
) -> ControllerRun:
    """Run wc_solve of the module ``text`` on ``readings`` (a log's, in its order).

    The points in plan order, as wc_run writes them; the twin's FlexPendant lines are the
    run's console.
    """
    folder.mkdir(parents=True, exist_ok=True)
    controller = IrcController(World(robot, {}, plan.theta0_deg, folder), signal_name(robot))
    interp = load_module(text, MODULE_FILE, controller, appended=load_routine(plan, readings))
    outcome = interp.execute(LOAD)
    if outcome.status != "completed":
        raise WirecalError(
            f"the controller solver stopped: {outcome.message} ({MODULE_FILE}, line {outcome.line})"
        )
    result = result_in_log((folder / SOLVE_FILE).read_text(encoding="ascii"))
    if result is None:
        raise WirecalError("wc_solve wrote no result lines")
    return ControllerRun(
        "wc_solve",
        parse_result(result, f"{SOLVE_FILE} (wc_solve)"),
        Counter(interp.ops),
        tuple(controller.flexpendant),
    )


def load_routine(plan: Plan, readings: Sequence[Reading]) -> str:
    """Return the twin's routine wc_twin_load: the readings, then wc_solve (docstring).

    wc_meas's slots: each step's zero reading first (slot = step), then the points in
    the readings' order (the closing zero reading is not kept).
    """
    steps = len(plan.steps)
    zeros = [r for r in readings if r.kind == "zero" and r.step <= steps]
    points = [r for r in readings if r.kind == "point"]
    lines = [f"  PROC {LOAD}()"]
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
