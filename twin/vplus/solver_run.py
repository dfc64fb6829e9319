"""The V+ module's controller solver (wc.solve, wc.solve2) run in the twin on a log's readings.

The readings are loaded into the globals exactly as wc.run leaves them; the result is
read back from the file the solver writes.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.formats.controller_result import read_result
from wirecal.formats.log import Reading
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.controller_run import ControllerRun
from wirecal.twin.machine import f32
from wirecal.twin.vplus.controller import VplusController
from wirecal.twin.vplus.interp import Interpreter
from wirecal.twin.world import World

_STORE_JOINT = re.compile(r"wc\.q\[c\*(\d+)\+k\]", re.IGNORECASE)
"""How wc.run stores a joint (c*stride+k): the module's own table layout."""


@dataclass(frozen=True)
class Readings:
    """What the measurement program stores for the solver (per configuration c = 0..N).

    Counts are kept as an integer base (the first sample, exact in a REAL) plus a small
    DOUBLE offset (the mean of the unwrapped samples minus the base), per point and per
    step's zero reading.
    """

    q: np.ndarray  # (N+1, n) logged joints (deg); row 0: the first zero reading
    cb: np.ndarray  # (N+1,) count base of each point (row 0 unused)
    co: np.ndarray  # (N+1,) count offset of each point
    zb: np.ndarray  # (S,) count base of each step's zero
    zo: np.ndarray  # (S,) count offset of each step's zero


def stored_readings(readings: Sequence[Reading], plan: Plan) -> Readings:
    """Rebuild from a log's readings the arrays the measurement program would have filled."""
    q_plan, step_no, index_no = plan.all_points()
    pos = {(int(s), int(i)): k + 1 for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    n = q_plan.shape[1]
    q = np.vstack([plan.theta0_deg, q_plan])
    cb = np.zeros(len(q))
    co = np.zeros(len(q))
    zb = np.zeros(len(plan.steps))
    zo = np.zeros(len(plan.steps))
    first_zero = True
    for r in readings:
        base = float(np.round(r.counts))
        if r.kind == "zero" and r.step > len(plan.steps):
            continue  # the closing zero checks the last step; it is not a reference
        if r.kind == "reference":
            continue  # the gauge's readings: the controller solver keeps the file's scale
        if r.kind == "zero":
            zb[r.step - 1], zo[r.step - 1] = base, r.counts - base
            if first_zero:
                q[0] = r.joints_deg[:n]
                first_zero = False
        else:
            k = pos[(r.step, r.index)]
            cb[k], co[k], q[k] = base, r.counts - base, r.joints_deg[:n]
    return Readings(q, cb, co, zb, zo)


def controller_solve(
    robot: Robot,
    plan: Plan,
    readings: Sequence[Reading],
    disk: Path,
    *,
    polish: bool,
    text: str,
    closed: bool = True,
) -> ControllerRun:
    """Run ``wc.solve`` (``wc.solve2`` with ``polish``) of module ``text`` on a log's readings.

    ``closed``: the log has the closing zero reading.
    """
    stride = _STORE_JOINT.search(text)
    if stride is None:
        raise WirecalError("the module's wc.run does not store its joints as wc.q[c*STRIDE+k]")
    disk.mkdir(parents=True, exist_ok=True)
    controller = VplusController(World(robot, {}, plan.theta0_deg, disk))
    interp = Interpreter(parse_module(text, "WIRECAL.V2"), controller)
    r = stored_readings(readings, plan)
    for c in range(len(r.cb)):
        for k in range(r.q.shape[1]):
            interp.set_global("wc.q", f32(r.q[c, k]), c * int(stride[1]) + k + 1)
        if c:
            interp.set_global("wc.cb", float(r.cb[c]), c)
            interp.set_global("wc.co", float(r.co[c]), c)
            interp.set_global("wc.got", -1.0, c)
    for s in range(len(r.zb)):
        interp.set_global("wc.zb", float(r.zb[s]), s + 1)
        interp.set_global("wc.zo", float(r.zo[s]), s + 1)
    interp.set_global("wc.closed", -1.0 if closed else 0.0)
    interp.ops.clear()
    program = "wc.solve2" if polish else "wc.solve"
    outcome = interp.execute(program)
    if outcome.status != "completed":
        raise WirecalError(
            f"the controller solver stopped: {outcome.message} "
            f"({outcome.program}, line {outcome.line})"
        )
    if not controller.written:
        raise WirecalError(f"{program} wrote no result file")
    return ControllerRun(
        program, read_result(controller.written[-1]), Counter(interp.ops), tuple(outcome.console)
    )
