"""The duties every language's generation has, whatever it renders: one pre-flight, one check after.

:func:`preflight` refuses, before anything is rendered, a plan the robot must not run: a
target within the margin of a joint limit or of a body limit of ``[cell]``
(:func:`check_limits`), a wire length beyond the encoder's range
(:func:`~wirecal.solver.wire_range.check_wire_range`), a move into the arm itself, the
floor or a keep-out volume (:func:`~wirecal.solver.cell.check.check_cell`), a declared
controller software of a line the language does not know (:func:`check_software`).
:func:`output_problems` runs the language's own checker over what was rendered, against
the declared software. :class:`~wirecal.gen.backends.Generator` calls both around a
language's rendering; a language cannot skip either.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from wirecal.gen.request import GenRequest
from wirecal.gen.targets import joint_literal
from wirecal.lang.base import Language
from wirecal.solver.cell.check import check_cell
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot, near_limits
from wirecal.solver.wire_range import check_wire_range, run_samples


def preflight(robot: Robot, plan: Plan, request: GenRequest, lang: Language) -> None:
    """Refuse, naming every broken rule, a plan the generated programs must not move through."""
    problems: list[str] = []
    samples = run_samples(robot, plan)  # the moves' samples and frames, for both checks
    for check in (
        lambda: check_limits(robot, plan, request.margin_deg),
        lambda: check_wire_range(robot, plan, request.range_margin_mm, samples=samples),
        lambda: check_cell(robot, plan, samples),
        lambda: check_software(robot, lang),
    ):
        try:
            check()
        except WirecalError as exc:
            problems += exc.problems
    if problems:
        raise WirecalError(problems)


def check_limits(robot: Robot, plan: Plan, margin_deg: float) -> None:
    """Refuse motion to any configuration within ``margin_deg`` of a joint or body limit.

    The joint limits are the robot file's (what the controller enforces); the body limits
    are ``[cell] body_min_deg``/``body_max_deg`` (joint ranges that keep the arm out of
    itself), where declared.
    """
    lo, hi = robot.limits_deg(margin_deg, body=False)
    body_lo, body_hi = robot.limits_deg(margin_deg, body=True)
    problems = []

    def check(q: np.ndarray, where: str) -> None:
        for j in np.flatnonzero((q < lo) | (q > hi)):
            lo_j, hi_j = robot.joint_min_deg[j], robot.joint_max_deg[j]
            problems.append(
                f"{plan.source}: {where}: joint {j + 1} = {joint_literal(q[j])} deg is "
                f"{near_limits(q[j], lo_j, hi_j, margin_deg)} its limits [{lo_j:g}, "
                f"{hi_j:g}]; move the point or lower --margin"
            )
        inside = (q >= lo) & (q <= hi)
        for j in np.flatnonzero(inside & ((q < body_lo) | (q > body_hi))):
            lo_j, hi_j = body_lo[j] - margin_deg, body_hi[j] + margin_deg
            problems.append(
                f"{plan.source}: {where}: joint {j + 1} = {joint_literal(q[j])} deg is "
                f"{near_limits(q[j], lo_j, hi_j, margin_deg)} its body limits [{lo_j:g}, "
                f"{hi_j:g}] ({robot.source} [cell]: the arm would fold into itself); move the "
                "point or lower --margin"
            )

    check(plan.theta0_deg, "theta0_deg")
    for j, s in enumerate(plan.steps, 1):
        for i, q in enumerate(s.via_deg, 1):
            check(q, f"step {j} ({s.parameter}) via point {i}")
        for i, q in enumerate(s.points_deg, 1):
            check(q, f"step {j} ({s.parameter}) point {i}")
    if problems:
        raise WirecalError(problems)


def check_software(robot: Robot, lang: Language) -> None:
    """Refuse a robot of another language, or declared software of a line the language lacks.

    The lines are the language's declared capabilities
    (:attr:`~wirecal.lang.base.Capabilities.software_lines`; none: not versioned).
    """
    controller = robot.controller
    if controller.language != lang.key:
        raise WirecalError(
            f"{robot.source}: [controller] language is {controller.language!r}, not "
            f"{lang.key!r}: the {lang.title} generator does not write its programs"
        )
    software = controller.software
    if software is not None and not lang.knows_software(software):
        raise WirecalError(
            f'{robot.source}: controller.software = "{software}": the {lang.title} programs '
            f"are written for {lang.software_lines_text()}"
        )


def output_problems(robot: Robot, programs: dict[str, str], lang: Language) -> list[str]:
    """Return the language's own checker's problems with the rendered programs.

    Checked against the robot file's declared controller software; a program checked
    before (the same text, name and software) is not checked again.
    """
    software = robot.controller.software
    return [p for name, text in programs.items() for p in _lint(lang, text, name, software)]


@lru_cache(maxsize=16)
def _lint(lang: Language, text: str, name: str, software: str | None) -> tuple[str, ...]:
    """Return ``lang``'s checker's problems with one program (remembered: a checker is pure)."""
    return tuple(lang.lint(text, name, software))
