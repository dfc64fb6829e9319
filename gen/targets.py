"""What every controller language's programs share: joint targets and the run's steps.

A generated program moves to literal joint targets only (checked before rendering by
:func:`wirecal.gen.preflight.preflight`); :func:`run_steps` lists the measurement run's
steps, via points and calibration points in plan order, each target written by the
backend's own literal function.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from typing import TypeVar, cast

import numpy as np

from wirecal.solver.plan.calibration_plan import PAYLOAD_STEP, Plan
from wirecal.solver.robot import Robot

T = TypeVar("T")


def joint_literal(x: float, decimals: int = 4) -> str:
    """Write a joint angle as the operator reads it: up to 4 decimals, no trailing zeros."""
    s = f"{x:.{decimals}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def name_problems(robot: Robot, forbidden: str, strings: str) -> list[str]:
    """Return the problem of a robot name the programs cannot write in a string literal.

    ``forbidden``: the characters a string literal of the language cannot hold beside the
    non-printable ones; ``strings``: what the message calls them ("a V+ string").
    """
    if all(32 <= ord(ch) <= 126 and ch not in forbidden for ch in robot.name):
        return []
    shown = " or ".join(repr(c) for c in forbidden)
    return [
        f"{robot.source}: name {robot.name!r}: the programs write it in {strings}: printable "
        f"ASCII without {shown}; rename the robot"
    ]


def joint_target(q_deg: np.ndarray, target: Callable[[np.ndarray], str]) -> dict[str, str]:
    """Return a target as the language writes it and as the operator reads it (deg)."""
    return {"target": target(q_deg), "deg": ", ".join(joint_literal(x) for x in q_deg)}


def run_steps(
    plan: Plan, first: Sequence[int] | np.ndarray, target: Callable[[np.ndarray], str]
) -> list[dict[str, object]]:
    """Return the run's steps for a template: number, parameter, vias and points.

    ``first`` is each step's first point (1-based, :attr:`Tables.first`); ``target``
    writes a joint target (deg) as the language's literal (:func:`joint_target`).
    """
    steps: list[dict[str, object]] = []
    for j, s in enumerate(plan.steps, 1):
        steps.append(
            {
                "number": j,
                "parameter": s.parameter,
                "count": len(s.points_deg),
                "payload_kg": f"{s.payload_kg:g}" if s.parameter == PAYLOAD_STEP else None,
                "vias": [joint_target(v, target) for v in s.via_deg],
                "points": [
                    {"index": i, "global": int(first[j - 1]) + i - 1, **joint_target(p, target)}
                    for i, p in enumerate(s.points_deg, 1)
                ],
            }
        )
    return steps


def tool_mass_problems(robot: Robot, declares: str) -> list[str]:
    """Return the problem of a robot file that gives the tool no mass, for programs that declare it.

    ``declares``: how the programs tell the controller the tool's mass. The flange always
    carries the wire's fixture, so 0 kg (``[gravity]`` or its ``payload_mass_kg`` left out,
    or written 0) would tell the controller less than the truth, the unsafe direction; no
    default is guessed. A mass below 0.5 mg (0 to 6 decimals, as the programs write kg) is
    no mass either.
    """
    if robot.masses is not None and round(float(robot.masses.payload_mass_kg), 6) != 0:
        return []
    return [
        f"{robot.source}: [gravity] payload_mass_kg: no tool mass; {declares}, and the flange "
        "carries at least the wire's fixture: give the mass (kg) of everything mounted on the "
        "flange (tool, fixture, the wire's attachment) and its centre, payload_com_mm (mm, "
        "flange frame), in [gravity]"
    ]


def payload_context(robot: Robot, plan: Plan) -> dict[str, object] | None:
    """Return the payload step for a template (None without one): mass, centre, step, points.

    ``kg`` and ``com_mm`` as written in the programs (the plan's numbers, shortest form),
    ``step`` its number (the last), ``points_before`` the points of the parameters' steps:
    the controller solver's, which has no gravity model and leaves the step's points out.
    What the plan's mass was checked against (:mod:`wirecal.formats.plan_file`):
    ``rated_kg``, the robot file's ``[calibration] rated_payload_kg``; ``tool_kg``, the tool
    it declares (``[gravity] payload_mass_kg``); ``spare_kg``, what the rating leaves for
    the tool beyond the step's mass.
    """
    step, loads = plan.payload_step, flange_loads(robot, plan)
    if step is None or loads is None or robot.rated_payload_kg is None:
        return None
    tool_kg = loads[1][0]
    return {
        "kg": f"{step.payload_kg:g}",
        "com_mm": [f"{x:g}" for x in step.payload_com_mm],
        "step": len(plan.steps),
        "points_before": plan.n_points - len(step.points_deg),
        "rated_kg": f"{robot.rated_payload_kg:g}",
        "tool_kg": f"{tool_kg:g}",
        "spare_kg": f"{robot.rated_payload_kg - step.payload_kg:g}",
    }


def stepwise_solver(plan: Plan, asked: bool) -> bool:
    """Return whether the programs end with the controller's step-by-step solver.

    As ``asked``, but never for a payload step (its points need the gravity model only
    ``wirecal solve`` has) nor for a plan written from a pool (``joint_only``: its steps
    isolate no parameter, so the stepwise solver does not apply; ``gen`` says so). The
    V+ module keeps its solver for a payload step (it leaves the step's points out).
    """
    return asked and plan.payload_step is None and not plan.joint_only


Load = tuple[float, np.ndarray]
"""A load at the flange: its mass (kg) and centre (mm, in the flange frame)."""


def flange_loads(robot: Robot, plan: Plan) -> tuple[Load, Load] | None:
    """Return the payload step's whole load at the flange and the tool's alone (None without).

    The tool's is the robot file's ``[gravity] payload_mass_kg`` at its ``payload_com_mm``
    (0 kg without ``[gravity]``); the whole load is the tool's with the step's mass, at
    their common centre of mass.
    """
    step = plan.payload_step
    if step is None:
        return None
    masses = robot.masses
    tool_kg = 0.0 if masses is None else float(masses.payload_mass_kg)
    tool_cog = np.zeros(3) if masses is None else np.asarray(masses.payload_com_mm, dtype=float)
    total = tool_kg + step.payload_kg
    cog = (tool_kg * tool_cog + step.payload_kg * np.asarray(step.payload_com_mm)) / total
    return (total, cog), (tool_kg, tool_cog)


def give_move_speeds(steps: list[dict[str, object]], speeds: Iterable[T], key: str) -> T:
    """Give each move of ``steps`` its value of ``speeds``; return the closing move's.

    ``speeds``: one value per move in the run's order (:func:`run_steps`'s steps: per
    step θ0, its vias, its points; last θ0), as
    :func:`~wirecal.solver.run_parameters.run_timeline` lists the SPEEDs the wire allows.
    A step's move to θ0 gets ``"zero_" + key``, each via and point ``key``.
    """
    values = iter(speeds)
    for step in steps:
        step["zero_" + key] = next(values)
        for move in [*cast(list, step["vias"]), *cast(list, step["points"])]:
            move[key] = next(values)
    return next(values)
