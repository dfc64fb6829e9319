"""Run the generated controller solver in the digital twin and compare it with Python's.

The controller solver, as generated, run in the digital twin on a log's readings, and its
comparison with the Python reference solver.

The generated programs are the oracle for the controller side: the twin executes them as
written (REAL in single precision, DOUBLE in double), so the differences from the Python
reference and the operation counts reported here are those of the program a user loads.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from wirecal.gen.urscript.program import UrOptions, scripts
from wirecal.gen.vplus.program import GenOptions, module_text
from wirecal.solver.errors import WirecalError
from wirecal.solver.measurements import Measurements
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.solve import SolveResult, solve
from wirecal.twin.controller_run import ControllerRun
from wirecal.twin.urscript.solver_run import controller_solve as urscript_solve
from wirecal.twin.vplus.solver_run import controller_solve as vplus_solve


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

    ``wc.solve``, or ``wc.solve2`` with ``polish``, of the module ``text`` (generated
    with the default options when not given).
    """
    options = GenOptions()
    text = text if text is not None else module_text(robot, plan, options)
    (disk / options.result_file).unlink(missing_ok=True)  # a previous run's result
    return vplus_solve(robot, plan, m.log.readings, disk, polish=polish, text=text, closed=m.closed)


def ur_controller_solve(
    robot: Robot, plan: Plan, m: Measurements, disk: Path, *, text: str | None = None
) -> ControllerRun:
    """Run wc_solve of the generated wc_run in the twin on a checked log's readings.

    ``text`` is wc_run's text (generated with the default options when not given; a robot
    file without [controller] host/port gets loopback ones, which the solver never uses).
    """
    if text is None:
        opt = UrOptions(
            host=robot.controller.host or "127.0.0.1", port=robot.controller.port or 50000
        )
        text = scripts(robot, plan, opt)["wc_run.script"]
    return urscript_solve(robot, plan, m.log.readings, disk, text)


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
