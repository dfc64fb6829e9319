"""``wirecal import-urdf`` and ``wirecal export-urdf``: URDF in, calibrated URDF out."""

from __future__ import annotations

import math
from pathlib import Path

import click
import numpy as np

from wirecal.app.urdf_import import ImportOptions, urdf_robot_file
from wirecal.cli.main import user_errors
from wirecal.cli.options import OUTPUT_FILE, POSITIVE, number
from wirecal.formats.fileio import Outputs
from wirecal.formats.patch import read_patch
from wirecal.formats.robot_file import load_robot
from wirecal.formats.robot_values import in_metres
from wirecal.formats.urdf import dh_urdf_text, read_urdf, urdf_with_origins
from wirecal.formats.urdf_model import calibrated_origins, read_chain
from wirecal.lang.registry import default_language, languages
from wirecal.solver.dh_from_axes import PARALLEL_TOL
from wirecal.solver.errors import WirecalError


def _numbers(count: int | None, what: str):
    """Return a click callback reading "x,y,z" as ``count`` floats (any count when None)."""

    def parse(_ctx, _param, value: str | None):
        if value is None:
            return None
        try:
            out = tuple(float(v) for v in value.split(","))
        except ValueError:
            raise click.BadParameter(f"{value!r}: give {what}, comma-separated") from None
        if (count is not None and len(out) != count) or not all(map(math.isfinite, out)):
            raise click.BadParameter(f"{value!r}: give {what}, comma-separated")
        return out

    return parse


def _output(what: str):
    """Return the ``-o, --output`` option (``--out``: the older spelling) for ``what``."""
    return click.option(
        "-o",
        "--output",
        "--out",
        "out",
        required=True,
        type=OUTPUT_FILE,
        help=f"{what} to write (--out: the older spelling).",
    )


MAX_WIRE_POINT_MM = 2000.0
"""A wire fixture farther than this from the tip link's origin is not on the tip link."""


def _wire_point(ctx, param, value: str | None):
    """Read --wire-point-mm: three numbers in mm, refusing metres and far-off points."""
    point = _numbers(3, "three numbers X,Y,Z (mm)")(ctx, param, value)
    if point is None:
        return None
    largest = max(map(abs, point))
    if largest > MAX_WIRE_POINT_MM:
        raise click.BadParameter(
            f"{value!r}: {largest:g} mm from the tip link's origin; the wire's fixture is on "
            f"the tip link, within {MAX_WIRE_POINT_MM:g} mm of it: give X,Y,Z in mm"
        )
    if in_metres(point):
        raise click.BadParameter(
            f"{value!r}: every coordinate under 1 mm: that looks like metres; give X,Y,Z in "
            "mm (e.g. -60,0,50)"
        )
    return point


@click.command("import-urdf")
@click.argument("urdf", type=click.Path(dir_okay=False))
@click.option("--tip", required=True, help="Link the wire is attached to (the chain's end).")
@click.option(
    "--base",
    default=None,
    help="The chain's first link (default: the root link of the tree --tip is in).",
)
@_output("Robot file")
@click.option("--name", default=None, help="Robot name (default: the URDF's robot name).")
@click.option(
    "--wire-point-mm",
    callback=_wire_point,
    metavar="X,Y,Z",
    help="The wire's attachment point in the tip link's frame, X,Y,Z in mm (default: the "
    "tip link's origin; write --wire-point-mm=-50,0,40 when X is negative).",
)
@click.option(
    "--language",
    type=click.Choice(sorted(languages())),
    default=default_language().key,
    show_default=True,
    help="Controller language; sets the encoder interface and counter width its programs read.",
)
@click.option(
    "--joint-speed-deg-s",
    callback=_numbers(None, "one speed per joint (deg/s)"),
    metavar="S1,…,Sn",
    help="The data sheet's maximum joint speeds, S1,…,Sn in deg/s, instead of the URDF's.",
)
@click.option(
    "--mm-per-count", default=0.025488, show_default=True, type=number(), help="Encoder scale."
)
@click.option(
    "--range-mm", default=1250.0, show_default=True, type=POSITIVE, help="Encoder wire range."
)
@click.option(
    "--counter-bits",
    type=int,
    default=None,
    help="Controller counter width (default: the language's: "
    + ", ".join(f"{lang.capabilities.counter_bits} for {key}" for key, lang in languages().items())
    + ").",
)
@click.option(
    "--interface",
    default=None,
    type=click.Choice(
        sorted(i for lang in languages().values() for i in lang.capabilities.encoder_interfaces)
    ),
    help="How the controller program reads the encoder (default: the language's: "
    + ", ".join(
        f"{lang.capabilities.encoder_interfaces[0]} for {key}" for key, lang in languages().items()
    )
    + ").",
)
@click.option("--host", default=None, help="URScript: the PC address the run sends its log to.")
@click.option(
    "--port", default=None, type=click.IntRange(1, 65535), help="URScript: the PC's port."
)
@click.option(
    "--parallel-tol-deg",
    type=number(0, 0.05, min_open=True),
    default=None,
    help="Take axes this close to parallel as parallel (a URDF with rounded angles); the "
    "import reports how far the tip then moves.",
)
@click.option("--force", is_flag=True, help="Replace OUT if it exists.")
@user_errors
def import_urdf(urdf, out, force, **options):
    """Write a robot file in Craig's modified DH from a URDF's chain BASE → TIP.

    The DH model's forward kinematics equals the URDF's: each joint turns the same way
    and is zero where the URDF's is (θ offsets absorb the difference); fixed joints are
    folded in; the wire point (--wire-point-mm in the tip link's frame) becomes the tool
    point. Limits and speeds are converted to degrees (placeholder speeds are flagged and
    left for you to confirm); link radii come from the URDF's collision geometry or link
    lengths; [cell] holds the mounting plane; the calibration parameters are proposed from
    the identifiability analysis. Prismatic and mimic joints are refused.
    """
    out_path = Path(out)
    with Outputs([out_path], force=force, inputs=[urdf]) as outs:
        result = urdf_robot_file(urdf, out_path, ImportOptions(**options))
        outs.put(out_path, result.text)
    moving = result.chain.moving
    click.echo(f"wrote {out_path}: {len(moving)} joints ({', '.join(j.name for j in moving)})")
    click.echo(f"calibration parameters: {' '.join(result.parameters)}")
    for note in result.notes:
        click.echo(f"note: {note}")
    for warning in result.warnings:
        click.echo(f"warning: {warning}", err=True)


def _tol(parallel_tol_deg: float | None) -> float:
    return PARALLEL_TOL if parallel_tol_deg is None else math.radians(parallel_tol_deg)


@click.command("export-urdf")
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("patch", type=click.Path(dir_okay=False), required=False)
@_output("URDF")
@click.option(
    "--from",
    "source",
    default=None,
    type=click.Path(dir_okay=False),
    help="URDF to keep links, visuals and collisions from (default: the robot file's [urdf]).",
)
@click.option("--force", is_flag=True, help="Replace OUT if it exists.")
@user_errors
def export_urdf(robot, patch, out, source, force):
    """Write the robot, calibrated by PATCH if given, as a URDF.

    Its joint origins reproduce the kinematics exactly. For a robot imported from a URDF
    (or with --from), a copy of that URDF where only the chain's joint origins change;
    otherwise a URDF of the DH chain (links link0…linkN and wire_point at the tool point).
    """
    inputs = [p for p in (robot, patch, source) if p]
    warning = read_patch(patch).warning if patch else None
    if warning:
        click.echo(f"warning: {patch}: {warning}", err=True)
    with Outputs([out], force=force, inputs=inputs) as outs:
        outs.put(out, _with_warning(_export_text(robot, patch, source), warning))
    click.echo(f"wrote {out}")


def _with_warning(text: str, warning: str | None) -> str:
    """Return the URDF text with the patch's overridden-gate warning as a comment.

    The comment follows the XML declaration; none when the patch passed the gate.
    """
    if not warning:
        return text
    declaration, rest = text.split("\n", 1)
    # '--' may not appear inside an XML comment
    comment = warning.replace("--accept-implausible", "option accept-implausible")
    comment = comment.replace("--", "- -")
    return f"{declaration}\n<!-- WARNING: {comment} -->\n{rest}"


def _export_text(robot, patch, source) -> str:
    rob = load_robot(robot)
    model = rob.model(read_patch(patch).offsets_for(rob) if patch else {})
    if source is None and rob.urdf is None:
        lo, hi = rob.limits_deg()  # a URDF's limits: the arm's own, inside the data sheet's
        return dh_urdf_text(
            rob.name,
            model.dh,
            model.tool_point,
            lo,
            hi,
            rob.joint_speed_deg_s,
            rob.cell.floor_z_mm,
        )
    else:
        base = rob.urdf.base_link if rob.urdf else None
        tip = rob.urdf.tip_link if rob.urdf else None
        if source is None:
            assert rob.urdf is not None, "the branch above took source = urdf = None"
            source = rob.urdf.path
        path_in = source
        doc = read_urdf(path_in)
        if tip is None:
            raise WirecalError(f"{robot}: no [urdf] table naming the tip link; import it first")
        wire = rob.urdf.wire_point_mm if rob.urdf else None
        ch = read_chain(
            doc,
            base,
            tip,
            _tol(rob.urdf.parallel_tol_deg if rob.urdf else None),
            None if wire is None else np.array(wire),
        )
        same = ch.dh.dh.shape == rob.dh.shape and np.allclose(ch.dh.dh, rob.dh, atol=1e-9)
        if not same or not np.allclose(ch.tool_point, rob.tool_point, atol=1e-9):
            raise WirecalError(
                f"{robot}: its DH table or tool point differs from what {path_in} gives for "
                f"{ch.base_link} → {ch.tip_link}: re-import the URDF (wirecal import-urdf)"
            )
        return urdf_with_origins(doc, calibrated_origins(ch, model))
