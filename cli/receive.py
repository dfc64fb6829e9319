"""``wirecal receive``: the PC side of a measurement run that sends its log over TCP."""

from __future__ import annotations

import sys

import click

from wirecal.app.receive import HANDSHAKE_S, receive, summary
from wirecal.cli.main import user_errors
from wirecal.cli.options import OUTPUT_FILE, POSITIVE, positional
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.run_token import NO_KEY, run_token
from wirecal.lang.registry import language
from wirecal.solver.errors import WirecalError


@click.command("receive")
@click.argument("robot", type=click.Path(dir_okay=False), required=False)
@click.argument("plan", type=click.Path(dir_okay=False), required=False)
@click.option(
    "--robot",
    "robot_alias",
    type=click.Path(dir_okay=False),
    help="ROBOT, as older versions took it.",
)
@click.option(
    "--plan", "plan_alias", type=click.Path(dir_okay=False), help="PLAN, as older versions took it."
)
@click.option("-o", "--output", required=True, type=OUTPUT_FILE, help="The log to write.")
@click.option(
    "--port",
    type=click.IntRange(1, 65535),
    help="TCP port to listen on  [default: the robot file's [controller] port].",
)
@click.option(
    "--host",
    help="Address to listen on: one this PC has on the robot's network, 0.0.0.0 for all  "
    "[default: the robot file's [controller] host, else 127.0.0.1].",
)
@click.option(
    "--timeout",
    "timeout_s",
    type=POSITIVE,
    default=600.0,
    show_default=True,
    help="Seconds to wait for the robot program, and between two of its lines.",
)
@click.option("--force", is_flag=True, help="Replace an existing log (never the robot or plan).")
@user_errors
def receive_cmd(robot, plan, robot_alias, plan_alias, output, port, host, timeout_s, force):
    """Receive a measurement log from a robot program over TCP.

    ROBOT is the robot file the programs were generated from (its key, host and port),
    PLAN the plan being measured.
    Listens on HOST:PORT for the robot program of PLAN, which must first present the
    run's token (derived from the robot file's [controller] key and the plan, as in the
    generated program); other connections are refused or closed without ending the run.
    Each line the program sends is written to OUTPUT.partial at once (flushed to disk).
    When the line '# end' arrives and the log is complete and passes its checks, OUTPUT
    is published and OUTPUT.partial removed (exit status 0). Otherwise — the connection
    drops, --timeout passes, or the log is incomplete — OUTPUT is not written,
    OUTPUT.partial keeps every line received (a wirecal log: solve can read it) and what
    is missing is named (exit status 1).
    """
    robot = positional(robot, robot_alias, "ROBOT", "--robot")
    plan = positional(plan, plan_alias, "PLAN", "--plan")
    rob = load_robot(robot)
    pl = load_plan(plan, rob)
    lang = language(rob.controller.language)
    if not lang.capabilities.sockets:
        raise WirecalError(
            f"{robot}: [controller] language is {rob.controller.language!r}: the {lang.title} "
            "programs write their log to the controller's disk, not over TCP (only a language "
            "with sockets sends it to wirecal receive)"
        )
    port = port or rob.controller.port
    if port is None:
        raise WirecalError(f"{robot}: no [controller] port: give --port (the one the program uses)")
    host = host or rob.controller.host or "127.0.0.1"
    if rob.controller.key is None:
        click.echo(f"warning: {robot}: {NO_KEY}", err=True)
    token = run_token(rob, pl.fingerprint())

    def listening(bound: int) -> None:  # once the log is reserved and the port bound
        click.echo(
            f"listening on {host}:{bound} for the run of plan {pl.fingerprint()[:12]}… (token "
            f"{token[:6]}…; a sender has {min(HANDSHAKE_S, timeout_s):g} s to present it); "
            "Ctrl-C to stop",
            err=True,
        )

    result = receive(
        port,
        output,
        rob,
        pl,
        timeout_s=timeout_s,
        force=force,
        host=host,
        on_listening=listening,
        on_refused=lambda message: click.echo(f"warning: {message}", err=True),
    )
    for line in summary(result, rob, pl):
        click.echo(line, err=not result.complete)
    if not result.complete:
        sys.exit(1)
