"""``wirecal gen``: the V+ module for the controller."""

from __future__ import annotations

import click

from wirecal.cli.main import user_errors
from wirecal.gen.vplus.program import GenOptions, module_text, write_module
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.validation_files import load_setup

_D = GenOptions()


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("plan", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    "out_dir",
    required=True,
    type=click.Path(file_okay=False),
    help="Folder for the module WIRECAL.V2 (created if missing).",
)
@click.option(
    "--speed",
    type=float,
    default=_D.speed,
    show_default=True,
    help="Program speed, % of full (SPEED … ALWAYS).",
)
@click.option(
    "--accel",
    type=float,
    default=_D.accel,
    show_default=True,
    help="Acceleration and deceleration, % of full (ACCEL).",
)
@click.option(
    "--settle-s",
    type=float,
    default=_D.settle_s,
    show_default=True,
    help="Wait after each stop before reading (s).",
)
@click.option(
    "--samples",
    type=int,
    default=_D.samples,
    show_default=True,
    help="Counter readings averaged per point.",
)
@click.option(
    "--zero-tol",
    type=float,
    default=_D.zero_tol_mm,
    show_default=True,
    help="Largest drift of a zero reading from the first before the run pauses (mm).",
)
@click.option(
    "--spread-tol",
    type=float,
    default=_D.spread_tol_mm,
    show_default=True,
    help="Largest spread of a point's samples before the run pauses (mm).",
)
@click.option(
    "--margin",
    type=float,
    default=_D.margin_deg,
    show_default=True,
    help="Refuse any target closer than this to a joint limit (deg).",
)
@click.option(
    "--log-name",
    default=_D.log_file,
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
@click.option("--force", is_flag=True, help="Replace an existing WIRECAL.V2.")
@user_errors
def gen(
    robot,
    plan,
    out_dir,
    speed,
    accel,
    settle_s,
    samples,
    zero_tol,
    spread_tol,
    margin,
    log_name,
    patch_file,
    setup_file,
    force,
):
    """Write the V+/eV+ module that runs PLAN on the controller.

    WIRECAL.V2 holds wc.mount (move to θ0, mount the encoder), wc.check (live counts),
    wc.run (the measurement; writes the log), wc.solve and wc.solve2 (identification on
    the controller: the paper's step-by-step method, then optionally a joint polish) and
    wc.patch (the table to enter in SPEC). Every target is a literal #PPOINT inside the
    joint limits with --margin; the same inputs give the same bytes.
    """
    rb = load_robot(robot)
    pl = load_plan(plan, rb)
    patch = None
    if patch_file:
        data = read_toml(patch_file, "patch file")
        try:
            if data.get("plan") != pl.fingerprint():
                raise WirecalError(
                    f"{patch_file}: plan: the patch was solved from another "
                    "plan; generate with the plan it came from"
                )
            patch = {n: float(v["offset"]) for n, v in data["parameters"].items()}
        except (KeyError, TypeError, ValueError, AttributeError):
            raise WirecalError(
                f"{patch_file}: parameters: not a wirecal patch (need "
                "[parameters.<name>] tables with an offset)"
            ) from None
    opt = GenOptions(
        speed=speed,
        accel=accel,
        settle_s=settle_s,
        samples=samples,
        zero_tol_mm=zero_tol,
        spread_tol_mm=spread_tol,
        margin_deg=margin,
        log_file=log_name.upper(),
        patch=patch,
        validation=load_setup(setup_file) if setup_file else None,
    )
    path = write_module(out_dir, module_text(rb, pl, opt), force=force)
    click.echo(f"wrote {path}: load it on the controller, then run wc.mount, wc.check, wc.run")
