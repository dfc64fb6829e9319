"""The planner's design around one θ0 (:func:`design_at`) and the designed plan's figures.

Candidates screened (:mod:`~wirecal.solver.plan.candidates`), the unidentifiable
parameters set aside, the steps in the order of §3.4 (:mod:`~wirecal.solver.plan.steps`),
the joint method's further points (:mod:`~wirecal.solver.plan.joint`), each step's tour
(:mod:`~wirecal.solver.plan.tour`) and the predictions
(:mod:`~wirecal.solver.plan.predict`); :class:`Design` holds them and writes the plan
file's header.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import describe
from wirecal.solver.identifiability import analyse
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.calibration_plan import Plan, Step
from wirecal.solver.plan.candidates import Screened, no_usable_error
from wirecal.solver.plan.compliance import add_compliance_points
from wirecal.solver.plan.exit import largest_exit_deg
from wirecal.solver.plan.joint import joint_choice
from wirecal.solver.plan.options import Method, PlanOptions, Progress
from wirecal.solver.plan.payload import payload_step, plan_sigmas
from wirecal.solver.plan.predict import predicted_accuracy, robot_time
from wirecal.solver.plan.steps import StepPool, step_by_step, step_error
from wirecal.solver.plan.tour import tour
from wirecal.solver.robot import Robot, near_limits
from wirecal.solver.sensitivity import sensitivity


@dataclass
class StepDesign:
    """One designed step and its figures of merit."""

    parameter: str
    points_deg: np.ndarray
    strength: float  # RMS |Ψ_j| of the points
    leak_ours: float  # variance factor with our choice
    leak_paper: float | None  # … with the paper's criterion (largest |Ψ_j|); None: joint
    via_deg: np.ndarray  # (0 or 1, n): passed on the way to the first point


@dataclass
class Design:
    """A designed plan with its per-step figures, exclusions and predictions."""

    plan: Plan
    steps: list[StepDesign]
    excluded: dict[str, str] = field(default_factory=dict)  # parameter → reason
    predicted: dict[str, float] = field(default_factory=dict)
    robot_time_s: float = 0.0
    exit_line: str = ""  # the wire exit and the plan's largest exit angle, in words
    cell_line: str = ""  # the cell the plan keeps clear of, in words
    method: Method = "stepwise"  # the estimator the points were chosen for
    theta0_tried: int = 1  # θ0s designed to find this plan (1: the θ0 given)
    search_line: str = ""  # the θ0 search in words, when it went past the first θ0s
    unidentifiable: tuple[str, ...] = ()  # excluded as unobservable or redundant
    compliance_lines: tuple[str, ...] = ()  # the compliances' predicted σ, in words
    compliance_sigma: dict[str, float] = field(default_factory=dict)  # µrad/(N·m), predicted

    def isolation_failed(self) -> list[str]:
        """Return the parameters excluded as not isolated (another θ0 may isolate them)."""
        return [n for n in self.excluded if n not in self.unidentifiable]

    def header(self) -> str:
        """Return the plan file's header comment: the design's figures in words."""
        lines = [
            "Designed by 'wirecal plan' (Boschetti & Sinico's method, see the README).",
            f"theta0 {np.round(self.plan.theta0_deg, 2).tolist()} deg; order "
            + " ".join(self.plan.order)
            + ".",
            *([self.search_line] if self.search_line else []),
            "Predicted tool-point error (sigma 0.01 mm, mean over the workspace"
            + (
                f"; the {len(self.excluded)} parameters not planned at their prior"
                if self.excluded
                else ""
            )
            + f"): joint {self.predicted['joint']:.4f} mm, step-by-step "
            f"{self.predicted['stepwise']:.4f} mm.",
            f"Estimated robot time {self.robot_time_s / 60:.1f} min "
            f"({self.plan.n_points} points, "
            f"{sum(len(s.via_deg) for s in self.plan.steps)} via points).",
            self.exit_line,
            self.cell_line,
        ]
        if self.method == "joint":
            lines.append(
                "Points chosen for the joint method (least tool-point variance over the "
                "workspace per second of robot time), each step's points isolating its "
                "parameter so the step-by-step method runs too. Per step: its points, "
                "RMS |Psi| (mm/deg or mm/mm), the noise gain (sigma of the estimate per "
                "mm of reading noise) and the step-by-step expected squared error."
            )
        else:
            lines.append(
                "Per step: RMS |Psi| of its points (mm/deg or mm/mm), the noise gain "
                "(sigma of the estimate per mm of reading noise) and the leak-aware "
                "choice against the paper's."
            )
        for j, s in enumerate(self.steps, 1):
            gain = 1 / (s.strength * np.sqrt(len(s.points_deg)))
            head = f"step {j} {s.parameter}: "
            if s.leak_paper is None:
                lines.append(
                    f"{head}{len(s.points_deg)} points, RMS |Psi| {s.strength:.2f}, noise "
                    f"gain {gain:.2f}; expected squared error with noise and leaks "
                    f"{s.leak_ours:.3g}"
                )
                continue
            cut = 100 * (1 - s.leak_ours / s.leak_paper) if s.leak_paper > 0 else 0.0
            lines.append(
                f"{head}RMS |Psi| {s.strength:.2f}, noise gain "
                f"{gain:.2f}; expected squared error with noise and leaks "
                f"{s.leak_ours:.3g} ({cut:.0f} % below the largest-|Psi| choice's "
                f"{s.leak_paper:.3g})"
            )
        for name, why in self.excluded.items():
            lines.append(f"not planned: {name}: {why}")
        lines += self.compliance_lines
        return "\n".join(lines)


def check_theta0(robot: Robot, theta0: np.ndarray, opt: PlanOptions) -> None:
    """Raise when a joint of θ0 is within the margin of its body limits, or θ0 collides."""
    lo, hi = robot.limits_deg()
    inner_lo, inner_hi = robot.limits_deg(opt.margin_deg)
    for j in np.flatnonzero((theta0 < inner_lo) | (theta0 > inner_hi)):
        raise WirecalError(
            f"theta0: joint {j + 1} = {theta0[j]:g} deg is "
            f"{near_limits(theta0[j], lo[j], hi[j], opt.margin_deg)} its limits [{lo[j]:g}, "
            f"{hi[j]:g}] (the joint limits, narrowed by [cell] body limits)"
        )
    p0 = tool_position(robot.nominal, np.radians(theta0)[None])[0]
    gaps = robot.cell_gaps(theta0, p0)
    if gaps.smallest()[0] < 0:
        raise WirecalError(f"theta0 {theta0.tolist()}: collides (cell): {gaps.cause(0)}")


def _unidentifiable(model, q: np.ndarray, theta0: np.ndarray, names: list[str]) -> dict[str, str]:
    """Return the parameters no plan can identify (unobservable, or redundant), with why."""
    excluded: dict[str, str] = {}
    ident = analyse(model, q, theta0, names)
    for name in ident.unobservable:
        excluded[name] = (
            "unobservable: it moves every point and the encoder alike"
            if name in ("th1", "d1", "a0", "al0")
            else "unobservable from any candidate configuration"
        )
    for combo in ident.combinations:
        last = combo[-1][0]
        excluded[last] = (
            "redundant with "
            + ", ".join(n for n, _ in combo[:-1])
            + ": no wire length separates them; keep one"
        )
    return excluded


MAX_TIME_RATIO = 1.24
"""Robot time of a plan with the compliances' points and the payload step over the same
plan without either (issue 30: at most 1.25×; the payload step takes what the
compliance points leave, :mod:`~wirecal.solver.plan.payload`)."""


def design_at(
    robot: Robot, theta0: np.ndarray, opt: PlanOptions, progress: Progress | None = None
) -> Design:
    """Design a plan around a given θ0 (see :func:`~wirecal.solver.plan.planner.design`).

    Step by step (paper §3.4), each step's points chosen by the leak-aware greedy: all
    ``points_per_step`` of them for the stepwise method, the first ``min_points`` for the
    joint method, whose remaining points
    :func:`~wirecal.solver.plan.joint.joint_choice` then adds over all steps
    (:func:`design_steps`, then :func:`finish`).
    """
    return finish(design_steps(robot, theta0, opt, progress), progress)


@dataclass
class Steps:
    """A design around θ0 up to its steps' first points (:func:`design_steps`).

    ``rank``: the plan of those points ranked as :func:`score` ranks a finished plan
    (parameters unplanned, then the predicted errors): the θ0 search finishes the θ0s
    that rank first (:func:`~wirecal.solver.plan.planner.design`).
    """

    robot: Robot
    theta0: np.ndarray
    opt: PlanOptions
    cands: Screened
    psi: np.ndarray  # the candidates' Ψ, columns ``remaining``
    remaining: list[str]  # the parameters but the unidentifiable
    excluded: dict[str, str]
    unidentifiable: tuple[str, ...]
    pools: list[StepPool]
    rank: tuple[int, float] = (0, 0.0)


def score(excluded: int, predicted: dict[str, float]) -> tuple[int, float]:
    """Return a plan's rank among θ0s: parameters unplanned, then the predicted errors."""
    return (excluded, predicted["stepwise"] + predicted["joint"] * 5)


def design_steps(
    robot: Robot, theta0: np.ndarray, opt: PlanOptions, progress: Progress | None = None
) -> Steps:
    """Design around θ0 up to the steps' first points and rank them (:class:`Steps`).

    The candidates screened, the unidentifiable parameters set aside, the order of §3.4
    and each step's first points (:func:`~wirecal.solver.plan.steps.step_by_step`).
    """
    tick = progress or (lambda f: None)
    model = robot.nominal
    check_theta0(robot, theta0, opt)
    cands = Screened(robot, theta0, opt)
    if len(cands.q) < opt.points_per_step:
        raise no_usable_error(robot, theta0, opt)
    q_all = cands.q
    tick(0.5)
    names = list(robot.parameters)
    excluded = _unidentifiable(model, q_all[:: max(1, len(q_all) // 3000)], theta0, names)
    unidentifiable = tuple(excluded)
    remaining = [n for n in names if n not in excluded]
    psi = sensitivity(model, q_all, theta0, remaining).psi
    pools = step_by_step(robot, theta0, cands, psi, remaining, excluded, opt, tick)
    s = Steps(robot, theta0, opt, cands, psi, remaining, excluded, unidentifiable, pools)
    first = Plan(
        theta0,
        tuple(p.parameter for p in pools),
        tuple(Step(p.parameter, q_all[p.iso[p.picks]], q_all[:0]) for p in pools),
    )
    s.rank = score(len(excluded), predicted_accuracy(robot, first, unplanned=tuple(excluded)))
    return s


def finish(s: Steps, progress: Progress | None = None) -> Design:
    """Return the plan of a design up to its steps (:func:`design_steps`), finished.

    The joint method's further points, each step's tour, the compliances' points and a
    payload step when the robot file asks for them, and the predictions.
    """
    robot, theta0, opt, cands, pools = s.robot, s.theta0, s.opt, s.cands, s.pools
    q_all, via_all, remaining, excluded = cands.q, cands.via, s.remaining, s.excluded
    p0 = cands.p0
    if opt.method == "joint":
        joint_choice(robot, theta0, q_all, via_all, s.psi, remaining, pools, opt)
    plain_s = _plain_time(robot, p0, theta0, (q_all, via_all), pools, opt)
    compliance = (
        add_compliance_points(robot, theta0, cands, remaining, pools, opt)
        if robot.compliances
        else ([], {})
    )
    steps = [
        _step_design(robot, p0, theta0, q_all, via_all, k, pool, opt)
        for k, pool in enumerate(pools)
    ]
    plan = Plan(
        theta0,
        tuple(p.parameter for p in pools),
        tuple(Step(sd.parameter, sd.points_deg, sd.via_deg) for sd in steps),
        robot=robot.name,
    )
    lines, sigma = compliance
    if plain_s is not None:
        budget_s = MAX_TIME_RATIO * plain_s - robot_time(robot, plan, opt.run)
        usable = cands.usable(np.ones(len(q_all), bool))  # the step's pool: all screened
        direct = np.vstack([plan.all_points()[0], q_all[usable & np.isnan(via_all[:, 0])]])
        plan, more = payload_step(robot, plan, remaining, opt, (direct, budget_s))
        lines, sigma = [*lines, *more], plan_sigmas(robot, plan, remaining)
    d = Design(plan, steps, excluded, method=opt.method, unidentifiable=s.unidentifiable)
    d.compliance_lines, d.compliance_sigma = tuple(lines), sigma
    d.predicted = predicted_accuracy(robot, plan, unplanned=tuple(excluded))
    d.robot_time_s = robot_time(robot, plan, opt.run)
    d.exit_line = exit_line(robot, plan)
    d.cell_line = cell_line(robot)
    (progress or (lambda f: None))(1.0)
    return d


def _plain_time(
    robot: Robot,
    p0: np.ndarray,
    theta0: np.ndarray,
    candidates_: tuple[np.ndarray, np.ndarray],
    pools: list[StepPool],
    opt: PlanOptions,
) -> float | None:
    """Return the robot time (s) of the plan without compliance points, for a payload step.

    None without a payload step's mass: the time is only its budget's scale
    (:data:`MAX_TIME_RATIO`). The steps are toured here as :func:`design_at` tours them.
    """
    if robot.payload_kg is None or not robot.compliances:
        return None
    q_all, via_all = candidates_
    steps = [
        _step_design(robot, p0, theta0, q_all, via_all, k, pool, opt)
        for k, pool in enumerate(pools)
    ]
    order = tuple(p.parameter for p in pools)
    plain = Plan(theta0, order, tuple(Step(s.parameter, s.points_deg, s.via_deg) for s in steps))
    return robot_time(robot, plain, opt.run)


def _step_design(
    robot: Robot,
    p0: np.ndarray,
    theta0: np.ndarray,
    q_all: np.ndarray,
    via_all: np.ndarray,
    k: int,
    pool: StepPool,
    opt: PlanOptions,
) -> StepDesign:
    """Return step k's design: its points in visiting order (:func:`tour`), and figures.

    Puts ``pool.picks`` in the visiting order; raises when no order keeps the wire clear.
    """
    pts = pool.iso[pool.picks]
    clear = pool.links.between(pool.picks)
    path = tour(robot, robot.nominal, p0, theta0, q_all[pts], via_all[pts], opt, clear)
    if path is None:
        raise WirecalError(
            f"{robot.source}: step {k + 1} ({pool.parameter}): no visiting "
            "order keeps the wire clear of the links; try another "
            "--seed or --theta0, or check the link radii"
        )
    pool.picks = [pool.picks[i] for i in path]
    first_via = via_all[pool.iso[pool.picks[0]]]
    return StepDesign(
        pool.parameter,
        q_all[pts[path]],
        float(np.sqrt(np.mean(pool.pj[pool.picks] ** 2))),
        step_error(
            pool.pj[pool.picks], pool.pprev[pool.picks], pool.cov_prev, pool.pnext[pool.picks], opt
        ),
        pool.leak_paper,
        first_via[None] if not np.isnan(first_via[0]) else np.zeros((0, len(theta0))),
    )


def exit_line(robot: Robot, plan: Plan) -> str:
    """Return the wire exit in words with the plan's largest exit angle (plan header)."""
    largest = largest_exit_deg(robot, plan)
    text = f"Wire exit: {describe(robot.encoder.exit)}"
    return text + ("." if largest is None else f"; largest exit angle {largest:.1f} deg.")


def cell_line(robot: Robot) -> str:
    """Return the robot file's cell in words (plan header): what every move keeps clear of."""
    c = robot.cell
    lo, hi = robot.limits_deg()
    narrowed = np.flatnonzero((lo > robot.joint_min_deg) | (hi < robot.joint_max_deg))
    body = (
        "body limits on joint " + ", ".join(str(j + 1) for j in narrowed)
        if narrowed.size
        else "no body limits"
    )
    return (
        f"Cell: floor at z = {c.floor_z_mm:g} mm of frame 0, margin {c.margin_mm:g} mm, "
        f"{len(c.boxes)} boxes, {len(c.half_spaces)} half-spaces, "
        f"{'an' if c.housing else 'no'} encoder housing, {body}: theta0, every point and "
        "every move keep the arm clear of itself and the cell (docs/cell.md)."
    )
