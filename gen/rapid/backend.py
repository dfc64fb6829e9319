"""The RAPID generator behind ``wirecal gen`` (the registry's ``Generator``): WIRECAL.mod."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from wirecal.gen.backends import Generator
from wirecal.gen.rapid.program import RapidOptions, module_text, write_module
from wirecal.gen.request import GenRequest
from wirecal.lang.rapid import Rapid
from wirecal.lang.rapid.module import LOG_DIR, LOG_FILE, MODULE_FILE, signal_name
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import PAPER_RUN


class RapidGenerator(Generator):
    """:func:`~wirecal.gen.rapid.program.module_text` for a :class:`GenRequest`."""

    key = Rapid.key
    # the log goes to HOME:/WIRECAL.LOG and is always echoed on the FlexPendant; no socket,
    # no patch or validation programs yet
    refuses = frozenset({"patch", "validation", "host", "port", "log_file", "echo_log"})
    default_run = PAPER_RUN
    payload_step = True  # wc_run asks for the mass (TPReadNum) and tells GripLoad

    def options(self, request: GenRequest) -> RapidOptions:
        """Return the module's options for ``request``."""
        return RapidOptions(
            run=request.run or self.default_run,
            zero_tol_mm=request.zero_tol_mm,
            spread_tol_mm=request.spread_tol_mm,
            solver=request.solver,
        )

    def render(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return ``{"WIRECAL.mod": text}`` (LF line ends; :meth:`write` sets them)."""
        return {MODULE_FILE: module_text(robot, plan, self.options(request))}

    def write(
        self,
        out_dir: str | Path,
        programs: dict[str, str],
        request: GenRequest,
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
    ) -> list[Path]:
        """Write WIRECAL.mod, CRLF line ends unless the request asks for LF (``--lf``)."""
        text = programs[MODULE_FILE]
        return [write_module(out_dir, text, crlf=request.crlf, force=force, inputs=inputs)]

    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return the warning for an undeclared RobotWare version."""
        if robot.controller.software is not None:
            return []
        return [
            f"{robot_path}: [controller] software not declared; the module needs RobotWare "
            'with GInputDnum and dnum (docs/rapid.md); declare it, e.g. software = "6.13"'
        ]

    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return how to run the module and where the log lands."""
        return (
            f"load {MODULE_FILE} on the controller (group input {signal_name(robot)} "
            "configured), run wc_mount, wc_check and wc_run (PP to Routine), then fetch "
            f"{LOG_DIR}/{LOG_FILE} and run 'wirecal solve {robot_path} {plan_path} "
            f"{LOG_FILE}' (docs/rapid.md)"
        )


GENERATOR = RapidGenerator()
