"""The URScript generator behind ``wirecal gen``: ``wc_mount``, ``wc_check``, ``wc_run``."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from wirecal.formats.run_token import NO_KEY, run_token
from wirecal.gen.backends import Generator
from wirecal.gen.request import GenRequest
from wirecal.gen.urscript.program import (
    UrOptions,
    pc_address,
    scripts,
    software_problems,
    write_scripts,
)
from wirecal.lang.urscript import URScript
from wirecal.lang.urscript.versions import NEEDED
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import PAPER_RUN


class URScriptGenerator(Generator):
    """:func:`~wirecal.gen.urscript.program.scripts` for a :class:`GenRequest`."""

    key = URScript.key
    # no file output (the log goes over the socket, mirrored with textmsg), LF line ends
    # (SD "script over port 30002"), no patch or validation programs yet
    refuses = frozenset({"patch", "validation", "log_file", "echo_log", "crlf"})
    default_run = PAPER_RUN
    payload_step = True  # wc_run asks for the mass by popup and tells set_payload

    def options(self, request: GenRequest) -> UrOptions:
        """Return the scripts' options for ``request``."""
        return UrOptions(
            run=request.run or self.default_run,
            host=request.host,
            port=request.port,
            zero_tol_mm=request.zero_tol_mm,
            spread_tol_mm=request.spread_tol_mm,
            solver=request.solver,
        )

    def render(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return the three ``.script`` files by name."""
        return scripts(robot, plan, self.options(request))

    def checker_problems(self, robot: Robot, problems: list[str]) -> list[str]:
        """Return the calls the declared software lacks (the user's); raise on a defect."""
        return software_problems(robot, problems)

    def write(
        self,
        out_dir: str | Path,
        programs: dict[str, str],
        request: GenRequest,
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
    ) -> list[Path]:
        """Write the scripts, LF line ends."""
        return write_scripts(out_dir, programs, force=force, inputs=inputs)

    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return the warnings for an undeclared software version or run key."""
        out = []
        if robot.controller.software is None:
            out.append(
                f"{robot_path}: [controller] software not declared; the programs need "
                f"e-Series software {'.'.join(map(str, NEEDED))} or later "
                "(docs/languages.md); declare it: a CB3 (3.x) gets the CB3 programs, and a "
                "version whose pages lack a call they make is refused"
            )
        if robot.controller.key is None:
            out.append(f"{robot_path}: {NO_KEY}")
        return out

    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return the order to run the scripts in and the receive command for the PC."""
        host, port = pc_address(robot, self.options(request))
        where = f" --host {host} --port {port}" if request.host or request.port else ""
        token = run_token(robot, plan.fingerprint())[:6]
        return (
            f"run wc_mount, wc_check, then on the PC 'wirecal receive {robot_path} "
            f"{plan_path}{where} -o LOG' (it listens on {host}:{port}, run token "
            f"{token}…) and wc_run"
        )


GENERATOR = URScriptGenerator()
