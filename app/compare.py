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

from wirecal.gen.vplus.program import STRIDE, GenOptions, module_text
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.controller_result import read_result
from wirecal.solver.formats.log import Log
from wirecal.solver.measurements import Measurements
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.solve import SolveResult, solve
from wirecal.twin.cell import Cell
from wirecal.twin.machine import f32
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

    program: str  # "wc.solve" or "wc.solve2"
    offsets: dict[str, float]  # identified offsets (deg, mm), read from its result file
    operations: Counter[str]  # arithmetic executed: add (+ −), mul, div, sqrt
    console: tuple[str, ...]

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


@dataclass(frozen=True)
class ControllerComparison:
    """wc.solve and wc.solve2 run in the twin beside the Python reference solver."""

    stepwise: ControllerRun  # wc.solve, against the reference's stepwise estimate
    polished: ControllerRun  # wc.solve2, against the reference's joint estimate
    stepwise_max_difference: float  # largest |controller − reference| (deg, mm)
    polished_max_difference: float

    def as_json(self) -> dict:
        """Return the ``methods.controller`` entry of ``wirecal solve --json``."""
        return {
            "parameters": self.stepwise.offsets,
            "parameters_operations": self.stepwise.total_operations,
            "parameters_max_difference": self.stepwise_max_difference,
            "polished": self.polished.offsets,
            "polished_operations": self.polished.total_operations,
            "polished_max_difference": self.polished_max_difference,
        }


def compare_controller(
    result: SolveResult, disk: Path, *, text: str | None = None
) -> ControllerComparison:
    """Run wc.solve and wc.solve2 in the twin on ``result``'s log; compare with Python's.

    Run wc.solve and wc.solve2 in the twin on the log ``result`` was solved from, and
    compare each with the Python reference's estimate (stepwise and joint) from the same
    lengths: the file's scale, no drift removed (the controller solver applies neither).
    """
    m = result.measurements
    if result.robot.controller.language != "vplus":
        raise WirecalError(
            f"--method controller runs the generated controller solver in the twin; the "
            f"{result.robot.controller.language} programs have none (only the V+ module has "
            "wc.solve): use --method stepwise, joint or all"
        )
    if result.left_nominal or m.missing:
        raise WirecalError(
            "--method controller needs a complete log (the controller solver "
            "refuses missing points too)"
        )
    # The controller solver reads the lengths at the file's scale with no drift removed:
    # its reference is the Python solve of those same lengths.
    plain = solve(result.robot, result.plan, m, corrections=False)
    runs, diffs = [], []
    for key, polish, method in (("stepwise", False, "stepwise"), ("polished", True, "joint")):
        run = controller_solve(result.robot, result.plan, m, disk / key, polish=polish, text=text)
        expected = plain.estimates[method].as_dict()
        runs.append(run)
        diffs.append(max(abs(run.offsets[n] - v) for n, v in expected.items()))
    return ControllerComparison(runs[0], runs[1], diffs[0], diffs[1])
