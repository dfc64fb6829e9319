"""``wirecal plan``: θ0, the identification order and the point sets for a robot."""

from __future__ import annotations

import click
import numpy as np

from wirecal.app.progress import ProgressBar
from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import OUTPUT_FILE, SEED, number
from wirecal.formats.fileio import Outputs
from wirecal.formats.plan_file import plan_to_toml
from wirecal.formats.robot_file import load_robot
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.design import Design
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.planner import design
from wirecal.solver.robot import Robot

_D = PlanOptions()


def _joints(value: str | None, n: int) -> np.ndarray | None:
    if value is None:
        return None
    items = value.replace(" ", "").split(",")
    try:
        q = np.array([float(x) for x in items])
    except ValueError:
        q = np.array([np.nan])
    if not np.all(np.isfinite(q)):  # nan, inf, a word: no angle
        bad = next(x for x in items if not _finite(x))
        raise WirecalError(
            f"--theta0 {value!r}: {bad!r} is not an angle: give {n} joint angles in degrees, "
            'e.g. "0,-90,210,-90,0,-90"'
        )
    if q.shape != (n,):
        raise WirecalError(f"--theta0 has {q.size} values; the robot has {n} joints")
    return q


def _finite(text: str) -> bool:
    """Return whether ``text`` reads as a finite number."""
    try:
        return bool(np.isfinite(float(text)))
    except ValueError:
        return False


def _plan_from_pool(
    rb: Robot,
    pool: str,
    options: tuple[str | None, str, int | None],
    output: str | None,
    as_json: bool,
    force: bool,
) -> None:
    """Plan from a pool of measured poses (--pool); ``options``: --theta0, --for, --points."""
    theta0, method, points = options
    if theta0 is not None or method != "joint":
        raise WirecalError("--pool chooses θ0 for the joint method: leave out --theta0 and --for")
    from wirecal.cli.plan_pool import plan_from_pool  # the fit's modules: only with --pool

    plan_from_pool(rb, pool, points, output, as_json, force)


def _controller_note(rb: Robot) -> str:
    """Say which commands take a plan for a robot file the controller cannot run."""
    return (
        f"note: {rb.controller_problem()}: 'psi' and 'observe' take this plan; "
        "'gen', 'simulate' and 'solve' do not"
    )


def _unplanned(robot: str, rb: Robot, d: Design, theta0_deg: np.ndarray | None) -> list[str]:
    """Return the refusal of a plan that leaves parameters out (without --allow-partial)."""
    return [
        f"{robot}: {len(d.excluded)} of the {len(rb.parameters)} parameters of "
        f"[calibration] cannot be planned ({_tried(d, theta0_deg)}); nothing "
        "written:",
        *(f"not planned: {name}: {why}" for name, why in d.excluded.items()),
        "remove them from [calibration] parameters, try another --theta0 or "
        "--seed, or give --allow-partial to take the plan without them",
    ]


def _summary(d: Design) -> dict[str, object]:
    """Return the plan's summary as --json prints it."""
    return {
        "theta0_deg": d.plan.theta0_deg.tolist(),
        "order": list(d.plan.order),
        "points": d.plan.n_points,
        "method": d.method,
        "robot_time_s": d.robot_time_s,
        "predicted_tool_error_mm": d.predicted,
        "excluded": d.excluded,
        "fingerprint": d.plan.fingerprint(),
        **_compliance_summary(d),
    }


def _compliance_summary(d: Design) -> dict[str, object]:
    """Return the compliances' predicted σ for --json (nothing when none is planned for)."""
    if not d.compliance_sigma:
        return {}
    sigma = {n: (s if np.isfinite(s) else None) for n, s in d.compliance_sigma.items()}
    return {"compliance_sigma_urad_per_nm": sigma}


def _tried(d: Design, theta0_deg: np.ndarray | None) -> str:
    """Say at which θ0s the plan was sought (the refusal of an incomplete plan)."""
    if theta0_deg is not None:
        return "at the --theta0 given; no other theta0 tried"
    return f"the best of {d.theta0_tried} theta0 tried"


@click.command()
@click.argument("robot", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    type=OUTPUT_FILE,
    help="Write the plan (TOML) here; without it, only the summary is shown.",
)
@click.option(
    "--theta0",
    help='The encoder location as joint angles, e.g. "0,-90,210,-90,0,-90" [default: chosen].',
)
@click.option(
    "--points-per-step",
    type=click.IntRange(2, 30),
    default=_D.points_per_step,
    show_default=True,
    help="Calibration points of each step.",
)
@click.option(
    "--tol",
    type=number(0.0, 1.0),
    default=_D.tol,
    show_default=True,
    help="Isolation while designing: later parameters' |Ψ| at most TOL·|Ψ_j|.",
)
@click.option(
    "--seed",
    type=SEED,
    default=_D.seed,
    show_default=True,
    help="Seed of the candidate search (the same seed, the same plan).",
)
@click.option(
    "--for",
    "method",
    type=click.Choice(["joint", "stepwise"]),
    default=_D.method,
    show_default=True,
    help="The method the points are chosen for: the joint method's least tool-point error "
    "per minute of robot time (still usable step by step), or the step-by-step method's "
    "POINTS-PER-STEP points per step.",
)
@click.option(
    "--points",
    type=click.IntRange(1, 1000),
    help="Joint design: calibration points in all [default: POINTS-PER-STEP per step]; "
    "with --pool: at most this many poses [default: 60].",
)
@click.option(
    "--pool",
    type=click.Path(dir_okay=False),
    help="Choose θ0 and the poses from this table of configurations the robot reaches "
    "(j1…jn in degrees, or a tracker data set); -o then writes the chosen ones as CSV, "
    "or to a .toml name as a plan 'gen' takes (the pre-flight applied).",
)
@click.option(
    "--allow-partial",
    is_flag=True,
    help="Take a plan that leaves parameters of [calibration] unplanned (named, with why; "
    "the predicted error counts them at their prior) instead of exiting with an error.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--force", is_flag=True, help="Replace an existing plan file.")
@user_errors
def plan(
    robot,
    output,
    theta0,
    points_per_step,
    tol,
    seed,
    method,
    points,
    pool,
    allow_partial,
    as_json,
    force,
):
    """Design a calibration plan for ROBOT's [calibration] parameters.

    Chooses θ0 (unless given), the order in which the parameters can be isolated one at
    a time (paper §3.4) and, for each, points where the wire-length error depends on it
    only, preferring points where neither earlier estimates nor still-unknown parameters
    leak into the step. With --for joint (the default) points are then added where they
    lower the joint method's tool-point error most per second of robot time. Every point
    is within the joint limits with a margin, has a wire length within the encoder's
    range and a wire clear of the links along the move from θ0, and every move keeps the
    arm out of itself, the floor and the robot file's [cell]. Prints the predicted
    accuracy (Cramér–Rao and step-by-step) and robot time; the plan file explains itself
    in its header and passes 'wirecal psi'. A parameter that cannot be planned is an
    error (exit 2, nothing written) unless --allow-partial.
    """
    rb = load_robot(robot)
    if pool is not None:
        _plan_from_pool(rb, pool, (theta0, method, points), output, as_json, force)
        return
    theta0_deg = _joints(theta0, rb.n_joints)
    if rb.controller_problem():
        click.echo(_controller_note(rb), err=True)
    if points is not None and method != "joint":
        raise WirecalError("--points applies to --for joint; give --points-per-step instead")
    opt = PlanOptions(
        points_per_step=points_per_step, tol=tol, seed=seed, method=method, points=points
    )
    with Outputs([output] if output else [], force=force, inputs=[robot]) as out:
        with ProgressBar(f"planning {rb.name}") as bar:
            d = design(rb, theta0_deg, opt, bar.update)
        if d.excluded and not allow_partial:
            raise WirecalError(_unplanned(robot, rb, d, theta0_deg))
        if output:
            out.put(output, plan_to_toml(d.plan, d.header()))
    if as_json:
        print_json(_summary(d))
        return
    click.echo(d.header())
    if points is not None and d.plan.n_points > points:
        click.echo(
            f"note: --points {points}: each of the plan's {len(d.plan.steps)} steps keeps at "
            f"least {opt.min_points} points, so it has {d.plan.n_points}",
            err=True,
        )
    if output:
        click.echo(f"wrote {output}")
