"""WIRECAL.mod's controller solver (wc_solve) run in the twin on a log's readings.

The readings are stored in the module's data as wc_meas would have kept them (``wc_rc``,
``wc_rj``: :func:`store_readings`); the twin appends a routine ``wc_twin_solve`` to the
module that opens a result file, calls wc_solve and closes it. The result is read from
that file's ``# controller:`` lines
(:func:`~wirecal.formats.controller_result.result_in_log`), the operations from the
interpreter's count (:attr:`~wirecal.twin.rapid.interp.Interpreter.ops`). The routine is
the same for every log, so a module's joined parse, its check and its compiled
statements are kept from one run to the next.
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
from wirecal.twin.machine import f32
from wirecal.twin.rapid.controller import IrcController
from wirecal.twin.rapid.interp import Interpreter, load_module
from wirecal.twin.rapid.values import RapidError, position
from wirecal.twin.world import World

SOLVE_FILE = "WCSOLVE.LOG"
"""The file wc_twin_solve has wc_solve write to."""

RUN = "wc_twin_solve"
"""The routine the twin appends to the module (module docstring)."""

ROUTINE = (
    f"  PROC {RUN}()\n"
    f'    Open "{LOG_DIR}" \\File:="{SOLVE_FILE}", wc_log \\Write;\n'
    "    wc_solve;\n"
    "    Close wc_log;\n"
    "  ENDPROC\n"
)
"""The routine's text: wc_solve with its result written to :data:`SOLVE_FILE`."""


def controller_solve(
    robot: Robot, plan: Plan, readings: Sequence[Reading], folder: Path, text: str
) -> ControllerRun:
    """Run wc_solve of the module ``text`` on ``readings`` (a log's, in its order).

    The points in plan order, as wc_run writes them; the twin's FlexPendant lines are the
    run's console.
    """
    folder.mkdir(parents=True, exist_ok=True)
    controller = IrcController(World(robot, {}, plan.theta0_deg, folder), signal_name(robot))
    interp = load_module(text, MODULE_FILE, controller, appended=ROUTINE)
    try:
        store_readings(interp, plan, readings)
    except RapidError as e:
        raise WirecalError(f"the controller solver's readings do not fit: {e}") from None
    outcome = interp.execute(RUN)
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


def store_readings(interp: Interpreter, plan: Plan, readings: Sequence[Reading]) -> None:
    """Store ``readings`` in ``wc_rc`` and ``wc_rj`` as wc_meas keeps them.

    wc_meas's slots: each step's zero reading first (slot = step), then the points in
    the readings' order (the closing zero reading is not kept). Each value is the one the
    module's assignment of the log's number (:func:`dnum_literal`, :func:`num_literal`)
    stores: a dnum as it is read, a num rounded to single precision.
    """
    steps = len(plan.steps)
    zeros = [r for r in readings if r.kind == "zero" and r.step <= steps]
    points = [r for r in readings if r.kind == "point"]
    counts, joints = interp.globals["wc_rc"], interp.globals["wc_rj"]
    for slot, r in enumerate((*zeros, *points), 1):
        counts[position(counts, slot)] = float(dnum_literal(r.counts))
        row = joints[position(joints, slot)]
        for k, x in enumerate(r.joints_deg, 1):
            row[position(row, k)] = f32(float(num_literal(x)))
