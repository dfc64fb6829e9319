"""``wirecal report``: the calibration and its validation as one HTML page."""

from __future__ import annotations

import tempfile
from pathlib import Path

import click

from wirecal.app.gate import gate, warnings
from wirecal.app.report import Validation, render_report
from wirecal.cli.main import user_errors
from wirecal.cli.options import OUTPUT_FILE
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import read_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import load_errors
from wirecal.formats.validation_files import read_validation_log
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve
from wirecal.solver.validation.analysis import check_logs, config_discrepancy, plane_residuals


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("plan", type=click.Path(dir_okay=False))
@click.argument("log", type=click.Path(dir_okay=False))
@click.option("-o", "--output", required=True, type=OUTPUT_FILE, help="The HTML file to write.")
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
@click.option(
    "--accept-implausible",
    is_flag=True,
    help="Report a result the plausibility gate refuses; the report says so.",
)
@click.option(
    "--partial",
    is_flag=True,
    help="Report an incomplete log from the points that are there (as solve --partial).",
)
@click.option("--force", is_flag=True, help="Replace an existing report.")
@user_errors
def report(
    robot,
    plan,
    log,
    output,
    config_logs,
    plane_logs,
    controller,
    truth_file,
    accept_implausible,
    partial,
    force,
):
    """Write a self-contained HTML report of a calibration.

    It shows the validation histograms before and after (paper Fig. 6 and 7), the
    parameters with σ and correlations, step-by-step against joint, the plan's Ψ per
    step and the robot. A result that fails the plausibility gate is refused with exit
    status 3.
    """
    if not str(output).endswith((".html", ".htm")):
        raise WirecalError(f"{output}: give the report an .html name")
    inputs = [robot, plan, log, *(config_logs or ()), *(plane_logs or ())]
    inputs += [truth_file] if truth_file else []
    with Outputs([output], force=force, inputs=inputs) as out:
        logs, flags = (config_logs, plane_logs), (accept_implausible, partial)
        html = _report_html(robot, plan, log, logs, controller, truth_file, flags)
        out.put(output, html)
    click.echo(f"wrote {output}")


def _report_html(robot, plan, log, logs, controller, truth_file, flags) -> str:
    """Solve and render; ``logs``: (config, plane), ``flags``: (accept, partial)."""
    (config_logs, plane_logs), (accept_implausible, partial) = logs, flags
    rb = load_robot(robot)
    pl = load_plan(plan, rb)
    parsed = read_log(log)
    result = solve(rb, pl, check_log(parsed, pl, rb), partial=partial)
    verdict = gate(result, result.recommended, accept=accept_implausible)
    for line in warnings(result, verdict):  # as solve states them
        click.echo(f"warning: {line}", err=True)
    validations = []
    if config_logs:
        runs = [read_validation_log(p, "configuration") for p in config_logs]
        check_logs(runs, rb)
        validations.append(
            Validation("configuration", *(config_discrepancy(v, rb.encoder.counter) for v in runs))
        )
    if plane_logs:
        runs = [read_validation_log(p, "plane") for p in plane_logs]
        check_logs(runs, rb)
        validations.append(Validation("plane", *(plane_residuals(v)[0] for v in runs)))
    ctl = None
    if controller:
        with tempfile.TemporaryDirectory() as tmp:
            from wirecal.app.compare import compare_controller  # the twin only when asked

            ctl = compare_controller(result, Path(tmp))
    truth = load_errors(truth_file, rb, result.measurements.sha256) if truth_file else None
    return render_report(result, validations, ctl, truth, plausibility=verdict.patch_field())
