"""wc_run's controller solver (wc_solve) run in the twin on a log's readings.

The readings list wc_run keeps (``rd``) is rebuilt from the log and handed to wc_solve;
the lines it sends are taken as the socket would carry them, and its result read from
them (:func:`~wirecal.formats.controller_result.result_in_log`).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from wirecal.formats.controller_result import parse_result, result_in_log
from wirecal.formats.log import Reading
from wirecal.lang.urscript.parser import parse_program
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.controller_run import ControllerRun
from wirecal.twin.machine import Halt, RunError, Stopped
from wirecal.twin.urscript.controller import URController
from wirecal.twin.urscript.interp import Interpreter, i32
from wirecal.twin.world import World

READING_INTS = 8
"""wc_solve's readings: 8 ints each (count, offset × 10⁴, 6 joints × 10⁴ deg)."""


def ur_readings(readings: Sequence[Reading], plan: Plan) -> list[int]:
    """Rebuild from a log's readings the list wc_run keeps for wc_solve (``rd``).

    The zero readings of the steps first, then the points in plan order; each reading as
    wc_meas returns it: the count as an int32 base and its offset × 10⁴, the joints in
    1e-4 deg, all ints (the log's own decimals).
    """
    q_plan, step_no, index_no = plan.all_points()
    pos = {(int(s), int(i)): k + 1 for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    n_steps = len(plan.steps)
    rd = [0] * READING_INTS * (n_steps + len(q_plan))
    for r in readings:
        if r.kind == "zero" and r.step > n_steps:
            continue  # the closing zero: not kept for the solver
        slot = r.step - 1 if r.kind == "zero" else n_steps - 1 + pos[(r.step, r.index)]
        base = int(np.floor(r.counts))
        joints = [int(np.floor(x * 10000 + 0.5)) for x in r.joints_deg[:6]]
        offset = int(np.floor((r.counts - base) * 10000 + 0.5))
        rd[slot * READING_INTS : (slot + 1) * READING_INTS] = [i32(base), offset, *joints]
    return rd


class _SolverController(URController):
    """The controller as wc_solve sees it: sent lines kept, operations counted per sync."""

    def __post_init__(self) -> None:
        super().__post_init__()
        self.sent: list[str] = []
        self.marks: list[int] = [0]  # operations executed at each sync()
        self.ops: Counter[str] = Counter()

    def socket_send_line(self, str, socket_name="socket_0") -> bool:
        """Keep the line as the socket would carry it."""
        self.sent.append(str)
        return True

    def sync(self) -> None:
        """Count the operations executed since the previous sync."""
        self.marks.append(sum(self.ops.values()))
        self.syncs += 1


def controller_solve(
    robot: Robot, plan: Plan, readings: Sequence[Reading], disk: Path, text: str
) -> ControllerRun:
    """Run wc_solve of wc_run's ``text`` in the twin on a log's readings."""
    disk.mkdir(parents=True, exist_ok=True)
    ctl = _SolverController(World(robot, {}, plan.theta0_deg, disk))
    interp = Interpreter(parse_program(text, "wc_run.script"), ctl)
    ctl.ops = interp.ops
    try:
        interp.function("wc_solve")([ur_readings(readings, plan)])
    except (RunError, Halt, Stopped) as exc:
        raise WirecalError(
            f"the controller solver stopped: {exc} (wc_run.script, line {interp.where})"
        ) from None
    result = result_in_log("\n".join(ctl.sent))
    if result is None:
        raise WirecalError("wc_solve sent no result lines")
    ctl.marks.append(sum(interp.ops.values()))
    return ControllerRun(
        "wc_solve",
        parse_result(result, "wc_solve"),
        Counter(interp.ops),
        tuple(ctl.console),
        ctl.syncs,
        int(np.max(np.diff(ctl.marks))),
    )
