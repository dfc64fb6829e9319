"""Run the generated controller solver in the digital twin and compare it with Python's.

The controller solver, as generated, run in the digital twin on a log's readings, and its
comparison with the Python reference solver.

The generated programs are the oracle for the controller side: the twin executes them as
written (REAL in single precision, DOUBLE in double), so the differences from the Python
reference and the operation counts reported here are those of the program a user loads.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.gen.urscript.program import UrOptions, scripts
from wirecal.gen.vplus.program import STRIDE, GenOptions, module_text
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.controller_result import parse_result, read_result, result_in_log
from wirecal.solver.measurements import Measurements
from wirecal.solver.plan import Plan
from wirecal.solver.readings import Log
from wirecal.solver.robot import Robot
from wirecal.solver.solve import SolveResult, solve
from wirecal.twin.cell import Cell
from wirecal.twin.machine import Halt, RunError, Stopped, f32
from wirecal.twin.ur_cell import URCell
from wirecal.twin.urscript.interp import Interpreter as URInterpreter
from wirecal.twin.urscript.interp import i32
from wirecal.twin.urscript.parser import parse_program
from wirecal.twin.vplus.interp import Interpreter
from wirecal.twin.vplus.parser import parse_module


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


def readings_from_log(log: Log, plan: Plan) -> Readings:
    """Rebuild from a log the arrays the measurement program would have filled."""
    q_plan, step_no, index_no = plan.all_points()
    pos = {(int(s), int(i)): k + 1 for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    n = q_plan.shape[1]
    q = np.vstack([plan.theta0_deg, q_plan])
    cb = np.zeros(len(q))
    co = np.zeros(len(q))
    zb = np.zeros(len(plan.steps))
    zo = np.zeros(len(plan.steps))
    first_zero = True
    for r in log.readings:
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


@dataclass(frozen=True)
class ControllerRun:
    """One run of the generated controller solver in the twin."""

    program: str  # "wc.solve", "wc.solve2" or "wc_solve"
    offsets: dict[str, float]  # identified offsets (deg, mm), read from its result
    operations: Counter[str]  # arithmetic executed: add (+ −), mul, div, sqrt
    console: tuple[str, ...]
    syncs: int = 0  # URScript: sync() calls (one 2 ms frame each)
    most_between_syncs: int = 0  # URScript: most operations between two sync() calls

    @property
    def total_operations(self) -> int:
        """Return the number of operations counted, all kinds together."""
        return sum(self.operations.values())


def controller_solve(
    robot: Robot,
    plan: Plan,
    m: Measurements,
    disk: Path,
    *,
    polish: bool,
    text: str | None = None,
) -> ControllerRun:
    """Run the generated controller solver in the twin on a checked log's readings.

    ``wc.solve``, or ``wc.solve2`` with ``polish``.

    The readings are loaded into the globals exactly as wc.run leaves them; the result is
    read back from the file the solver writes. ``text`` is the module (generated with the
    default options when not given).
    """
    options = GenOptions()
    disk.mkdir(parents=True, exist_ok=True)
    text = text if text is not None else module_text(robot, plan, options)
    interp = Interpreter(parse_module(text, "WIRECAL.V2"), Cell(robot, {}, plan.theta0_deg, disk))
    r = readings_from_log(m.log, plan)
    for c in range(len(r.cb)):
        for k in range(r.q.shape[1]):
            interp.set_global("wc.q", f32(r.q[c, k]), c * STRIDE + k + 1)
        if c:
            interp.set_global("wc.cb", float(r.cb[c]), c)
            interp.set_global("wc.co", float(r.co[c]), c)
            interp.set_global("wc.got", -1.0, c)
    for s in range(len(r.zb)):
        interp.set_global("wc.zb", float(r.zb[s]), s + 1)
        interp.set_global("wc.zo", float(r.zo[s]), s + 1)
    interp.set_global("wc.closed", -1.0 if m.closed else 0.0)
    result_file = disk / options.result_file
    result_file.unlink(missing_ok=True)
    interp.ops.clear()
    program = "wc.solve2" if polish else "wc.solve"
    outcome = interp.execute(program)
    if outcome.status != "completed":
        raise WirecalError(
            f"the controller solver stopped: {outcome.message} "
            f"({outcome.program}, line {outcome.line})"
        )
    return ControllerRun(
        program, read_result(result_file), Counter(interp.ops), tuple(outcome.console)
    )


READING_INTS = 8
"""wc_solve's readings: 8 ints each (count, offset × 10⁴, 6 joints × 10⁴ deg)."""


def ur_readings(log: Log, plan: Plan) -> list[int]:
    """Rebuild from a log the readings list wc_run keeps for wc_solve (``rd``).

    The zero readings of the steps first, then the points in plan order; each reading as
    wc_meas returns it: the count as an int32 base and its offset × 10⁴, the joints in
    1e-4 deg, all ints (the log's own decimals).
    """
    q_plan, step_no, index_no = plan.all_points()
    pos = {(int(s), int(i)): k + 1 for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    n_steps = len(plan.steps)
    rd = [0] * READING_INTS * (n_steps + len(q_plan))
    for r in log.readings:
        if r.kind == "zero" and r.step > n_steps:
            continue  # the closing zero: not kept for the solver
        slot = r.step - 1 if r.kind == "zero" else n_steps - 1 + pos[(r.step, r.index)]
        base = int(np.floor(r.counts))
        joints = [int(np.floor(x * 10000 + 0.5)) for x in r.joints_deg[:6]]
        offset = int(np.floor((r.counts - base) * 10000 + 0.5))
        rd[slot * READING_INTS : (slot + 1) * READING_INTS] = [i32(base), offset, *joints]
    return rd


def ur_controller_solve(
    robot: Robot, plan: Plan, m: Measurements, disk: Path, *, text: str | None = None
) -> ControllerRun:
    """Run wc_solve of the generated wc_run in the twin on a checked log's readings.

    ``text`` is wc_run's text (generated with the default options when not given; a robot
    file without [controller] host/port gets loopback ones, which the solver never uses).
    The lines wc_solve sends are taken as the socket would carry them, and its result read
    from them (:func:`result_in_log`).
    """
    if text is None:
        opt = UrOptions(
            host=robot.controller.host or "127.0.0.1", port=robot.controller.port or 50000
        )
        text = scripts(robot, plan, opt)["wc_run.script"]
    disk.mkdir(parents=True, exist_ok=True)
    cell = URCell(robot, {}, plan.theta0_deg, disk)
    interp = URInterpreter(parse_program(text, "wc_run.script"), cell)
    sent: list[str] = []
    marks: list[int] = [0]

    def send(line, socket_name="socket_0"):
        sent.append(line)
        return True

    def sync():
        marks.append(sum(interp.ops.values()))
        cell.syncs += 1

    cell.socket_send_line = send  # type: ignore[method-assign]
    cell.sync = sync  # type: ignore[method-assign]
    try:
        interp.function("wc_solve")([ur_readings(m.log, plan)])
    except (RunError, Halt, Stopped) as exc:
        raise WirecalError(
            f"the controller solver stopped: {exc} (wc_run.script, line {interp.where})"
        ) from None
    result = result_in_log("\n".join(sent))
    if result is None:
        raise WirecalError("wc_solve sent no result lines")
    marks.append(sum(interp.ops.values()))
    return ControllerRun(
        "wc_solve",
        parse_result(result, "wc_solve"),
        Counter(interp.ops),
        tuple(cell.console),
        cell.syncs,
        int(np.max(np.diff(marks))),
    )


@dataclass(frozen=True)
class ControllerComparison:
    """The controller solver run in the twin beside the Python reference solver.

    V+: wc.solve and wc.solve2; URScript: wc_solve (step by step only: no polish).
    """

    stepwise: ControllerRun  # wc.solve / wc_solve, against the reference's stepwise estimate
    polished: ControllerRun | None  # wc.solve2, against the reference's joint estimate
    stepwise_max_difference: float  # largest |controller − reference| (deg, mm)
    polished_max_difference: float | None

    def as_json(self) -> dict:
        """Return the ``methods.controller`` entry of ``wirecal solve --json``."""
        out: dict[str, object] = {
            "parameters": self.stepwise.offsets,
            "parameters_operations": self.stepwise.total_operations,
            "parameters_max_difference": self.stepwise_max_difference,
        }
        if self.polished is not None:
            out["polished"] = self.polished.offsets
            out["polished_operations"] = self.polished.total_operations
            out["polished_max_difference"] = self.polished_max_difference
        else:
            out["syncs"] = self.stepwise.syncs
            out["most_operations_between_syncs"] = self.stepwise.most_between_syncs
        return out


def compare_controller(
    result: SolveResult, disk: Path, *, text: str | None = None
) -> ControllerComparison:
    """Run the controller solver in the twin on ``result``'s log; compare with Python's.

    V+: wc.solve and wc.solve2 against the reference's stepwise and joint estimates;
    URScript: wc_solve (``text``: wc_run's) against the stepwise estimate. The reference is
    the Python solve of the same lengths: the file's scale, no drift removed (the
    controller solvers apply neither).
    """
    m = result.measurements
    if result.left_nominal or m.missing:
        raise WirecalError(
            "--method controller needs a complete log (the controller solver "
            "refuses missing points too)"
        )
    # The controller solver reads the lengths at the file's scale with no drift removed:
    # its reference is the Python solve of those same lengths.
    plain = solve(result.robot, result.plan, m, corrections=False)
    if result.robot.controller.language == "urscript":
        run = ur_controller_solve(result.robot, result.plan, m, disk / "stepwise", text=text)
        expected = plain.estimates["stepwise"].as_dict()
        diff = max(abs(run.offsets[n] - v) for n, v in expected.items())
        return ControllerComparison(run, None, diff, None)
    runs, diffs = [], []
    for key, polish, method in (("stepwise", False, "stepwise"), ("polished", True, "joint")):
        run = controller_solve(result.robot, result.plan, m, disk / key, polish=polish, text=text)
        expected = plain.estimates[method].as_dict()
        runs.append(run)
        diffs.append(max(abs(run.offsets[n] - v) for n, v in expected.items()))
    return ControllerComparison(runs[0], runs[1], diffs[0], diffs[1])
