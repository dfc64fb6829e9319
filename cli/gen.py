"""``wirecal gen``: the controller programs (V+ module or URScript programs)."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import click

from wirecal.app.languages import language_mismatch, registered
from wirecal.cli.main import user_errors
from wirecal.cli.options import NON_NEGATIVE, POSITIVE, number
from wirecal.formats.patch import read_patch
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.validation_files import load_setup
from wirecal.gen.backends import Generator
from wirecal.gen.request import GenRequest
from wirecal.lang.registry import languages
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.plan.exit import cone_problems
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import PAPER_RUN, RunParameters

_D = RunParameters()
_G = GenRequest()


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("plan", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False),
    help="Folder for the programs (created if missing): WIRECAL.V2 (V+), "
    "wc_mount/wc_check/wc_run.script (URScript) or WIRECAL.mod (RAPID).",
)
@click.option(
    "--language",
    type=click.Choice(sorted(languages())),
    help="Controller language: must be the robot file's [controller] language (V+ if none), "
    "whose encoder interface and counter width the file holds; a check, not a switch.",
)
@click.option(
    "--host",
    help="URScript: the PC address the run sends its log to (default: [controller] host).",
)
@click.option(
    "--port",
    type=click.IntRange(1, 65535),
    help="URScript: the port 'wirecal receive' listens on (default: [controller] port).",
)
@click.option(
    "--no-solver",
    is_flag=True,
    help="URScript: wc_run without wc_solve (the controller's step-by-step solver at its end).",
)
@click.option(
    "--speed",
    type=number(),
    help=f"V+: the highest program speed, % of full (default {_D.speed_pct:g}); each move's "
    "SPEED is lower where the wire's limits (robot file, [encoder]) ask for it. RAPID: "
    f"the same, default {PAPER_RUN.speed_pct:g}. URScript: the one speed of every move "
    f"(default {PAPER_RUN.speed_pct:g}).",
)
@click.option(
    "--accel",
    type=number(),
    default=_D.accel_pct,
    show_default=True,
    help="Acceleration and deceleration, % of full (ACCEL).",
)
@click.option(
    "--settle-s",
    type=number(),
    help=f"V+: a fixed wait after each stop before the settle rule (s, default {_D.settle_s:g}; "
    "the paper waited 3 s). URScript and RAPID: the wait before reading (default "
    f"{PAPER_RUN.settle_s:g}).",
)
@click.option(
    "--settle-max-s",
    type=number(),
    default=_D.settle_max_s,
    show_default=True,
    help="Longest wait for the counter to be still (5 readings within 2 counts); a point "
    "not still by then is logged as unsettled and measured again (s).",
)
@click.option(
    "--samples",
    type=int,
    default=_D.readings,
    show_default=True,
    help="Counter readings averaged per point.",
)
@click.option(
    "--zero-tol",
    type=POSITIVE,
    default=_G.zero_tol_mm,
    show_default=True,
    help="Largest jump of a zero reading from the previous one before the run pauses (mm): "
    "a slip; a slow drift is fitted on the PC. With a declared repeatability_mm at least "
    "5.84 times the zero readings' mean length (docs/faults.md).",
)
@click.option(
    "--spread-tol",
    type=POSITIVE,
    default=_G.spread_tol_mm,
    show_default=True,
    help="Largest spread of a point's samples before the run pauses (mm).",
)
@click.option(
    "--margin",
    type=NON_NEGATIVE,
    default=_G.margin_deg,
    show_default=True,
    help="Refuse any target closer than this to a joint limit (deg).",
)
@click.option(
    "--log-name",
    default=_G.log_file,
    show_default=True,
    help="8.3 name of the log the run writes on the controller's disk.",
)
@click.option(
    "--patch",
    "patch_file",
    type=click.Path(dir_okay=False),
    help="A patch from 'wirecal solve -o': wc.patch then holds its offsets.",
)
@click.option(
    "--validation",
    "setup_file",
    type=click.Path(dir_okay=False),
    help="A validation setup: adds wc.vcfg and wc.vpln, the paper's two "
    "validation runs (configuration change, plane fit).",
)
@click.option(
    "--range-margin",
    type=NON_NEGATIVE,
    default=_G.range_margin_mm,
    show_default=True,
    help="Refuse a plan whose nominal wire length, at a point or along a move, comes "
    "closer than this to the encoder's range_mm (mm).",
)
@click.option(
    "--echo-log",
    is_flag=True,
    help="wc.run also types every log line on the controller's terminal, and goes on "
    "without a usable disk: copy the lines into 'wirecal solve ROBOT PLAN -'.",
)
@click.option(
    "--lf",
    is_flag=True,
    help="LF line ends instead of CRLF (ACE writes V+ files with CRLF; whether LOAD "
    "accepts LF-only files is not confirmed).",
)
@click.option("--force", is_flag=True, help="Replace existing programs of the same names.")
@user_errors
def gen(robot: str, plan: str, out_dir: str, force: bool, **options: Any) -> None:
    """Write the controller programs that run PLAN: V+/eV+, URScript or ABB RAPID.

    URScript (--language urscript, or [controller] language in the robot file): wc_mount,
    wc_check and wc_run (the measurement; sends the log to 'wirecal receive' on --host,
    --port and mirrors it in the log tab; at its end wc_solve, the step-by-step solver on
    the controller, unless --no-solver), each a .script file. RAPID (ABB): WIRECAL.mod,
    whose run writes HOME:/WIRECAL.LOG and shows each row on the FlexPendant (no patch or
    validation programs yet). The rest below is V+.

    WIRECAL.V2 holds wc.mount (move to θ0, mount the encoder), wc.check (live counts),
    wc.run (the measurement; writes the log), wc.solve and wc.solve2 (identification on
    the controller: the paper's step-by-step method, then optionally a joint polish) and
    wc.patch (the table to enter in SPEC). Every target is a literal #PPOINT inside the
    joint limits with --margin, and the nominal wire stays within the encoder's range
    less --range-margin at every point and along every move, with the arm clear of
    itself, the floor and the robot file's [cell] (a plan that is not is refused, naming
    step, point and the colliding pair); the same inputs give the same bytes.
    """
    rb, pl = _load(robot, plan, options["language"])
    backend = registered(rb).generator
    request = _request(backend, rb, pl, options)
    programs = backend.programs(rb, pl, request)
    inputs = [robot, plan, *(f for f in (options["patch_file"], options["setup_file"]) if f)]
    paths = backend.write(out_dir, programs, request, force=force, inputs=inputs)
    for note in backend.notes(rb, robot):
        click.echo(f"warning: {note}", err=True)
    if pl.joint_only:
        click.echo(f"note: {plan}: {JOINT_ONLY_SOLVER}", err=True)
    steps = backend.next_steps(rb, pl, request, robot, plan)
    click.echo(f"wrote {', '.join(str(p) for p in paths)}: {steps}")


JOINT_ONLY_SOLVER = (
    "joint_only = true: the plan was written from a pool for the joint method; its steps "
    "isolate no parameter, so the controller's step-by-step solver does not apply and is "
    "left out (V+ wc.solve and wc.solve2, URScript and RAPID wc_solve): solve the log with "
    "'wirecal solve', which runs the wire fit the plan was made for"
)
"""Why ``gen`` leaves the controller's solver out of a pool's plan (the generators' rule:
:func:`wirecal.gen.targets.stepwise_solver`, and the V+ module's ``solver``).

Left out rather than refused: the measurement programs are what a pool's plan is generated
for, and V+ has no --no-solver to ask for them without it."""


def _load(robot: str, plan: str, language: str | None) -> tuple[Robot, Plan]:
    """Load ROBOT and PLAN; refuse a --language that is not the robot file's.

    Warns of the plan's points beyond the robot file's exit cone (a plan made for a wider
    exit, the paper's, still runs).
    """
    rb = load_robot(robot)
    if language is not None and language != rb.controller.language:
        raise WirecalError(language_mismatch(rb, language))
    pl = load_plan(plan, rb)
    for line in cone_problems(rb, pl):
        click.echo(f"warning: {line}", err=True)
    return rb, pl


def _request(backend: Generator, rb: Robot, pl: Plan, options: dict[str, Any]) -> GenRequest:
    """Return the generation the options ask for (the language's run defaults for the rest).

    Reads --patch (warning of an overridden plausibility gate) and --validation.
    """
    o = options
    patch_file, setup_file = o["patch_file"], o["setup_file"]
    patch = read_patch(patch_file) if patch_file else None
    if patch is not None and patch.warning:
        click.echo(f"warning: {patch_file}: {patch.warning}", err=True)
    run = (o["speed"], o["accel"], o["settle_s"], o["samples"], o["settle_max_s"])
    return GenRequest(
        run=_run(backend.default_run, *run),
        zero_tol_mm=o["zero_tol"],
        spread_tol_mm=o["spread_tol"],
        margin_deg=o["margin"],
        range_margin_mm=o["range_margin"],
        solver=not o["no_solver"],
        patch=patch.offsets_for(rb, pl) if patch is not None else None,
        patch_warning=patch.warning if patch is not None else None,
        validation=load_setup(setup_file) if setup_file else None,
        host=o["host"],
        port=o["port"],
        log_file=o["log_name"],
        echo_log=o["echo_log"],
        crlf=not o["lf"],
    )


def _run(
    language_default: RunParameters,
    speed: float | None,
    accel: float,
    settle_s: float | None,
    samples: int,
    settle_max_s: float,
) -> RunParameters:
    """Return the run's settings: the options given, the language's defaults for the others."""
    return replace(
        language_default,
        speed_pct=language_default.speed_pct if speed is None else speed,
        accel_pct=accel,
        settle_s=language_default.settle_s if settle_s is None else settle_s,
        readings=samples,
        settle_max_s=settle_max_s,
    )
