"""Calibration plan files (TOML): read, validate against a robot, and write.

Format (joint angles in degrees)::

    theta0_deg = [0, -90, 210, -90, 0, -90]      # encoder mounted here (wire length 0)
    order = ["th6", "d6", ...]                   # identification order, one step each
    [[step]]
    parameter = "th6"
    points_deg = [[0, -90, 210, -90, -26, -180], ...]
    via_deg = [[...], ...]                       # optional: passed (blended) from θ0 to
                                                 # the first point, in this order
    omega = 5.0                                  # optional: bound Ω_j (deg or mm)
"""

from __future__ import annotations

import difflib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.distance import wire_lengths
from wirecal.solver.errors import Problems
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.plan import Plan, Step
from wirecal.solver.robot import Robot

_TOP_KEYS = ("theta0_deg", "order", "step", "robot", "description")


_STEP_KEYS = ("parameter", "points_deg", "via_deg", "omega")


def load_plan(path: str | Path, robot: Robot) -> Plan:
    """Read and validate a plan against a robot; raise :class:`WirecalError` listing problems."""
    return plan_from_dict(read_toml(path, "plan file"), robot, str(path))


def plan_from_dict(data: dict[str, Any], robot: Robot, source: str = "<plan>") -> Plan:
    pr = Problems(source)
    n = robot.n_joints
    for key in data:
        if key not in _TOP_KEYS:
            hint = difflib.get_close_matches(key, _TOP_KEYS, n=1)
            pr.add(key, "unknown key" + (f" (did you mean {hint[0]!r}?)" if hint else ""))
    for key in ("theta0_deg", "order", "step"):
        if key not in data:
            pr.add(key, "is missing")

    theta0 = _joints(data.get("theta0_deg"), "theta0_deg", n, pr) if "theta0_deg" in data else None
    if theta0 is not None:
        _check_limits(theta0[None], robot, "theta0_deg", pr)

    plan_robot = data.get("robot")
    if plan_robot is not None and plan_robot != robot.name:
        pr.add(
            "robot",
            f"plan is for {plan_robot!r} but the robot file describes "
            f"{robot.name!r}; use the matching robot file",
        )

    order = data.get("order", [])
    if not isinstance(order, list) or not all(isinstance(x, str) for x in order):
        pr.add("order", "must be a list of parameter names")
        order = []
    for name in order:
        if name not in robot.parameters:
            try:
                P.parse(name, n)
                pr.add(
                    "order",
                    f"{name!r} is not in the robot file's [calibration] parameters "
                    f"{list(robot.parameters)}",
                )
            except ValueError as exc:
                pr.add("order", str(exc))
    if len(set(order)) != len(order):
        pr.add("order", "lists a parameter twice")

    raw_steps = data.get("step", [])
    if not isinstance(raw_steps, list):
        pr.add("step", "must be an array of tables [[step]]")
        raw_steps = []
    steps: list[Step] = []
    for j, raw in enumerate(raw_steps, 1):
        where = f"step[{j}]"
        if not isinstance(raw, dict):
            pr.add(where, "must be a table")
            continue
        for key in raw:
            if key not in _STEP_KEYS:
                hint = difflib.get_close_matches(key, _STEP_KEYS, n=1)
                pr.add(
                    f"{where}.{key}",
                    "unknown key" + (f" (did you mean {hint[0]!r}?)" if hint else ""),
                )
        param = raw.get("parameter")
        if not isinstance(param, str):
            pr.add(f"{where}.parameter", "is missing or not a name")
        elif j <= len(order) and param != order[j - 1]:
            pr.add(
                f"{where}.parameter",
                f"is {param!r} but order[{j}] is {order[j - 1]!r}; steps must follow the order",
            )
        points = _rows(raw.get("points_deg"), f"{where}.points_deg", n, pr, required=True)
        via = _rows(raw.get("via_deg", []), f"{where}.via_deg", n, pr, required=False)
        if points is not None:
            _check_limits(points, robot, f"{where}.points_deg", pr)
            if theta0 is not None:
                _check_wire(points, theta0, robot, f"{where}.points_deg", pr)
        if via is not None:
            _check_limits(via, robot, f"{where}.via_deg", pr)
        omega = raw.get("omega")
        if omega is not None and (
            not isinstance(omega, int | float)
            or isinstance(omega, bool)
            or not math.isfinite(omega)
            or omega <= 0
        ):
            pr.add(f"{where}.omega", f"is {omega!r}; give a positive bound (deg or mm)")
        if isinstance(param, str) and points is not None and via is not None:
            steps.append(
                Step(param, points, via, float(omega) if isinstance(omega, int | float) else None)
            )
    if raw_steps and len(raw_steps) != len(order):
        pr.add(
            "step",
            f"has {len(raw_steps)} step(s) but order names {len(order)} "
            "parameter(s); give one [[step]] per parameter",
        )
    pr.raise_if_any()
    return Plan(
        theta0_deg=theta0,
        order=tuple(order),
        steps=tuple(steps),
        robot=plan_robot,
        description=data.get("description"),
        source=source,
    )


def _joints(x: Any, where: str, n: int, pr: Problems) -> np.ndarray | None:
    if (
        not isinstance(x, list)
        or len(x) != n
        or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in x
        )
    ):
        pr.add(where, f"must be {n} finite joint angles in degrees")
        return None
    return np.asarray(x, dtype=float)


def _rows(x: Any, where: str, n: int, pr: Problems, required: bool) -> np.ndarray | None:
    if x is None:
        pr.add(where, "is missing")
        return None
    if not isinstance(x, list) or (required and not x):
        pr.add(where, f"must be a {'non-empty ' if required else ''}list of {n}-vectors")
        return None
    rows = []
    for i, row in enumerate(x, 1):
        r = _joints(row, f"{where}[{i}]", n, pr)
        if r is None:
            return None
        rows.append(r)
    return np.asarray(rows, dtype=float).reshape(-1, n)


def _check_limits(q: np.ndarray, robot: Robot, where: str, pr: Problems) -> None:
    lo, hi = robot.joint_min_deg, robot.joint_max_deg
    for i, row in enumerate(q, 1):
        for j in np.flatnonzero((row < lo) | (row > hi)):
            label = where if q.shape[0] == 1 and where == "theta0_deg" else f"{where}[{i}]"
            pr.add(
                label, f"joint {j + 1} = {row[j]:g} deg is beyond its limits [{lo[j]:g}, {hi[j]:g}]"
            )


MIN_WIRE_MM = 1.0
"""Shortest wire length a plan point may have: at θ0 itself the wire has no direction, so
its derivatives (Ψ, the Jacobian) are undefined."""


def _check_wire(q: np.ndarray, theta0: np.ndarray, robot: Robot, where: str, pr: Problems) -> None:
    d = wire_lengths(robot.nominal, np.radians(q), np.radians(theta0))
    for i in np.flatnonzero(~(d >= MIN_WIRE_MM)):
        pr.add(
            f"{where}[{i + 1}]",
            f"the wire length there is {d[i]:.3g} mm (below {MIN_WIRE_MM:g} mm): the point "
            "(nearly) coincides with θ0, where the wire has no direction; move or remove it",
        )


def plan_to_toml(plan: Plan, header: str = "") -> str:
    """Serialise a plan in the canonical file layout (numbers as given, one point per line)."""

    def vec(v: np.ndarray) -> str:
        return "[" + ", ".join(_short(x) for x in v) + "]"

    lines = [f"# {h}" for h in header.splitlines()] if header else []
    if plan.robot:
        lines.append(f"robot = {json.dumps(plan.robot, ensure_ascii=False)}")
    if plan.description:
        lines.append(f"description = {json.dumps(plan.description, ensure_ascii=False)}")
    lines.append(f"theta0_deg = {vec(plan.theta0_deg)}")
    lines.append("order = [" + ", ".join(json.dumps(o) for o in plan.order) + "]")
    for s in plan.steps:
        lines += ["", "[[step]]", f"parameter = {json.dumps(s.parameter)}"]
        if s.omega is not None:
            lines.append(f"omega = {_short(s.omega)}")
        lines.append("points_deg = [")
        lines += [f"    {vec(r)}," for r in s.points_deg]
        lines.append("]")
        if len(s.via_deg):
            lines.append("via_deg = [")
            lines += [f"    {vec(r)}," for r in s.via_deg]
            lines.append("]")
    return "\n".join(lines) + "\n"


def _short(x: float) -> str:
    """Shortest text that reads back to the same float, without a trailing '.0'."""
    s = repr(float(x))
    return s[:-2] if s.endswith(".0") else s
