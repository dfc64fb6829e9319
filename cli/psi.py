"""``wirecal psi`` and ``wirecal observe``: the Table 4 view and the identifiability analysis."""

from __future__ import annotations

import sys

import click
import numpy as np

from wirecal.app.psi_view import PsiTable, psi_table
from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import NON_NEGATIVE
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.gen.templating import render
from wirecal.solver import params as P
from wirecal.solver.cell.check import check_cell
from wirecal.solver.compliance import ComplianceObservability, compliance_observability
from wirecal.solver.distance import wire_lengths
from wirecal.solver.errors import WirecalError
from wirecal.solver.identifiability import Identifiability, analyse
from wirecal.solver.identify import at_points
from wirecal.solver.plan.exit import cone_problems
from wirecal.solver.scale import ScaleObservability, scale_observability
from wirecal.solver.sensitivity import DEFAULT_TOL, sensitivity
from wirecal.solver.verdict import READING_NOISE_MM
from wirecal.solver.wire_range import RANGE_MARGIN_MM, check_wire_range

ROBOT = click.argument("robot", type=click.Path(dir_okay=False))
PLAN = click.argument("plan", type=click.Path(dir_okay=False))


def _fmt(x: float) -> str:
    return f"{x:.2f}".replace("-0.00", "0.00")


@click.command()
@ROBOT
@PLAN
@click.option("--json", "as_json", is_flag=True, help="Print the table as JSON.")
@click.option(
    "--tol",
    type=NON_NEGATIVE,
    default=DEFAULT_TOL,
    show_default=True,
    help="Largest |Ψ| of a later parameter, relative to the step's own |Ψ_j|, "
    "for a point to be ok.",
)
@click.option(
    "--strict",
    is_flag=True,
    help="Exit with status 1 if any point is not ok or the wire leaves the encoder's range.",
)
@click.option(
    "--range-margin",
    type=NON_NEGATIVE,
    default=RANGE_MARGIN_MM,
    show_default=True,
    help="The nominal wire must stay this far inside the encoder's range_mm, at every "
    "point and along every move (mm).",
)
@user_errors
def psi(
    robot: str, plan: str, as_json: bool, tol: float, strict: bool, range_margin: float
) -> None:
    """Ψ of every calibration point, step by step (the paper's Table 4).

    For each step and point: the joints, Ψ (change of wire length per unit error, in
    the plan's order: mm/deg for th*/al*, dimensionless for a*/d*) and a verdict. A
    point is ok when every parameter identified after its step has
    |Ψ| ≤ TOL·|Ψ_j|, so the step's cost depends on its own parameter only. The nominal
    wire length is checked against the encoder's range at every point and along every
    move of the run, a wire leaving an eyelet within its cone at every point, and the
    arm clear of itself, the floor and the robot file's [cell] along every move (a
    warning; an error with --strict).
    """
    rb = load_robot(robot)
    pl = load_plan(plan, rb)
    table = psi_table(rb, pl, tol)
    compliance = _compliance(rb, pl)
    if as_json:
        data = _psi_json(table)
        if compliance is not None:
            data["compliance"] = compliance.as_json()
        print_json(data)
    else:
        click.echo(_psi_text(table, robot, plan), nl=False)
        for line in compliance.describe() if compliance is not None else ():
            click.echo(line)
    problems = cone_problems(rb, pl)
    for check in (lambda: check_wire_range(rb, pl, range_margin), lambda: check_cell(rb, pl)):
        try:
            check()
        except WirecalError as exc:
            problems = exc.problems + problems
    for line in problems:
        click.echo(f"{'error' if strict else 'warning'}: {line}", err=True)
    if strict and (problems or table.n_ok != len(table.rows)):
        sys.exit(1)


def _compliance(rb, pl) -> ComplianceObservability | None:
    """Which of the robot file's compliances the plan identifies (None: it asks for none).

    The points of a payload step with its mass on (:func:`at_points`).
    """
    if not rb.compliances:
        return None
    q, _, _ = pl.all_points()
    return compliance_observability(
        at_points(rb.nominal, pl), q, pl.theta0_deg, rb.parameters, rb.compliances, READING_NOISE_MM
    )


def _identifiability_json(ident: Identifiability) -> dict:
    return {
        "parameters": list(ident.names),
        "rank": ident.rank,
        "singular_values": [float(s) for s in ident.singular_values],
        "unobservable": list(ident.unobservable),
        "combinations": [dict(combo) for combo in ident.combinations],
        "indices": ident.indices,
        "summary": ident.describe(),
    }


def _psi_json(table: PsiTable) -> dict:
    """Return what ``wirecal psi --json`` prints."""
    return {
        "robot": table.robot,
        "fingerprint": table.fingerprint,
        "theta0_deg": [float(x) for x in table.theta0_deg],
        "tolerance": table.tolerance,
        "floor": table.floor,
        "order": list(table.order),
        "rows": [
            {
                "step": r.step,
                "index": r.index,
                "parameter": r.parameter,
                "joints_deg": [float(x) for x in r.joints_deg],
                "psi": r.psi,
                "ok": r.ok,
                "violations": list(r.violations),
            }
            for r in table.rows
        ],
        "identifiability": _identifiability_json(table.identifiability),
    }


def _psi_text(table: PsiTable, robot_file: str, plan_file: str) -> str:
    order = table.order
    width = max(6, *(len(n) + 1 for n in order))
    header = (
        "  #"
        + "".join(f"{f'j{k}':>8}" for k in range(1, 7))
        + " |"
        + "".join(f"{n:>{width}}" for n in order)
        + " | verdict"
    )
    steps = []
    for j, name in enumerate(order, 1):
        rows = [r for r in table.rows if r.step == j]
        lines = []
        for r in rows:
            joints = "".join(f"{x:8.2f}" for x in r.joints_deg)
            psis = "".join(f"{_fmt(r.psi[n]):>{width}}" for n in order)
            mark = "ok" if r.ok else "leaks " + ",".join(r.violations)
            lines.append(f"{r.index:3d}{joints} |{psis} | {mark}")
        steps.append(
            {"number": j, "parameter": name, "rows": lines, "n_ok": sum(r.ok for r in rows)}
        )
    ident = table.identifiability
    return render(
        "text/psi.txt.j2",
        robot=table.robot,
        robot_file=robot_file,
        plan_file=plan_file,
        fingerprint=table.fingerprint,
        theta0=", ".join(f"{x:g}" for x in table.theta0_deg),
        tol=table.tolerance,
        floor=table.floor,
        steps=steps,
        header=header,
        n_ok=table.n_ok,
        n_rows=len(table.rows),
        ident=ident.describe(),
        ident_names=", ".join(ident.names),
    )


@click.command()
@ROBOT
@PLAN
@click.option(
    "--all",
    "all_params",
    is_flag=True,
    help="Analyse every DH error parameter and the tool point, not only the "
    "robot file's [calibration] parameters.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the analysis as JSON.")
@user_errors
def observe(robot: str, plan: str, all_params: bool, as_json: bool) -> None:
    """Which parameters the plan's wire lengths can identify, and how well.

    Rank and singular values of the distance Jacobian over all the plan's points,
    the parameters or combinations no wire length can reveal (θ1 always; the tool
    point against th6/d6 with --all), and the observability indices O1–O5. With the robot
    file's [calibration] compliances: which of them the plan identifies with the geometry,
    with their σ at the reading noise, and why not the others.
    """
    rb = load_robot(robot)
    pl = load_plan(plan, rb)
    names = P.all_names(rb.n_joints, with_tool=True) if all_params else rb.parameters
    q, _, _ = pl.all_points()
    result = analyse(rb.nominal, q, pl.theta0_deg, names)
    scale = _scale(rb, q, pl.theta0_deg, tuple(names))
    compliance = _compliance(rb, pl)
    if as_json:
        data = _identifiability_json(result)
        if compliance is not None:
            data["compliance"] = compliance.as_json()
        data["scale"] = {
            "std_ppm": None if not np.isfinite(scale.std_ppm) else scale.std_ppm,
            "noise_mm": READING_NOISE_MM,
            "fixed_lengths": list(scale.fixed_lengths),
            "resolved_by": "reference_length_mm",
        }
        print_json(data)
        return
    click.echo(f"Robot {rb.name}; plan {plan} ({pl.n_points} points)")
    if pl.joint_only:
        click.echo(
            "note: joint_only = true: 'wirecal solve' runs the wire fit this plan was chosen "
            "for (the anchor fitted, every DH error with a prior; its predicted error is the "
            "one 'wirecal plan --pool' printed); below, the paper's model of the file's "
            "parameters at these points"
        )
    click.echo(
        "Singular values: " + " ".join(f"{s:.4g}" for s in np.asarray(result.singular_values))
    )
    for line in result.describe():
        click.echo(line)
    for line in scale.describe(READING_NOISE_MM, rb.encoder.scale_tolerance_ppm):
        click.echo(line)
    for line in compliance.describe() if compliance is not None else ():
        click.echo(line)


def _scale(rb, q_deg, theta0_deg, names: tuple[str, ...]) -> ScaleObservability:
    """How well the plan's wire lengths alone tell the encoder's scale."""
    lengths = {
        n: rb.nominal_value(n)
        for n in P.all_names(rb.n_joints, with_tool=True)
        if P.unit_of(n) == "mm" and abs(rb.nominal_value(n)) > 1e-9
    }
    psi = sensitivity(rb.nominal, q_deg, theta0_deg, names).psi
    d = wire_lengths(rb.nominal, np.radians(q_deg), np.radians(theta0_deg))
    return scale_observability(psi, d, names, lengths, READING_NOISE_MM)
