"""``wirecal import-urdf`` and ``wirecal export-urdf``: URDF in, calibrated URDF out."""

from __future__ import annotations

import math
import os
import tomllib
from pathlib import Path

import click
import numpy as np

from wirecal.cli.main import user_errors
from wirecal.solver.dh_from_axes import PARALLEL_TOL
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import Outputs
from wirecal.solver.formats.patch import read_patch
from wirecal.solver.formats.robot_file import load_robot, robot_file_text, robot_from_dict
from wirecal.solver.formats.urdf import (
    dh_urdf_text,
    matrix_rpy,
    read_urdf,
    urdf_with_origins,
)
from wirecal.solver.identifiability import propose_parameters
from wirecal.solver.kinematics import Model
from wirecal.solver.robot import Encoder, Robot, UrdfSource
from wirecal.solver.urdf_model import calibrated_origins, fk_difference_mm, read_chain

CONTINUOUS_DEG = 360.0
"""Range written for a URDF ``continuous`` joint (no limits in the file): one turn each way."""

PROPOSAL_POINTS = 300
EXACT_MM = 1e-9


def _limits(ch) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    lo, hi, speed, notes, problems = [], [], [], [], []
    for j in ch.moving:
        where = f"{ch.urdf.path}: joint {j.name!r}"
        if j.type == "continuous":
            lo.append(-CONTINUOUS_DEG)
            hi.append(CONTINUOUS_DEG)
            notes.append(
                f"joint {j.name!r} is continuous (no limits in the URDF): written as "
                f"±{CONTINUOUS_DEG:g}°; narrow it to what the cabling allows"
            )
        elif j.lower_rad is None or j.upper_rad is None or j.lower_rad >= j.upper_rad:
            problems.append(f"{where}: needs <limit lower=… upper=…> with lower < upper")
            lo.append(0.0)
            hi.append(0.0)
        else:
            lo.append(math.degrees(j.lower_rad))
            hi.append(math.degrees(j.upper_rad))
        if j.velocity_rad_s is None or j.velocity_rad_s <= 0:
            problems.append(f"{where}: needs <limit velocity=…> > 0 (rad/s)")
            speed.append(0.0)
        else:
            speed.append(math.degrees(j.velocity_rad_s))
    if problems:
        raise WirecalError(problems)
    return np.array(lo), np.array(hi), np.array(speed), notes


def _pose_text(T: np.ndarray) -> str:
    xyz = ", ".join(f"{v:.6g}" for v in T[:3, 3])
    rpy = ", ".join(f"{v:.6g}" for v in np.degrees(matrix_rpy(T[:3, :3])))
    return f"xyz ({xyz}) mm, rpy ({rpy}) deg"


@click.command("import-urdf")
@click.argument("urdf", type=click.Path(dir_okay=False))
@click.option("--tip", required=True, help="Link at the wire attachment point (chain's end).")
@click.option("--base", default=None, help="The chain's first link (default: the root link).")
@click.option(
    "-o", "--out", "out", required=True, type=click.Path(dir_okay=False), help="Robot file."
)
@click.option("--name", default=None, help="Robot name (default: the URDF's robot name).")
@click.option(
    "--mm-per-count", default=0.025488, show_default=True, type=float, help="Encoder scale."
)
@click.option(
    "--range-mm", default=1250.0, show_default=True, type=float, help="Encoder wire range."
)
@click.option(
    "--counter-bits", default=24, show_default=True, type=int, help="Controller counter width."
)
@click.option(
    "--interface",
    default="belt",
    show_default=True,
    type=click.Choice(["belt", "device"]),
    help="How the controller program reads the encoder (see the robot file format).",
)
@click.option(
    "--parallel-tol-deg",
    type=click.FloatRange(0, 0.05, min_open=True),
    default=None,
    help="Take axes this close to parallel as parallel (a URDF with rounded angles); the "
    "import reports how far the tip then moves.",
)
@click.option("--force", is_flag=True, help="Replace OUT if it exists.")
@user_errors
def import_urdf(
    urdf,
    tip,
    base,
    out,
    name,
    mm_per_count,
    range_mm,
    counter_bits,
    interface,
    parallel_tol_deg,
    force,
):
    """Write a robot file in Craig's modified DH from a URDF's chain BASE → TIP.

    The DH model's forward kinematics equals the URDF's: each joint turns the same way
    and is zero where the URDF's is (θ offsets absorb the difference); fixed joints are
    folded in; the tip link's origin becomes the tool point (the wire attachment point:
    choose a tip link there). Limits and speeds are converted to degrees; the calibration
    parameters are proposed from the identifiability analysis. Prismatic and mimic joints
    are refused.
    """
    out_path = Path(out)
    with Outputs([out_path], force=force, inputs=[urdf]) as outs:
        text, ch, params, notes = _import_text(
            urdf,
            tip,
            base,
            out_path,
            name,
            Encoder(mm_per_count, range_mm, counter_bits, interface),
            parallel_tol_deg,
        )
        outs.put(out_path, text)
    n = len(ch.moving)
    click.echo(f"wrote {out_path}: {n} joints ({', '.join(j.name for j in ch.moving)})")
    click.echo(f"calibration parameters: {' '.join(params)}")
    for note in notes:
        click.echo(f"note: {note}")


def _tol(parallel_tol_deg: float | None) -> float:
    return PARALLEL_TOL if parallel_tol_deg is None else math.radians(parallel_tol_deg)


def _import_text(urdf, tip, base, out_path: Path, name, encoder: Encoder, parallel_tol_deg):
    """Return the robot file's text for import-urdf, checked to read back."""
    doc = read_urdf(urdf)
    ch = read_chain(doc, base, tip, _tol(parallel_tol_deg))
    lo, hi, speed, notes = _limits(ch)
    n = len(ch.moving)
    robot_name = name or doc.name or Path(urdf).stem
    model = Model(ch.dh.dh, ch.dh.tool_point)
    rng = np.random.default_rng(0)
    q = lo + rng.uniform(0, 1, (PROPOSAL_POINTS, n)) * (hi - lo)
    params = propose_parameters(model, q, (lo + hi) / 2, ch.dh.dh)
    if f"th{n}" not in params:
        notes.append(
            f"th{n} is not proposed: the tip lies on the last joint's axis, so no wire length "
            "depends on it; import with a tip link at the wire attachment point"
        )
    for i, angle in ch.dh.snapped:
        notes.append(
            f"the axes of {ch.moving[i].name!r} and {ch.moving[i + 1].name!r} are "
            f"{angle:.2g} rad from parallel (a rounded π/2 in the URDF): taken as parallel"
        )
    diff = fk_difference_mm(ch, np.radians(q))
    if ch.dh.snapped:
        notes.append(
            f"so the DH tip differs from the URDF's by up to {diff:.2g} mm "
            f"({PROPOSAL_POINTS} configurations within the limits)"
        )
    elif diff > EXACT_MM:  # a guard: the construction is exact
        raise WirecalError(
            f"{urdf}: the DH model's tip differs from the URDF's by {diff:.3g} mm; "
            "please report this URDF"
        )
    robot = Robot(
        name=robot_name,
        dh=ch.dh.dh,
        joint_min_deg=lo,
        joint_max_deg=hi,
        joint_speed_deg_s=speed,
        tool_point=ch.dh.tool_point,
        encoder=encoder,
        parameters=params,
        urdf=UrdfSource(str(urdf), ch.base_link, ch.tip_link, parallel_tol_deg),
    )
    source = os.path.relpath(Path(urdf).resolve(), out_path.resolve().parent)
    frame0 = (
        ["frame 0 is the base link's frame"]
        if np.allclose(ch.dh.frame0, np.eye(4), atol=0)
        else [
            "frame 0 is not the base link's frame (row 1 cannot place joint 1's axis in it;",
            f"wire lengths do not depend on it): base link → frame 0 is {_pose_text(ch.dh.frame0)}",
        ]
    )
    header = [
        f"{robot_name}: imported from {source} (chain {ch.base_link} → {ch.tip_link}) by",
        "wirecal import-urdf. Each number below is derived from that URDF: the DH rows from its",
        "joint origins and axes, the limits and speeds from its <limit> tags (rad → deg).",
        *frame0,
        *notes,
        "",
    ]
    row_notes = [f"{j.name}" for j in ch.moving]
    text = robot_file_text(
        robot,
        header=header,
        row_notes=row_notes,
        encoder_note="not in a URDF: from the import's options (defaults: a Unimeasure EP-50)",
        urdf_source=source,
    )
    robot_from_dict(tomllib.loads(text), str(out_path))  # what is written reads back
    return text, ch, params, notes


@click.command("export-urdf")
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("patch", type=click.Path(dir_okay=False), required=False)
@click.option(
    "-o", "--out", "out", required=True, type=click.Path(dir_okay=False), help="URDF to write."
)
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
        return dh_urdf_text(
            rob.name,
            model.dh,
            model.tool_point,
            rob.joint_min_deg,
            rob.joint_max_deg,
            rob.joint_speed_deg_s,
        )
    else:
        base = rob.urdf.base_link if rob.urdf else None
        tip = rob.urdf.tip_link if rob.urdf else None
        path_in = source or rob.urdf.path
        doc = read_urdf(path_in)
        if tip is None:
            raise WirecalError(f"{robot}: no [urdf] table naming the tip link; import it first")
        ch = read_chain(doc, base, tip, _tol(rob.urdf.parallel_tol_deg if rob.urdf else None))
        same = ch.dh.dh.shape == rob.dh.shape and np.allclose(ch.dh.dh, rob.dh, atol=1e-9)
        if not same or not np.allclose(ch.dh.tool_point, rob.tool_point, atol=1e-9):
            raise WirecalError(
                f"{robot}: its DH table or tool point differs from what {path_in} gives for "
                f"{ch.base_link} → {ch.tip_link}: re-import the URDF (wirecal import-urdf)"
            )
        return urdf_with_origins(doc, calibrated_origins(ch, model))
