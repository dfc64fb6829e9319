"""The V+ generator behind ``wirecal gen``: one module, ``WIRECAL.V2``."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from wirecal.gen.backends import Generator
from wirecal.gen.request import GenRequest
from wirecal.gen.vplus.program import MODULE_NAME, GenOptions, module_text, write_module
from wirecal.lang.vplus import VPlus
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN


class VPlusGenerator(Generator):
    """:func:`~wirecal.gen.vplus.program.module_text` for a :class:`GenRequest`."""

    key = VPlus.key
    refuses = frozenset({"solver", "host", "port"})  # the log is a file; no socket
    payload_step = True  # wc.run prompts the operator to mount and remove the mass
    default_run = DEFAULT_RUN

    def options(self, request: GenRequest) -> GenOptions:
        """Return the module's options for ``request``."""
        return GenOptions(
            run=request.run or self.default_run,
            zero_tol_mm=request.zero_tol_mm,
            spread_tol_mm=request.spread_tol_mm,
            margin_deg=request.margin_deg,
            log_file=request.log_file.upper(),
            patch=request.patch,
            patch_warning=request.patch_warning,
            validation=request.validation,
            echo_log=request.echo_log,
            crlf=request.crlf,
        )

    def render(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return ``{WIRECAL.V2: the module}`` (LF line ends; :meth:`write` sets the file's)."""
        return {MODULE_NAME: module_text(robot, plan, self.options(request))}

    def write(
        self,
        out_dir: str | Path,
        programs: dict[str, str],
        request: GenRequest,
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
    ) -> list[Path]:
        """Write the module with the request's line ends (CRLF unless ``--lf``)."""
        text = programs[MODULE_NAME]
        return [write_module(out_dir, text, force=force, inputs=inputs, crlf=request.crlf)]

    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return nothing: the module depends on no undeclared controller fact."""
        return []

    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return the order to run the module's programs in."""
        return "load it on the controller, then run wc.mount, wc.check, wc.run"


GENERATOR = VPlusGenerator()
