"""``wirecal receive``: the PC side of a measurement run that sends its log over TCP."""

from __future__ import annotations

import sys

import click

from wirecal.app.receive import receive, summary
from wirecal.cli.main import user_errors
from wirecal.cli.options import POSITIVE
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot


@click.command("receive")
@click.option("--port", required=True, type=click.IntRange(1, 65535), help="TCP port to listen on.")
@click.option(
    "-o", "--output", required=True, type=click.Path(dir_okay=False), help="The log to write."
)
@click.option(
    "--timeout",
    "timeout_s",
    type=POSITIVE,
    default=600.0,
    show_default=True,
    help="Seconds to wait for the robot program, and for each next line.",
)
@click.option("--robot", type=click.Path(dir_okay=False), help="With --plan: name missing points.")
@click.option("--plan", type=click.Path(dir_okay=False), help="With --robot: name missing points.")
@click.option("--host", default="127.0.0.1", show_default=True, help="Address to listen on.")
@click.option("--force", is_flag=True, help="Replace an existing log.")
@user_errors
def receive_cmd(port, output, timeout_s, robot, plan, host, force):
    """Receive a measurement log from a robot program over TCP.

    Listens on HOST:PORT for one robot program, writes each line it sends to
    OUTPUT.partial at once (flushed to disk), and when the line '# end' arrives
    publishes OUTPUT and removes the .partial file. A second sender is turned away while
    one is connected. If the connection drops or --timeout passes first, OUTPUT is not
    written and OUTPUT.partial keeps every line received (it is a wirecal log: solve can
    read it); with --robot and --plan the missing points are named. Exit status 0 for a
    complete run, 1 for a run that stopped early.
    """
    if (robot is None) != (plan is None):
        raise WirecalError("--robot and --plan go together (to name the missing points)")
    rob = load_robot(robot) if robot else None
    pl = load_plan(plan, rob) if plan and rob else None
    click.echo(f"listening on {host}:{port} (Ctrl-C to stop) …", err=True)
    result = receive(port, output, timeout_s=timeout_s, force=force, host=host)
    for line in summary(result, rob, pl):
        click.echo(line, err=not result.complete)
    if not result.complete:
        sys.exit(1)
