"""``wirecal plan ROBOT --pool TABLE``: θ0 and at most N poses from reachable configurations.

The planner is :mod:`wirecal.solver.plan.pool`; this module reads the pool, prints the
choice and writes it (``-o``) as a CSV of the chosen configurations, θ0 first, each with
its line in the pool, so the poses can be taught or replayed in that order; or, to a
``.toml`` name, as a plan file ``gen`` takes, the pre-flight applied
(:mod:`~wirecal.cli.plan_pool_file`).
"""

from __future__ import annotations

import click
import numpy as np

from wirecal.cli.main import print_json
from wirecal.cli.plan_pool_file import safe_plan
from wirecal.formats.fileio import Outputs
from wirecal.formats.plan_file import plan_to_toml
from wirecal.formats.tracker_sets import read_pool
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.pool import PoolPlan, plan_pool
from wirecal.solver.robot import Robot

DEFAULT_POINTS = 60
"""Poses chosen when --points is not given."""

PREDICTED = "RMS over the pool after a rigid registration, at the reading noise"
"""What the plan's predicted tool-point error is (:mod:`~wirecal.solver.plan.pool`)."""


def selection_csv(plan: PoolPlan, source: str, lines: np.ndarray, q_deg: np.ndarray) -> str:
    """Return the chosen configurations as CSV: role, pool line, j1…jn (deg)."""
    n = q_deg.shape[1]
    out = [
        f"# wirecal plan --pool {source}: θ0 (the wire's anchor) and {len(plan.rows)} poses",
        f"# predicted tool-point error {plan.predicted_mm:.4f} mm ({PREDICTED})",
        "role,pool_line," + ",".join(f"j{i + 1}" for i in range(n)),
    ]
    rows = [("theta0", plan.theta0_row), *(("point", int(r)) for r in plan.rows)]
    for role, r in rows:
        out.append(f"{role},{int(lines[r])}," + ",".join(f"{v:.6f}" for v in q_deg[r]))
    return "\n".join(out) + "\n"


def plan_header(plan: PoolPlan, source: str, lines: np.ndarray) -> str:
    """Return a pool plan file's header: where each pose comes from, what it is for."""
    return "\n".join(
        [
            f"wirecal plan --pool {source}: θ0 (the wire's anchor) and {len(plan.rows)} poses, "
            "for the wire fit 'wirecal solve' runs on this plan",
            "the steps split the poses, each in a clear visiting order: the step-by-step "
            "estimate does not apply",
            f"predicted tool-point error {plan.predicted_mm:.4f} mm ({PREDICTED})",
            f"pool lines: θ0 {int(lines[plan.theta0_row])}, poses "
            + ", ".join(str(int(lines[r])) for r in plan.rows),
        ]
    )


def _notes(plan: PoolPlan, refused: int | None, q_deg: np.ndarray) -> list[str]:
    """Return what the choice left out of the pool, and a pool that repeats its rows."""
    notes = []
    if refused:
        notes.append(
            f"{refused} pool rows the pre-flight of 'gen' refuses left out (within 1 deg of "
            "a joint or body limit, beyond the wire's range, or colliding)"
        )
    elif plan.outside:
        notes.append(f"{plan.outside} pool rows beyond the robot file's joint limits left out")
    distinct = len(np.unique(q_deg, axis=0))
    if distinct < len(q_deg):
        notes.append(
            f"the pool's {len(q_deg)} rows hold {distinct} distinct configurations: the plan "
            "may visit one more than once, and its prediction rests on that few"
        )
    return notes


def plan_from_pool(
    rb: Robot, pool: str, points: int | None, output: str | None, as_json: bool, force: bool
) -> None:
    """Choose θ0 and the poses from ``pool``, print the choice and write it (``-o``)."""
    source, lines, q_deg = read_pool(pool)
    if q_deg.shape[1] != rb.n_joints:
        raise WirecalError(
            f"{source}: {q_deg.shape[1]} joint columns; the robot {rb.name!r} has "
            f"{rb.n_joints} joints: give a pool of this robot's configurations"
        )
    n = DEFAULT_POINTS if points is None else points
    refused = None
    with Outputs([output] if output else [], force=force, inputs=[pool]) as out:
        if output and output.lower().endswith(".toml"):
            plan, made, refused = safe_plan(rb, q_deg, n, PlanOptions(), output)
            out.put(output, plan_to_toml(made, plan_header(plan, source, lines)))
        else:
            plan = plan_pool(rb, q_deg, n, PlanOptions())
            if output:
                out.put(output, selection_csv(plan, source, lines, q_deg))
    theta0 = q_deg[plan.theta0_row]
    if as_json:
        print_json(
            {
                "theta0_deg": theta0.tolist(),
                "theta0_line": int(lines[plan.theta0_row]),
                "anchor_mm": plan.anchor_mm.tolist(),
                "lines": [int(lines[r]) for r in plan.rows],
                "points": len(plan.rows),
                "parameters": list(plan.names),
                "predicted_tool_error_mm": plan.predicted_mm,
                "theta0_tried": plan.theta0_tried,
                "outside_limits": plan.outside,
                "refused_by_preflight": refused,
            }
        )
        return
    click.echo(
        f"θ0 = {', '.join(f'{v:.3f}' for v in theta0)} deg ({source}:{lines[plan.theta0_row]}), "
        f"the anchor at {', '.join(f'{v:.1f}' for v in plan.anchor_mm)} mm (nominal)"
    )
    click.echo(
        f"{len(plan.rows)} of the pool's {len(q_deg)} configurations, the best of "
        f"{plan.theta0_tried} θ0 tried; for a fit of {', '.join(plan.names)} "
        "(the DH errors and compliances with a prior)"
    )
    click.echo(f"predicted tool-point error {plan.predicted_mm:.4f} mm ({PREDICTED})")
    for note in _notes(plan, refused, q_deg):
        click.echo(f"note: {note}")
    if output:
        click.echo(f"wrote {output}")
