"""``wirecal report``: the calibration and its validation as one HTML page."""

from __future__ import annotations

import tempfile
from pathlib import Path

import click

from wirecal.app.report import Validation, render_report
from wirecal.cli.main import user_errors
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import write_atomic
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.truth import load_errors
from wirecal.solver.formats.validation_files import read_validation_log
from wirecal.solver.measurements import load_measurements
from wirecal.solver.solve import solve
from wirecal.solver.validation_analysis import config_discrepancy, plane_residuals


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("plan", type=click.Path(dir_okay=False))
@click.argument("log", type=click.Path(dir_okay=False))
@click.option(
    "-o", "--output", required=True, type=click.Path(dir_okay=False), help="The HTML file to write."
)
@click.option(
    "--config",
    "config_logs",
    nargs=2,
    type=click.Path(dir_okay=False),
    help="Configuration-change logs BEFORE AFTER (wc.vcfg).",
)
@click.option(
    "--plane",
    "plane_logs",
    nargs=2,
    type=click.Path(dir_okay=False),
    help="Plane-fit logs BEFORE AFTER (wc.vpln).",
)
@click.option(
    "--controller",
    is_flag=True,
    help="Also run the generated controller solver in the digital twin.",
)
@click.option(
    "--truth",
    "truth_file",
    type=click.Path(dir_okay=False),
    help="A truth file (simulations): show the true offsets beside the estimates.",
)
@click.option("--force", is_flag=True, help="Replace an existing report.")
@user_errors
def report(robot, plan, log, output, config_logs, plane_logs, controller, truth_file, force):
    """Write a self-contained HTML report of a calibration.

    It shows the validation histograms before and after (paper Fig. 6 and 7), the
    parameters with σ and correlations, step-by-step against joint, the plan's Ψ per
    step and the robot."""
    rb = load_robot(robot)
    pl = load_plan(plan, rb)
    result = solve(rb, pl, load_measurements(log, pl, rb))
    validations = []
    if config_logs:
        validations.append(
            Validation(
                "configuration",
                *(config_discrepancy(read_validation_log(p, "configuration")) for p in config_logs),
            )
        )
    if plane_logs:
        validations.append(
            Validation(
                "plane", *(plane_residuals(read_validation_log(p, "plane"))[0] for p in plane_logs)
            )
        )
    ctl = None
    if controller:
        with tempfile.TemporaryDirectory() as tmp:
            from wirecal.app.compare import compare_controller  # the twin only when asked

            ctl = compare_controller(result, Path(tmp))
    truth = load_errors(truth_file, rb) if truth_file else None
    if not str(output).endswith((".html", ".htm")):
        raise WirecalError(f"{output}: give the report an .html name")
    write_atomic(output, render_report(result, validations, ctl, truth), force=force)
    click.echo(f"wrote {output}")
