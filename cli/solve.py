"""Provide ``wirecal solve``: identification from a measurement log.

The command parses options, reads the files, calls :func:`wirecal.solver.solve.solve` and
the plausibility gate, writes the patch and prints (:mod:`wirecal.cli.solve_text`).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import click

from wirecal import __version__
from wirecal.app.gate import gate, warnings
from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import (
    ACCEPT_IMPLAUSIBLE,
    NON_NEGATIVE,
    PATCH_FORCE,
    PATCH_OUTPUT,
    PLAN,
    POSITIVE,
    ROBOT,
)
from wirecal.cli.solve_text import controller_text, solve_text
from wirecal.formats.csv_table import STDIN
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import read_log
from wirecal.formats.patch import companion_paths, put_patch
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.solver.errors import WirecalError
from wirecal.solver.identify import DEFAULT_OMEGA
from wirecal.solver.log.measurements import Tolerances, check_log
from wirecal.solver.plausibility import READING_NOISE_MM
from wirecal.solver.solve import refuse_options
from wirecal.solver.solve import solve as solve_api

if TYPE_CHECKING:
    from wirecal.app.compare import ControllerComparison
    from wirecal.solver.log.measurements import Measurements
    from wirecal.solver.plan.calibration_plan import Plan
    from wirecal.solver.robot import Robot
    from wirecal.solver.solve import SolveResult
    from wirecal.solver.verdict import Plausibility


@click.command()
@ROBOT
@PLAN
@click.argument("log", type=click.Path(dir_okay=False))
@PATCH_OUTPUT
@click.option(
    "--method",
    type=click.Choice(["stepwise", "joint", "all", "controller"]),
    default="all",
    show_default=True,
    help="Which identification to run and show; 'controller' adds the generated "
    "controller solver (V+, URScript or RAPID: the robot file's language) run in the "
    "digital twin beside the Python reference.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@click.option(
    "--omega",
    type=POSITIVE,
    default=DEFAULT_OMEGA,
    show_default=True,
    help="Bound Ω of each step (deg or mm) where the plan gives none.",
)
@click.option(
    "--robust", is_flag=True, help="Joint method with a robust loss (soft L1) against outliers."
)
@click.option(
    "--partial", is_flag=True, help="Solve an incomplete log from the points that are there."
)
@click.option(
    "--refine-scale",
    is_flag=True,
    help="Refine the reference's encoder scale jointly with the parameters (the lengths "
    "tell it only through the lengths held at nominal, e.g. the tool point: use it when "
    "those are exact).",
)
@click.option(
    "--joint-tol",
    type=POSITIVE,
    default=Tolerances.joint_deg,
    show_default=True,
    help="Largest difference of logged joints from the plan (deg).",
)
@click.option(
    "--spread-tol",
    type=POSITIVE,
    default=Tolerances.spread_mm,
    show_default=True,
    help="Largest spread of a point's samples (mm).",
)
@click.option(
    "--zero-tol",
    type=POSITIVE,
    default=Tolerances.zero_mm,
    show_default=True,
    help="Largest step change of the zero readings (mm): a slip. With the log's times a "
    "slope (a drift) is fitted and removed instead; without, any drift from the first. "
    "With a declared repeatability_mm at least 5.84 times the zero readings' mean length.",
)
@click.option(
    "--noise-mm",
    type=NON_NEGATIVE,
    default=READING_NOISE_MM,
    show_default=True,
    help="Reading noise σ (mm) the plausibility gate expects, before quantisation.",
)
@ACCEPT_IMPLAUSIBLE
@PATCH_FORCE
@click.option(
    "--accept-foreign",
    is_flag=True,
    help="Accept a log taken with another plan, robot file or encoder scale.",
)
@user_errors
def solve(
    robot,
    plan,
    log,
    patch_path,
    method,
    as_json,
    omega,
    robust,
    partial,
    refine_scale,
    joint_tol,
    spread_tol,
    zero_tol,
    noise_mm,
    accept_implausible,
    force,
    accept_foreign,
):
    """Identify the kinematic errors from a measurement LOG.

    LOG '-' reads standard input, e.g. the lines pasted from the controller's terminal.
    By default runs the paper's step-by-step method and the joint refinement and shows
    them side by side, with residuals and the predicted tool-point accuracy after
    calibration. With -o, writes the recommended method's patch (or the one --method
    names) and a table of values for the controller. A result that fails the plausibility
    gate (docs/accuracy.md) is refused with exit status 3 and nothing written.
    """
    rb = load_robot(robot)
    if rb.controller_problem():
        raise WirecalError(f"{rb.controller_problem()}; 'wirecal solve' reads that log")
    pl = load_plan(plan, rb)
    refuse_options(rb, pl, _methods(pl, method), refine_scale)  # before the log is read
    paths = [patch_path, *companion_paths(rb, patch_path)] if patch_path else []
    if log == STDIN and sys.stdin is not None and sys.stdin.isatty():
        click.echo("paste the log, then Ctrl-D (Windows: Ctrl-Z, Enter)", err=True)
    with Outputs(paths, force=force, inputs=[robot, plan, log]) as out:
        m = check_log(
            read_log(log), pl, rb, Tolerances(joint_tol, spread_tol, zero_tol), accept_foreign
        )
        options = (omega, robust, partial, refine_scale)
        result = _solve(rb, pl, m, method, options)
        chosen = result.recommended if method in ("all", "controller") else method
        verdict = gate(
            result, chosen, accept=accept_implausible, noise_mm=noise_mm, omega_default=omega
        )
        for line in warnings(result, verdict):
            click.echo(f"warning: {line}", err=True)
        ctl = _controller(result) if method == "controller" else None
        if patch_path:
            _put_patch(out, patch_path, result, chosen, verdict)
    _show(result, chosen, verdict, ctl, as_json)
    if patch_path:
        others = " and ".join(str(p) for p in companion_paths(rb, patch_path))
        click.echo(f"wrote {patch_path} ({chosen}) and {others}", err=as_json)


def _solve(
    rb: Robot, pl: Plan, m: Measurements, method: str, options: tuple[float, bool, bool, bool]
) -> SolveResult:
    """Solve by --method (both methods for "all" and "controller").

    ``options``: --omega, --robust, --partial, --refine-scale.
    """
    omega, robust, partial, refine_scale = options
    return solve_api(
        rb,
        pl,
        m,
        methods=_methods(pl, method),
        omega_default=omega,
        robust=robust,
        partial=partial,
        refine_scale=refine_scale,
    )


def _methods(pl: Plan, method: str) -> tuple[str, ...]:
    """Return the methods --method runs: both for "all" and "controller".

    The controller's solver (wc.solve, then wc.solve2 from it) is step by step: refused for
    a plan written from a pool (``joint_only``), whose steps isolate no parameter.
    """
    if pl.joint_only and method == "controller":
        from wirecal.app.compare import JOINT_ONLY_CONTROLLER  # the twin's module: only here

        raise WirecalError(f"{pl.source}: {JOINT_ONLY_CONTROLLER}")
    return ("stepwise", "joint") if method in ("all", "controller") else (method,)


def _put_patch(
    out: Outputs, patch_path: str, result: SolveResult, chosen: str, verdict: Plausibility
) -> None:
    """Write the ``chosen`` method's patch and its companions, with the log and the verdict."""
    m = result.measurements
    put_patch(
        out,
        patch_path,
        result.robot,
        result.estimates[chosen],
        plan_fingerprint=result.plan.fingerprint(),
        log_path=m.source,
        log_sha256=m.sha256,
        version=__version__,
        plausibility=verdict.patch_field(),
        unchecked=result.unchecked,
    )


def _show(
    result: SolveResult,
    chosen: str,
    verdict: Plausibility,
    ctl: ControllerComparison | None,
    as_json: bool,
) -> None:
    """Print the result, the verdict and the controller's, as text or --json."""
    if as_json:
        data = result.as_json()
        data["plausibility"] = verdict.as_json()
        if ctl:
            data["methods"]["controller"] = ctl.as_json()
        print_json(data)
    else:
        click.echo(solve_text(result))
        click.echo(f"plausibility ({chosen}): {verdict.summary()}")
        if ctl:
            click.echo(controller_text(ctl))


def _controller(result: SolveResult) -> ControllerComparison:
    """Run the generated controller solver (wc.solve, wc.solve2) in the twin on the log."""
    from wirecal.app.compare import compare_controller  # the twin only when asked for

    with tempfile.TemporaryDirectory() as tmp:
        return compare_controller(result, Path(tmp))
