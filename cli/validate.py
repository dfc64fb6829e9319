"""``wirecal validate``: the paper's validation metrics from the validation logs."""

from __future__ import annotations

import click

from wirecal.cli.main import print_json, user_errors
from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.validation_files import read_validation_log
from wirecal.solver.validation_analysis import (
    Stats,
    config_discrepancy,
    plane_residuals,
    reduction,
)


def analyse(kind: str, path: str, counter: Counter | None) -> Stats:
    """Read a validation log of ``kind`` (configuration or plane) and return its statistics."""
    log = read_validation_log(path, kind)
    if kind == "plane":
        return plane_residuals(log)[0]
    if counter is None:
        raise WirecalError(
            f"{path}: a configuration log's counts wrap at the robot's counter width: "
            "give --robot ROBOT.toml"
        )
    return config_discrepancy(log, counter)


@click.command()
@click.argument("kind", type=click.Choice(["configuration", "plane"]))
@click.argument("before", type=click.Path(dir_okay=False))
@click.argument("after", type=click.Path(dir_okay=False), required=False)
@click.option(
    "--robot",
    "robot_file",
    type=click.Path(dir_okay=False),
    help="The robot file (configuration logs: the encoder's counter width).",
)
@click.option("--json", "as_json", is_flag=True, help="Print the figures as JSON.")
@user_errors
def validate(kind, before, after, robot_file, as_json):
    """Compute the validation metric of a log from wc.vcfg or wc.vpln (paper §3.6).

    configuration: per pose, the largest difference among the wire lengths of its four
    configurations. plane: the absolute residuals of the least-squares plane through the
    probed points. With a second log (after calibration), also the reduction.
    """
    counter = load_robot(robot_file).encoder.counter if robot_file else None
    runs = {"before": analyse(kind, before, counter)}
    if after:
        runs["after"] = analyse(kind, after, counter)
    figures = {
        name: {"mean_mm": s.mean, "std_mm": s.std, "max_mm": s.max, "n": int(s.values.size)}
        for name, s in runs.items()
    }
    if after:
        figures["reduction"] = reduction(runs["before"], runs["after"])
    if as_json:
        print_json({"kind": kind, **figures})
        return
    what = (
        "maximum discrepancy among configurations"
        if kind == "configuration"
        else "plane-fit residual"
    )
    click.echo(f"{what} (mm)")
    click.echo(f"{'':<10}{'n':>5}{'mean':>10}{'std':>10}{'max':>10}")
    for name, s in runs.items():
        click.echo(f"{name:<10}{s.values.size:5d}{s.mean:10.4f}{s.std:10.4f}{s.max:10.4f}")
    if after:
        click.echo(
            f"{'reduction':<15}"
            + "".join(
                f"{'–':>10}" if r is None else f"{100 * r:9.0f}%"
                for r in figures["reduction"].values()
            )
        )
