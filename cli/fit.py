"""``wirecal fit``: calibrate from a cable-length table taken without wirecal."""

from __future__ import annotations

from typing import Any

import click

from wirecal import __version__
from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import (
    ACCEPT_IMPLAUSIBLE,
    NON_NEGATIVE,
    PATCH_FORCE,
    PATCH_OUTPUT,
    POSITIVE,
    SEED,
    given,
)
from wirecal.formats.cable_table import read_cable_table
from wirecal.formats.fileio import Outputs
from wirecal.formats.patch import companion_paths, put_patch
from wirecal.formats.robot_file import load_robot
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.cable_data import CableTable
from wirecal.solver.fit.gate import Gate, Judged, gate_fit, gate_json
from wirecal.solver.fit.holdout import parse_scheme
from wirecal.solver.fit.result import (
    FitOptions,
    FitResult,
    Run,
    copies_note,
    fit_table,
    result_json,
)
from wirecal.solver.robot import Robot
from wirecal.solver.verdict import READING_NOISE_MM


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.argument("table", type=click.Path(dir_okay=False))
@click.option(
    "--map",
    "column_map",
    help='Which column is which: "j1=q1,…,j6=q6,length=L[,x=X,y=Y,z=Z]" (default: columns '
    "named j1…j6, length, and x, y, z if present).",
)
@click.option("--sheet", help="The sheet of an .xlsx workbook to read (default: the first).")
@click.option(
    "--holdout",
    default="random:0.2",
    show_default=True,
    help="Held-out validation: random:F (a share F of the rows, --repeats times), half "
    "(first half fits, second half is held out) or none.",
)
@click.option(
    "--repeats",
    type=click.IntRange(1, 100),
    default=5,
    show_default=True,
    help="Random splits of --holdout random:F.",
)
@click.option("--seed", type=SEED, default=0, show_default=True, help="Seed of the random splits.")
@click.option(
    "--scale",
    is_flag=True,
    help="Fit the cable's scale (ppm) too; one link length is then held at the robot file's "
    "value and the scale absorbs its error: use it when that length is exact.",
)
@click.option(
    "--single-session",
    is_flag=True,
    help="Fit one length offset even where the lengths jump (the jumps are listed).",
)
@click.option(
    "--refine-joints",
    is_flag=True,
    help="Refine the logged joints from the controller's x, y, z and fit again (both fits "
    "reported; a patch holds the refined fit when it passes the gate, else the other).",
)
@click.option(
    "--joint-resolution-deg",
    type=POSITIVE,
    help="Resolution of the logged joints (default: read off the table's decimals).",
)
@click.option(
    "--length-resolution-mm",
    type=POSITIVE,
    help="Resolution of the logged lengths (default: read off the table's decimals).",
)
@click.option(
    "--noise-mm",
    type=NON_NEGATIVE,
    default=READING_NOISE_MM,
    show_default=True,
    help="Reading noise σ (mm) the plausibility gate allows beside the quantisation floor.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@PATCH_OUTPUT
@click.option(
    "--report",
    "report_path",
    type=click.Path(dir_okay=False),
    help="Write a self-contained HTML report of the fit here.",
)
@ACCEPT_IMPLAUSIBLE
@PATCH_FORCE
@user_errors
def fit(
    robot,
    table,
    column_map,
    sheet,
    holdout,
    repeats,
    seed,
    scale,
    single_session,
    refine_joints,
    joint_resolution_deg,
    length_resolution_mm,
    noise_mm,
    as_json,
    patch_path,
    report_path,
    accept_implausible,
    force,
):
    """Calibrate ROBOT from a TABLE of joint angles and cable lengths taken without wirecal.

    TABLE is CSV/TSV with a header line or an .xlsx workbook: joints in degrees, an
    absolute cable length in mm to an anchor anywhere in the cell, optionally the
    controller's nominal x, y, z. Fits the anchor, the wire attachment, a length offset per
    sensor session (jumps found automatically), optionally the cable's scale, and the DH
    errors these rows identify; rejects outliers beyond 5σ; validates on held-out rows
    beside the resolutions' quantisation floor. The gate's verdict comes first: a fit it
    refuses (its error budget not below the correction it makes, held-out rows beyond 10
    floors, the residual, implausible sizes) exits with status 3, nothing written (docs/fit.md).
    """
    _random_only(holdout)
    rb = load_robot(robot)
    options = FitOptions(
        holdout=holdout,
        repeats=repeats,
        seed=seed,
        scale=scale,
        single_session=single_session,
        refine_joints=refine_joints,
        joint_resolution_deg=joint_resolution_deg,
        length_resolution_mm=length_resolution_mm,
    )
    paths = [patch_path, *companion_paths(rb, patch_path)] if patch_path else []
    paths += [report_path] if report_path else []
    with Outputs(paths, force=force, inputs=[robot, table]) as out:
        tb = read_cable_table(table, column_map, sheet=sheet, n_joints=rb.n_joints)
        result = fit_table(rb, tb, options)
        gate = gate_fit(result, accept=accept_implausible, noise_mm=noise_mm)
        for finding in gate.chosen.verdict.findings:
            click.echo(f"warning: implausible result accepted: {finding.message}", err=True)
        if patch_path:
            _put_patch(out, patch_path, rb, tb, result, gate.chosen)
        if report_path:
            _put_report(out, report_path, result, gate)
    if as_json:
        print_json(_json(result, gate))
    else:
        click.echo("\n".join([*gate_text(gate), "", *fit_text(result)]))
    _say_written(rb, patch_path, report_path, gate.chosen.label, as_json)


def _random_only(holdout: str) -> None:
    """Refuse --repeats and --seed, which act on random splits only, with another --holdout."""
    if parse_scheme(holdout)[0] == "random":
        return
    for name in ("repeats", "seed"):
        if given(name):
            raise WirecalError(
                f"--{name} acts on --holdout random:F only; with --holdout {holdout} leave it out"
            )


def _say_written(
    rb: Robot, patch_path: str | None, report_path: str | None, label: str, as_json: bool
) -> None:
    """Say which files were written (on stderr with --json)."""
    if patch_path:
        others = " and ".join(str(p) for p in companion_paths(rb, patch_path))
        click.echo(f"wrote {patch_path} and {others} ({label})", err=as_json)
    if report_path:
        click.echo(f"wrote {report_path}", err=as_json)


def _put_patch(
    out: Outputs, patch_path: str, rb: Robot, tb: CableTable, result: FitResult, chosen: Judged
) -> None:
    """Write the chosen fit's patch and its companions, the table standing for the log."""
    put_patch(
        out,
        patch_path,
        rb,
        result.estimate(chosen.run),
        plan_fingerprint=tb.sha256,
        log_path=tb.source,
        log_sha256=tb.sha256,
        version=__version__,
        plausibility=chosen.verdict.patch_field(),
    )


def _put_report(out: Outputs, report_path: str, result: FitResult, gate: Gate) -> None:
    """Write the fit's HTML report (--report)."""
    from wirecal.app.fit_report import render_fit_report  # matplotlib only here

    out.put(report_path, render_fit_report(result, gate))


def _json(result: FitResult, gate: Gate) -> dict[str, Any]:
    """Return the fit, the chosen fit's verdict and budget and the gate as --json prints them."""
    data = result_json(result)
    data["plausibility"] = gate.chosen.verdict.as_json()
    data["budget"] = gate.chosen.budget.as_json()
    data["gate"] = gate_json(gate)
    return data


def gate_text(gate: Gate) -> list[str]:
    """Return the gate's verdict on each fit, why first, and which fit a patch holds."""
    lines = []
    for j in gate.judged:
        lines += [
            f"plausibility ({j.label}): {j.verdict.summary()}",
            *(f"  why: {f.message}" for f in j.verdict.findings),
            f"  error budget (tool point, mean over the workspace) {j.budget.total:.4f} mm "
            f"(noise {j.budget.terms['noise']:.4f}, scale {j.budget.terms['scale']:.4f}) "
            f"against a correction of {j.correction_mm:.4f} mm",
        ]
    if len(gate.judged) > 1:
        lines.append(f"a patch holds the {gate.chosen.label}")
    return lines


def _rows(result: FitResult, rows, values=None) -> str:
    t = result.table
    if not len(rows):
        return "none"
    parts = [f"row {r} (line {int(t.lines[r])})" for r in rows]
    if values is not None:
        parts = [f"{p} {v:+.2f} mm" for p, v in zip(parts, values, strict=True)]
    return ", ".join(parts)


def run_text(result: FitResult, run: Run) -> list[str]:
    """Return one run's parameters, sessions, outliers and held-out figures as lines."""
    core, ho = run.core, run.holdout
    per = core.layout.boundary_per_internal
    k0 = len(core.layout.names) - core.layout.n_sessions
    outliers = [int(r) for r in range(len(core.inliers)) if not core.inliers[r]]
    lines = [
        f"parameters chosen on these rows: rank {core.identifiability.rank} of "
        f"{len(core.layout.names)}, O2 {core.identifiability.indices['O2']:.2g}",
        *(f"  left out {name}: {why}" for name, why in core.dropped),
        f"sessions: {core.layout.n_sessions}; new session at {_rows(result, core.starts[1:])}",
        "  offsets (mm): " + ", ".join(f"{v:.3f}" for v in core.x[k0:]),
    ]
    if core.ignored_jumps:
        lines.append(f"  jumps NOT fitted (--single-session): {_rows(result, core.ignored_jumps)}")
    lines += [
        f"outliers (beyond 5σ, or x, y, z disagree): {len(outliers)}: "
        + _rows(result, outliers, core.residual_mm[outliers]),
        "",
        f"{'parameter':<10}{'unit':<5}{'value':>12}{'± σ':>10}",
        *(
            f"{n:<10}{u:<5}{v:12.4f}{s:10.4f}"
            for n, u, v, s in zip(
                core.layout.names, core.layout.units, core.x * per, core.std * per, strict=True
            )
        ),
        "(DH errors and tool_x/y/z, the attachment: offsets from the robot file; anchor: "
        "base frame)",
        f"residual σ {core.sigma_mm:.4f} mm over {int(core.inliers.sum())} rows; "
        f"quantisation floor {run.floor_mm:.4f} mm",
    ]
    if ho.rows:
        lines.append(
            f"held-out ({ho.scheme}, {ho.repeats} split(s), {ho.rows} rows): RMS "
            f"{ho.rms_mm:.4f} mm, MAE {ho.mae_mm:.4f} mm, max {ho.max_mm:.4f} mm; floor "
            f"{ho.floor_mm:.4f} mm; RMS/floor {ho.ratio:.2f}"
        )
        lines += [f"  note: {n}" for n in ho.notes]
    return lines


def fit_text(result: FitResult) -> list[str]:
    """Return what ``wirecal fit`` prints without --json."""
    t = result.table
    jr, lr = result.resolution
    lines = [
        f"Robot {result.robot.name}; table {t.source}: {len(t.length_mm)} rows "
        f"(resolution: joints {jr:g} deg, length {lr:g} mm)",
        *filter(None, [copies_note(result)]),
        *run_text(result, result.main),
    ]
    if result.xyz is not None:
        x = result.xyz
        lines += [
            "",
            f"x, y, z against the nominal FK: {x.agreement_rms_mm:.4f} mm RMS (controller TCP "
            f"in the flange frame {', '.join(f'{v:.2f}' for v in x.tcp_mm)} mm); rows beyond "
            f"what rounding can make (typos? left out of the fit): {_rows(result, x.flagged)}",
        ]
    if result.refined is not None:
        lines += ["", "With the joints refined from x, y, z:", *run_text(result, result.refined)]
    return lines
