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

from wirecal.app.languages import Registered, registered
from wirecal.gen.request import GenRequest
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.solve import SolveResult, solve
from wirecal.twin.controller_run import ControllerRun

LOOPBACK = ("127.0.0.1", 50000)
"""The PC address given to socket programs whose robot file names none (the solver never
uses it)."""


def solver_programs(reg: Registered, robot: Robot, plan: Plan) -> dict[str, str]:
    """Return the language's programs generated with the default request.

    A language that sends its log over a socket gets a loopback PC address when the robot
    file has none: its controller solver never connects.
    """
    request = GenRequest()
    if reg.language.capabilities.sockets and robot.controller.host is None:
        host, port = LOOPBACK
        request = GenRequest(host=host, port=robot.controller.port or port)
    return reg.generator.programs(robot, plan, request)


def controller_runs(
    robot: Robot,
    plan: Plan,
    m: Measurements,
    disk: Path,
    *,
    programs: dict[str, str] | None = None,
) -> dict[str, ControllerRun]:
    """Run the generated controller solver in the twin on a checked log's readings.

    Method ("stepwise", "joint") → its run, by the language's twin adapter's
    ``controller_runs`` (V+: wc.solve and wc.solve2; URScript, RAPID: wc_solve); ``programs``
    are the generated ones (the default request's when not given).
    """
    reg = registered(robot)
    if not reg.adapter.capabilities.controller_runs:
        raise WirecalError(
            f"--method controller: the {reg.language.title} twin does not yet run its "
            "controller solver on a log's readings apart from the measurement run (its result "
            "is in the log wc_run writes)"
        )
    return reg.adapter.controller_runs(
        robot, plan, m, disk, programs or solver_programs(reg, robot, plan)
    )


@dataclass(frozen=True)
class ControllerComparison:
    """The controller solver run in the twin beside the Python reference solver.

    V+: wc.solve and wc.solve2; URScript, RAPID: wc_solve (step by step only: no polish).
    """

    stepwise: ControllerRun  # wc.solve / wc_solve, against the reference's stepwise estimate
    polished: ControllerRun | None  # wc.solve2, against the reference's joint estimate
    stepwise_max_difference: float  # largest |controller − reference| (deg, mm)
    polished_max_difference: float | None
    language: str = ""  # the robot's controller language (its title), for the text
    float_bits: int = 64  # the width of the reals its solver computes in

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
        elif self.stepwise.syncs:  # a language whose solver yields the frame (URScript)
            out["syncs"] = self.stepwise.syncs
            out["most_operations_between_syncs"] = self.stepwise.most_between_syncs
        return out


JOINT_ONLY_CONTROLLER = (
    "joint_only = true: the plan was written from a pool for the wire fit 'wirecal solve' "
    "runs; the controller's solver starts step by step, which does not apply, and gen "
    "leaves it out: solve without --method controller, report without --controller"
)
"""Why the controller's solver is not run for a plan from a pool (``solve``, ``report``)."""


def compare_controller(
    result: SolveResult, disk: Path, *, programs: dict[str, str] | None = None
) -> ControllerComparison:
    """Run the controller solver in the twin on ``result``'s log; compare with Python's.

    Each controller solver (:func:`controller_runs`; V+: wc.solve and wc.solve2, URScript
    and RAPID: wc_solve) against the reference's estimate of its method. The reference is
    the Python solve of the same lengths: the file's scale, no drift removed (the
    controller solvers apply neither).
    """
    m = result.measurements
    if result.plan.joint_only:  # gen wrote no controller solver for it
        raise WirecalError(f"{result.plan.source}: {JOINT_ONLY_CONTROLLER}")
    if result.left_nominal or m.missing:
        raise WirecalError(
            "--method controller needs a complete log (the controller solver "
            "refuses missing points too)"
        )
    # The controller solver reads the lengths at the file's scale with no drift removed:
    # its reference is the Python solve of those same lengths.
    plain = solve(result.robot, result.plan, m, corrections=False)
    runs = controller_runs(result.robot, result.plan, m, disk, programs=programs)
    diffs = {
        method: max(abs(run.offsets[n] - v) for n, v in plain.estimates[method].as_dict().items())
        for method, run in runs.items()
    }
    joint = runs.get("joint")
    lang = registered(result.robot).language
    return ControllerComparison(
        runs["stepwise"],
        joint,
        diffs["stepwise"],
        None if joint is None else diffs["joint"],
        lang.title,
        lang.capabilities.float_bits,
    )
