"""``wirecal validate``: the paper's validation metrics from the validation logs."""

from __future__ import annotations

import click

from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import positional
from wirecal.formats.robot_file import load_robot
from wirecal.formats.validation_files import read_validation_log
from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.validation.analysis import (
    Stats,
    ValidationLog,
    check_logs,
    config_discrepancy,
    plane_residuals,
    reduction,
)


def analyse(log: ValidationLog, counter: Counter | None) -> Stats:
    """Return a validation log's statistics (configuration or plane, its kind)."""
    if log.kind == "plane":
        return plane_residuals(log)[0]
    if counter is None:
        raise WirecalError(
            f"{log.source}: a configuration log's counts wrap at the robot's counter width: "
            "give the robot file: wirecal validate ROBOT.toml configuration …"
        )
    return config_discrepancy(log, counter)


KINDS = ("configuration", "plane")


def _arguments(args: tuple[str, ...]) -> tuple[str | None, str, str, str | None]:
    """Split ``[ROBOT] KIND BEFORE [AFTER]`` into its parts."""
    if args and args[0] in KINDS:
        robot, rest = None, args
    else:
        robot, rest = (args[0] if args else None), args[1:]
    if len(rest) not in (2, 3) or rest[0] not in KINDS:
        raise click.UsageError(
            "give [ROBOT] KIND BEFORE [AFTER]: KIND is configuration or plane, BEFORE and "
            "AFTER the validation logs"
        )
    return robot, rest[0], rest[1], rest[2] if len(rest) == 3 else None


@click.command()
@click.argument("args", nargs=-1, metavar="[ROBOT] KIND BEFORE [AFTER]")
@click.option(
    "--robot",
    "robot_alias",
    type=click.Path(dir_okay=False),
    help="ROBOT, as older versions took it.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the figures as JSON.")
@user_errors
def validate(args, robot_alias, as_json):
    """Compute the validation metric of a log from wc.vcfg or wc.vpln (paper §3.6).

    KIND configuration: per pose, the largest difference among the wire lengths of its
    four configurations (ROBOT, the robot file, gives the encoder's counter width).
    KIND plane: the absolute residuals of the least-squares plane through the probed
    points. With a second log AFTER (after calibration), also the reduction.
    """
    robot, kind, before, after = _arguments(args)
    if robot_alias is not None:
        robot = positional(robot, robot_alias, "ROBOT", "--robot")
    rob = load_robot(robot) if robot else None
    logs = [read_validation_log(path, kind) for path in (before, after) if path]
    check_logs(logs, rob)
    counter = rob.encoder.counter if rob is not None else None
    runs = dict(zip(("before", "after"), (analyse(log, counter) for log in logs), strict=False))
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
