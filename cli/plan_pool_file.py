"""``wirecal plan ROBOT --pool TABLE -o PLAN.toml``: the pool's choice as a plan ``gen`` takes.

The plan is for the pool planner's wire fit, which ``wirecal solve`` runs on it
(:mod:`~wirecal.solver.solve_pool`): θ0 and the chosen poses, split over the steps of the
robot file's ``[calibration] parameters`` in the order chosen (the plan file has one step
per parameter; the fit uses every point whatever its step, the step-by-step estimate
does not apply to poses nobody chose to isolate a parameter).

Before anything is written, the pre-flight ``gen`` applies
(:func:`~wirecal.gen.preflight.check_limits`,
:func:`~wirecal.solver.wire_range.check_wire_range`,
:func:`~wirecal.solver.cell.check.check_cell`): the pool rows within ``gen``'s margin of a
joint or body limit are left out before choosing; each chosen pose whose move from θ0 and
back, or from the pose before it in its step, leaves the wire's range or meets the arm,
the floor or the cell is refused and the choice made again without it (at most
:data:`SAFETY_ROUNDS` times); the whole plan must then pass, else nothing is written.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from wirecal.gen.preflight import check_limits
from wirecal.gen.request import GenRequest
from wirecal.solver.cell.check import check_cell
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.calibration_plan import Plan, Step
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.pool import PoolPlan, plan_pool
from wirecal.solver.plan.tour import tour
from wirecal.solver.robot import Robot
from wirecal.solver.wire_range import check_wire_range

SAFETY_ROUNDS = 16
"""Choices made again without the poses the pre-flight refused, before giving up.

Measured on the public UR10 series D (ISO cubes, a training half of seed 1): each choice
finds new poses whose move from θ0 draws the wire beyond the encoder's range or brings a
link near the floor, and the 13th choice passes (48 rows left out, 0.5 s of CPU a choice);
at 4 nothing was written."""


def as_plan(rb: Robot, q_deg: np.ndarray, pp: PoolPlan, source: str) -> Plan:
    """Return θ0 and the chosen poses as a plan: the poses split over the steps in order."""
    order = rb.parameters
    empty = np.empty((0, rb.n_joints))
    chunks = np.array_split(q_deg[pp.rows], len(order))
    steps = tuple(Step(p, c, empty) for p, c in zip(order, chunks, strict=True))
    return Plan(q_deg[pp.theta0_row], tuple(order), steps, rb.name, None, source, joint_only=True)


def toured(rb: Robot, q_deg: np.ndarray, pp: PoolPlan) -> PoolPlan:
    """Return ``pp`` with each step's poses in the planner's visiting order over clear moves.

    The steps' poses as :func:`as_plan` splits them, each step ordered by
    :func:`~wirecal.solver.plan.tour.tour` (a step it cannot order keeps the chosen order:
    the pre-flight then names the move).
    """
    theta0 = q_deg[pp.theta0_row]
    p0 = tool_position(rb.nominal, np.radians(theta0)[None])[0]
    rows = []
    for chunk in np.array_split(pp.rows, len(rb.parameters)):
        vias = np.full((len(chunk), rb.n_joints), np.nan)
        order = tour(rb, rb.nominal, p0, theta0, q_deg[chunk], vias, PlanOptions())
        rows.append(chunk if order is None else chunk[order])
    return replace(pp, rows=np.concatenate(rows))


def problems(rb: Robot, plan: Plan) -> list[str]:
    """Return what the pre-flight of ``gen`` refuses in ``plan`` (empty: nothing)."""
    found: list[str] = []
    request = GenRequest()
    for check in (
        lambda: check_limits(rb, plan, request.margin_deg),
        lambda: check_wire_range(rb, plan, request.range_margin_mm),
        lambda: check_cell(rb, plan),
    ):
        try:
            check()
        except WirecalError as exc:
            found += exc.problems
    return found


def _unsafe(rb: Robot, q_deg: np.ndarray, pp: PoolPlan) -> list[int]:
    """Return the chosen rows the pre-flight refuses.

    Each alone (from θ0 and back); when none is, each whose move from the pose before it
    in its step is refused.
    """
    first, empty = rb.parameters[0], np.empty((0, rb.n_joints))
    theta0 = q_deg[pp.theta0_row]

    def refused(rows: list[int]) -> bool:
        step = Step(first, q_deg[rows], empty)
        return bool(problems(rb, Plan(theta0, (first,), (step,), rb.name)))

    alone = [int(r) for r in pp.rows if refused([r])]
    if alone:
        return alone
    chunks = np.array_split(pp.rows, len(rb.parameters))
    return [int(c[i]) for c in chunks for i in range(1, len(c)) if refused([c[i - 1], c[i]])]


def safe_plan(
    rb: Robot, q_deg: np.ndarray, n: int, opt: PlanOptions, source: str
) -> tuple[PoolPlan, Plan, int]:
    """Return the pool's choice, its plan and how many rows the pre-flight refused (docstring).

    Raises :class:`WirecalError` naming every problem when no safe choice is found.
    """
    lo, hi = rb.limits_deg(GenRequest().margin_deg)
    usable = np.flatnonzero(np.all((q_deg >= lo) & (q_deg <= hi), axis=1))
    refused = len(q_deg) - len(usable)
    if len(usable) == 0:
        raise WirecalError(
            f"{source}: nothing written: every one of the pool's {len(q_deg)} configurations is "
            f"within {GenRequest().margin_deg:g} deg of a joint or body limit of {rb.source}"
        )
    for _ in range(SAFETY_ROUNDS):
        found = plan_pool(rb, q_deg[usable], n, opt)
        pp = PoolPlan(
            int(usable[found.theta0_row]),
            usable[found.rows],
            found.names,
            found.anchor_mm,
            found.predicted_mm,
            found.theta0_tried,
            found.outside,
        )
        if len(pp.rows) < len(rb.parameters):
            raise WirecalError(
                f"{source}: nothing written: {len(pp.rows)} poses for the "
                f"{len(rb.parameters)} steps of {rb.source}'s [calibration] parameters: a plan "
                f"file needs a pose per step; give --points of at least {len(rb.parameters)}"
            )
        pp = toured(rb, q_deg, pp)
        unsafe = _unsafe(rb, q_deg, pp)
        if unsafe and len(unsafe) == len(pp.rows):  # every move refused: θ0 is the suspect
            unsafe.append(pp.theta0_row)
        if not unsafe:
            plan = as_plan(rb, q_deg, pp, source)
            if not (left := problems(rb, plan)):
                return pp, plan, refused
            raise WirecalError([*left, f"{source}: nothing written: {NOT_SAFE}"])
        usable = np.setdiff1d(usable, unsafe)
        refused += len(unsafe)
    raise WirecalError(
        f"{source}: after {SAFETY_ROUNDS} choices the pre-flight still refused poses "
        f"({refused} rows left out): nothing written: {NOT_SAFE}"
    )


NOT_SAFE = (
    "the pool's poses do not make a plan the pre-flight of 'gen' passes; give a pool of "
    "poses clear of the cell, or write the choice as CSV (-o CHOSEN.csv) to review it"
)
