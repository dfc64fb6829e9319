"""The payload step: some of the plan's points again with a known mass at the flange.

One wire tells a compliance c_j from the offset θ_j only through the change of the
gravity torque τ_j over the points (:mod:`~wirecal.solver.compliance`). A known mass
mounted at the flange changes τ_j at the same configurations by its own weight's torque,
which no geometric parameter can mimic, so a few points measured with it identify the
compliances far better than more points without it (issue 30: 12 points with 5 kg cut
the σ of c2/c3 1.6–3× against the same 12 without).

The step (:func:`payload_step`), when the robot file gives ``[calibration] payload_kg``:
the points of the plan that bring the most information about the listed compliances
with the mass on (a greedy Ds-optimal choice, the geometry estimated with them, as
:mod:`~wirecal.solver.plan.compliance` does without it), as many as
the robot time left allows (the designer's budget: the plan with the compliances' points
and this step at most :data:`~wirecal.solver.plan.design.MAX_TIME_RATIO` of the plan
without them), in a visiting order that keeps the
arm and the wire clear (:func:`~wirecal.solver.plan.tour.tour`). It is kept only when it
pays: each per cent of robot time it adds must cut the largest predicted σ of the
listed compliances by at least :data:`PAYS_PER_TIME` per cent. The operator's two stops
(mounting the mass after the step's zero reading at θ0, removing it before the closing
zero) are operator time, stated apart from the robot time.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from wirecal.solver.compliance import PRIOR_COMPLIANCE_URAD_PER_NM, compliance_observability
from wirecal.solver.kinematics import loaded, tool_position
from wirecal.solver.plan.calibration_plan import PAYLOAD_STEP, Plan, Step
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.predict import robot_time
from wirecal.solver.plan.tour import tour
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.verdict import READING_NOISE_MM

PAYS_PER_TIME = 1.0
"""Least cut of the largest predicted compliance σ (per cent) per per cent of robot time
the step adds, for the step to be kept."""

MAX_TRIES = 60
"""Candidates tried for the step (each its tour and time worked out): the best by gain
first; one too far for the time left, or without a clear tour, is passed over."""

MOUNT_STOPS = 2
"""The operator's stops the step adds: mounting the mass, removing it."""


def plan_sigmas(robot: Robot, plan: Plan, geometry: list[str]) -> dict[str, float]:
    """Return each listed compliance's σ (µrad/(N·m)) at ``plan``'s points, its mass on."""
    q, _, _ = plan.all_points()
    model = robot.nominal
    load = plan.point_load_kg()
    if np.any(load):
        step = plan.payload_step
        assert step is not None  # a load only in the payload step
        model = loaded(model, load, np.array(step.payload_com_mm))
    found = compliance_observability(
        model, q, plan.theta0_deg, geometry, robot.compliances, READING_NOISE_MM
    )
    return found.sigma_urad_per_nm


def payload_step(
    robot: Robot,
    plan: Plan,
    geometry: list[str],
    opt: PlanOptions,
    candidates_deg: tuple[np.ndarray, float],
) -> tuple[Plan, list[str]]:
    """Return ``plan`` with the payload step when it pays, and the header's lines.

    ``geometry``: the planned parameters, estimated with the compliances;
    ``candidates_deg``: the designer's screened candidates reached without a via point
    (clear of the arm, the cell and the wire from θ0), and the robot time (s) the step
    may add.
    """
    kg = robot.payload_kg
    assert kg is not None
    assert robot.payload_com_mm is not None
    com = np.asarray(robot.payload_com_mm, dtype=float)
    before = plan_sigmas(robot, plan, geometry)
    base_s = robot_time(robot, plan, opt.run)
    q, budget_s = candidates_deg
    picks = _choose(robot, plan, q, geometry, kg, com, budget_s, opt)
    step = Step(PAYLOAD_STEP, q[picks], np.zeros((0, plan.theta0_deg.size)), None, kg, tuple(com))
    with_step = replace(plan, steps=(*plan.steps, step)) if len(picks) else plan
    after = plan_sigmas(robot, with_step, geometry) if len(picks) else before
    added = robot_time(robot, with_step, opt.run) / base_s - 1.0
    cut = _cut(before, after)
    pays = len(picks) > 0 and cut >= PAYS_PER_TIME * added
    lines = _lines(kg, com, before, after, (len(picks), added, cut, pays), robot)
    return (with_step if pays else plan), lines


def _choose(
    robot: Robot,
    plan: Plan,
    q: np.ndarray,
    geometry: list[str],
    kg: float,
    com: np.ndarray,
    budget_s: float,
    opt: PlanOptions,
) -> list[int]:
    """Return the points (rows of ``q``) for the step: Ds-optimal, in visiting order.

    Greedy on log det of the compliances' information (the geometry estimated with
    them) with the mass on; a point is added when the step's tour (from θ0 and back)
    stays clear and within ``budget_s``, else the next best is tried
    (:data:`MAX_TRIES` in all).
    """
    names = [*geometry, *robot.compliances]
    theta0 = plan.theta0_deg
    s2 = READING_NOISE_MM**2
    unloaded = sensitivity(robot.nominal, plan.all_points()[0], theta0, names).psi
    model = loaded(robot.nominal, np.full(len(q), kg), com)
    x = sensitivity(model, q, theta0, names).psi
    prior = np.r_[
        np.full(len(geometry), opt.prior),
        np.full(len(robot.compliances), PRIOR_COMPLIANCE_URAD_PER_NM),
    ]
    info = np.diag(prior**-2.0) + unloaded.T @ unloaded / s2
    others = np.arange(len(geometry))
    chosen: list[int] = []
    order: list[int] = []
    tried = np.zeros(len(q), bool)
    for _ in range(MAX_TRIES):
        sig, sig_o = np.linalg.inv(info), np.linalg.inv(info[np.ix_(others, others)])
        xo = x[:, others]
        gain = np.log1p(np.einsum("nm,mk,nk->n", x, sig, x) / s2) - np.log1p(
            np.einsum("nm,mk,nk->n", xo, sig_o, xo) / s2
        )
        gain[tried] = -np.inf
        best = int(np.argmax(gain))
        if not np.isfinite(gain[best]):
            break
        tried[best] = True
        path = _tour(robot, theta0, q[[*chosen, best]], opt)
        if path is None or _step_time(robot, plan, q[[*chosen, best]][path], opt) > budget_s:
            continue  # too far for the time left, or no clear tour: the next best
        chosen.append(best)
        order = [chosen[i] for i in path]
        info = info + np.outer(x[best], x[best]) / s2
    return order


def _tour(robot: Robot, theta0: np.ndarray, pts: np.ndarray, opt: PlanOptions) -> list[int] | None:
    """Return the visiting order of ``pts`` from θ0 and back that keeps all clear, or None."""
    p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
    vias = np.full(pts.shape, np.nan)
    path = tour(robot, robot.nominal, p0, theta0, pts, vias, opt)
    return None if path is None else [int(i) for i in path]


def _step_time(robot: Robot, plan: Plan, pts: np.ndarray, opt: PlanOptions) -> float:
    """Return the robot time (s) a payload step of points ``pts`` adds to ``plan``."""
    none = np.zeros((0, pts.shape[1]))
    alone = Plan(plan.theta0_deg, (), (Step(PAYLOAD_STEP, pts, none),), robot=plan.robot)
    empty = Plan(plan.theta0_deg, (), (), robot=plan.robot)
    return robot_time(robot, alone, opt.run) - robot_time(robot, empty, opt.run)


def _cut(before: dict[str, float], after: dict[str, float]) -> float:
    """Return the relative cut of the largest σ over the compliances the step gives a σ.

    Compliances with no σ either way (no torque, or inseparable) are left out; one that
    has a σ only with the step is a full cut.
    """
    names = [n for n in after if np.isfinite(after[n])]
    if not names:
        return 0.0
    worst_b = max(before[n] for n in names)
    return 1.0 - max(after[n] for n in names) / worst_b if np.isfinite(worst_b) else 1.0


def _lines(
    kg: float,
    com: np.ndarray,
    before: dict[str, float],
    after: dict[str, float],
    figures: tuple[int, float, float, bool],
    robot: Robot,
) -> list[str]:
    """Return the header's lines: the step, and each compliance's σ with and without it.

    ``figures``: the step's points, the robot time it adds (share), the σ cut, kept.
    """
    count, added, cut, pays = figures
    verdict = "added" if pays else "not added: it does not pay"
    head = (
        f"Payload step ({kg:g} kg at {np.round(com, 1).tolist()} mm from the flange, rated "
        f"payload {robot.rated_payload_kg:g} kg): {count} points, {verdict} (kept when each "
        f"% of robot time it adds cuts the largest compliance sigma by >= {PAYS_PER_TIME:g} %: "
        f"+{100 * added:.1f} % robot time, sigma cut {100 * cut:.0f} %); plus the operator's "
        f"{MOUNT_STOPS} stops (mount the mass after the step's zero at theta0, remove it "
        "before the closing zero), not robot time."
    )
    rows = [
        f"compliance {n}: predicted sigma {after[n]:.3g} urad/Nm with the payload step, "
        f"{before[n]:.3g} without it"
        for n in before
    ]
    return [head, *rows]
