"""wirecal — kinematic calibration of robot arms with a single draw-wire encoder.

The public API (see docs/api.md). Names are imported on first use
(PEP 562), so ``import wirecal`` stays cheap; ``from wirecal import solve`` imports the
solver, and only the twin or the report import the interpreter or matplotlib.

Example::

    import wirecal

    robot = wirecal.load_robot("examples/viper_s650/robot.toml")
    plan = wirecal.load_plan("examples/viper_s650/paper_plan.toml", robot)
    truth = {name: 0.5 for name in robot.parameters}  # deg or mm
    log = wirecal.simulate_log(robot, plan, truth, seed=1)
    m = wirecal.check_log(wirecal.parse_log(log, "sim.csv"), plan, robot)
    result = wirecal.solve(robot, plan, m)
    print(result.estimates[result.recommended].as_dict())
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_API = {
    # robot and plan files
    "load_robot": "wirecal.formats.robot_file",
    "load_plan": "wirecal.formats.plan_file",
    "Robot": "wirecal.solver.robot",
    "Plan": "wirecal.solver.plan.calibration_plan",
    # design a plan, and its Ψ table (paper Table 4)
    "design": "wirecal.solver.plan.planner",
    "PlanOptions": "wirecal.solver.plan.options",
    "Design": "wirecal.solver.plan.design",
    "psi_table": "wirecal.app.psi_view",
    # simulate a measurement run
    "simulate_log": "wirecal.formats.simulated_log",
    "EncoderTruth": "wirecal.solver.simulate",
    "realistic_encoder": "wirecal.solver.simulate",
    "random_errors": "wirecal.formats.truth",
    # read and check a log
    "read_log": "wirecal.formats.log",
    "parse_log": "wirecal.formats.log",
    "check_log": "wirecal.solver.log.measurements",
    "load_measurements": "wirecal.formats.log",
    "Measurements": "wirecal.solver.log.measurements",
    "Tolerances": "wirecal.solver.log.measurements",
    # solve and write the patch
    "solve": "wirecal.solver.solve",
    "SolveResult": "wirecal.solver.solve",
    "Budget": "wirecal.solver.budget",
    "write_patch": "wirecal.formats.patch",
    # gravity compliance: what one wire identifies, and offline compensation
    "compliance_observability": "wirecal.solver.compliance",
    "compensated_joints": "wirecal.solver.compliance",
    "read_patch": "wirecal.formats.patch",
    # fit a cable-length table taken without wirecal
    "read_cable_table": "wirecal.formats.cable_table",
    "fit_table": "wirecal.solver.fit.result",
    "FitOptions": "wirecal.solver.fit.result",
    "FitResult": "wirecal.solver.fit.result",
    "synthetic_table": "wirecal.solver.fit.synth",
    # the plausibility gate between identification and any output
    "gate": "wirecal.app.gate",
    "assess": "wirecal.solver.plausibility",
    # generate the controller programs, in the robot file's language
    "generate": "wirecal.app.twin_runs",
    "write_programs": "wirecal.app.twin_runs",
    "GenRequest": "wirecal.gen.request",
    # the digital twin, in the robot file's language
    "measure_in_twin": "wirecal.app.twin_runs",
    "compare_controller": "wirecal.app.compare",
    "ControllerComparison": "wirecal.app.compare",
    # the demo and the report
    "run_demo": "wirecal.app.demo",
    "render_report": "wirecal.app.report",
    # errors a user can act on
    "WirecalError": "wirecal.solver.errors",
}

__all__ = ["__version__", *_API]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use (PEP 562)."""
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'wirecal' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(__all__)
