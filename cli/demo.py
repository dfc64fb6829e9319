"""``wirecal demo``: the whole chain on the built-in Viper s650 (or a shipped robot) in the twin."""

from __future__ import annotations

import click

from wirecal.app.demo import run_demo
from wirecal.app.progress import ProgressBar
from wirecal.cli.main import user_errors
from wirecal.cli.options import SEED, number
from wirecal.solver.identify import DEFAULT_OMEGA

MAX_SCALE = DEFAULT_OMEGA / 2
"""The largest --scale: true errors within half the identification's bound Ω."""


@click.command()
@click.option(
    "-o",
    "--output",
    "folder",
    default="wirecal-demo",
    show_default=True,
    type=click.Path(file_okay=False),
    help="Folder for every output.",
)
@click.option(
    "--seed",
    type=SEED,
    default=1,
    show_default=True,
    help="Seed of the true errors and of the simulated readings.",
)
@click.option(
    "--scale",
    type=number(0.0, MAX_SCALE),
    default=1.0,
    show_default=True,
    help="True errors are drawn within ±SCALE deg/mm: at most half the bound Ω (5) of the "
    "identification; larger ones reach it and the gate refuses them, as it would a real "
    "arm's robot file that far off.",
)
@click.option(
    "--robot",
    type=click.Path(dir_okay=False, exists=True),
    default=None,
    help="A robot file with its plan.toml beside it (examples/ur5e/robot.toml, "
    "examples/abb_irb120/robot.toml): its language's chain. Default: the Viper s650 (V+).",
)
@click.option("--force", is_flag=True, help="Replace the outputs of an earlier demo.")
@user_errors
def demo(folder, seed, scale, robot, force):
    """Calibrate a simulated robot end to end, before and after.

    One chain for every controller language: generate the robot's programs for its plan,
    run them in the digital twin on a robot with random true errors (the log written on
    the controller or sent over a loopback socket to wirecal receive), identify the
    parameters on the PC, take the controller solver's result, validate with unmodelled
    errors on, write the patch (with the language's companion file) and report.html.

    The Viper s650 (the default, V+) validates with both of the paper's procedures
    before and after calibration (validation.toml beside the robot file); a robot
    without them (--robot examples/ur5e/robot.toml, examples/abb_irb120/robot.toml)
    runs the programs again over new points and compares the wire lengths with the
    nominal and the calibrated model.
    """
    with ProgressBar("demo") as bar:
        r = run_demo(
            folder,
            robot=robot,
            seed=seed,
            scale=scale,
            force=force,
            progress=bar.stages(echo=True),
        )
    click.echo("")
    click.echo(f"{'':<38}{'before':>10}{'after':>10}{'reduction':>11}")
    for v in r.validations:
        name = _NAMES[v.kind]
        click.echo(
            f"{name:<38}{v.before.mean:10.4f}{v.after.mean:10.4f}{100 * v.reduction['mean']:10.0f}%"
        )
    tb, ta = r.tool_error_mm["before"], r.tool_error_mm["after"]
    cut = f"{100 * (1 - ta / tb):10.0f}%" if tb > 0 else f"{'—':>11}"  # --scale 0: no error
    click.echo(f"{'tool-point error vs truth, mean (mm)':<38}{tb:10.4f}{ta:10.4f}{cut}")
    if r.predicted_mm is not None:
        scale = (
            ""
            if r.encoder_scale_ppm is None
            else f"   (encoder scale {r.encoder_scale_ppm:+.0f} ppm, no reference measured)"
        )
        click.echo(
            f"{'  predicted by the error budget (mm)':<38}{'':>10}{r.predicted_mm:10.4f}{scale}"
        )
    if r.bound_mm is not None:
        click.echo(f"{'  its 95 % bound (mm)':<38}{'':>10}{r.bound_mm:10.4f}")
    ctl = f"controller solver vs PC: {r.controller_difference:.1e} deg/mm"
    click.echo(f"{ctl}; total {r.total_s:.0f} s")
    click.echo(f"files in {r.folder}/: " + ", ".join(r.outputs))


_NAMES = {
    "configuration": "configuration discrepancy, mean (mm)",
    "plane": "plane-fit residual, mean (mm)",
    "distance": "wire length at new points, mean (mm)",
}
