"""Calibration plan files (TOML): read, validate against a robot, and write.

Format (joint angles in degrees)::

    theta0_deg = [0, -90, 210, -90, 0, -90]      # encoder mounted here (wire length 0)
    order = ["th6", "d6", ...]                   # identification order, one step each
    [[step]]
    parameter = "th6"
    points_deg = [[0, -90, 210, -90, -26, -180], ...]
    via_deg = [[...], ...]                       # optional: passed (blended) from θ0 to
                                                 # the first point, in this order
    omega = 5.0                                  # optional: bound Ω_j (deg or mm), ≤ 1000
    [[step]]                                     # optional, last: the payload step
    parameter = "payload"
    payload_kg = 5.0                             # the mass the operator mounts at the flange
    payload_com_mm = [0, 0, 50]                  # its centre in the last frame
    points_deg = [...]                           # measured with it, after the zero at θ0

The payload step (``wirecal plan`` adds it when the robot file's ``[calibration]
payload_kg`` is given and it pays, :mod:`wirecal.solver.plan.payload`) needs the robot
file's ``compliances`` and may not exceed its ``rated_payload_kg``.

``joint_only = true`` (optional; ``plan --pool`` writes it): the steps split poses chosen
for the joint method, so the step-by-step estimate does not apply and ``solve`` runs the
joint method alone.

Field rules: :mod:`wirecal.formats.toml_fields`; every joint angle within the robot's
limits.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.formats.fileio import read_toml
from wirecal.formats.robot_gravity import MAX_MASS_KG, read_com
from wirecal.formats.toml_fields import Table, document, duplicates, valid
from wirecal.solver import params as P
from wirecal.solver.angle_units import within_a_turn
from wirecal.solver.distance import wire_lengths
from wirecal.solver.plan.calibration_plan import PAYLOAD_STEP, Plan, Step
from wirecal.solver.robot import Robot

_TOP_KEYS = ("theta0_deg", "order", "step", "robot", "description", "joint_only")
_STEP_KEYS = ("parameter", "points_deg", "via_deg", "omega", "payload_kg", "payload_com_mm")
MAX_OMEGA = 1000.0
"""Largest bound Ω_j of a step (deg or mm): offsets beyond it are not calibration errors."""


MAX_STEP_POINTS = 1000
"""Most points (and via points) of one step: ``wirecal plan`` designs at most 1000 in all;
a larger list is refused before any work, which grows with the points."""


def load_plan(path: str | Path, robot: Robot) -> Plan:
    """Read and validate a plan against a robot; raise :class:`WirecalError` listing problems."""
    return plan_from_dict(read_toml(path, "plan file"), robot, str(path))


def plan_from_dict(data: dict[str, Any], robot: Robot, source: str = "<plan>") -> Plan:
    """Validate a parsed plan against the robot it is for (see module docstring)."""
    doc = document(data, source, "plan file", _TOP_KEYS)
    n = robot.n_joints
    theta0 = doc.vector("theta0_deg", length=n, labels="(one per joint, deg)")
    plan_robot = doc.string("robot", None)
    plan_robot = plan_robot.strip() if plan_robot is not None else None  # as the robot file's
    if plan_robot is not None and plan_robot != robot.name:
        doc.add(
            "robot",
            f"plan is for {plan_robot!r} but the robot file describes "
            f"{robot.name!r}; use the matching robot file",
        )
    description = doc.string("description", None)
    joint_only = doc.boolean("joint_only", False)
    order = _order(doc, robot)
    raw_steps = doc.tables("step", _STEP_KEYS)
    read = [(st, _point_sets(st, n)) for st in raw_steps]
    _check_angles(doc, theta0, read, robot)
    steps = [_step(st, j, order, robot, *q) for j, (st, q) in enumerate(read, 1)]
    payload = bool(raw_steps) and (raw_steps[-1].data or {}).get("parameter") == PAYLOAD_STEP
    if raw_steps and len(raw_steps) != len(order) + payload:
        doc.add(
            "step",
            f"has {len(raw_steps)} step(s) but order names {len(order)} "
            "parameter(s); give one [[step]] per parameter (and the payload step last)",
        )
    doc.raise_if_any()
    return Plan(
        theta0_deg=valid(theta0),
        order=tuple(order),
        steps=tuple(s for s in steps if s is not None),
        robot=plan_robot,
        description=description,
        source=source,
        joint_only=bool(joint_only),
    )


def _order(doc: Table, robot: Robot) -> list[str]:
    order = doc.strings("order", what="parameter names") or []
    for name in order:
        if name not in robot.parameters:
            try:
                P.parse(name, robot.n_joints)
                doc.add(
                    "order",
                    f"{name!r} is not in the robot file's [calibration] parameters "
                    f"{list(robot.parameters)}",
                )
            except ValueError as exc:
                doc.add("order", str(exc))
    if duplicates(order):
        doc.add("order", f"lists {duplicates(order)[0]!r} twice")
    return order


def _theta0_in_radians(theta0: np.ndarray, sets: list[np.ndarray]) -> bool:
    """Whether θ0 alone was written in radians: within ±2π, and in degrees nearer the points.

    A plan's points lie around its θ0 (the wire is short); a θ0 near the zero pose in
    degrees has points nearer itself than its values times 57.3 (all zero: equal, kept).
    """
    if not within_a_turn(theta0):
        return False
    q = np.concatenate(sets)

    def nearest(x: np.ndarray) -> float:
        return float(np.min(np.max(np.abs(q - x), axis=1)))

    return nearest(np.degrees(theta0)) < nearest(theta0)


def _point_sets(st: Table, n: int) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Return a step's ``points_deg`` and ``via_deg`` (None where they have problems)."""
    joints = "(one per joint, deg)"
    points = st.matrix("points_deg", cols=n, labels=joints, max_rows=MAX_STEP_POINTS)
    via = st.matrix("via_deg", [], cols=n, labels=joints, nonempty=False, max_rows=MAX_STEP_POINTS)
    return points, via


def _check_angles(
    doc: Table,
    theta0: np.ndarray | None,
    steps: list[tuple[Table, tuple[np.ndarray | None, np.ndarray | None]]],
    robot: Robot,
) -> None:
    """Check θ0 and each step's points and vias against the joint limits and the wire.

    A plan whose angles all lie within ±2π is in radians: one problem says so, not one
    per point beyond a limit or too near θ0.
    """
    sets = [
        (st, key, q)
        for st, qs in steps
        for key, q in zip(("points_deg", "via_deg"), qs, strict=True)
    ]
    if theta0 is not None and any(q is not None and q.size for _, _, q in sets):
        angles = np.concatenate([theta0, *(q.ravel() for _, _, q in sets if q is not None)])
        if within_a_turn(angles):
            doc.add(
                "theta0_deg",
                "θ0 and every point of the plan are within ±2π: they look like radians (θ0 "
                f"would be [{', '.join(f'{v:.4g}' for v in np.degrees(theta0))}] deg); give "
                "degrees",
            )
            return
        if _theta0_in_radians(theta0, [q for _, _, q in sets if q is not None and q.size]):
            doc.add(
                "theta0_deg",
                "θ0 is within ±2π while the points are not: θ0 looks like radians (in degrees "
                f"[{', '.join(f'{v:.4g}' for v in np.degrees(theta0))}], nearer the plan's "
                "points); give degrees",
            )
            return
    if theta0 is not None:
        _check_limits(theta0[None], robot, "theta0_deg", doc)
    for st, key, q in sets:
        if q is not None:
            _check_limits(q, robot, st.name(key), st)
            if key == "points_deg" and theta0 is not None:
                _check_wire(q, theta0, robot, st.name(key), st)


def _step(
    st: Table,
    j: int,
    order: list[str],
    robot: Robot,
    points: np.ndarray | None,
    via: np.ndarray | None,
) -> Step | None:
    param = st.string("parameter")
    if param is not None and j <= len(order) and param != order[j - 1]:
        st.add(
            "parameter",
            f"is {param!r} but order[{j}] is {order[j - 1]!r}; steps must follow the order",
        )
    kg, com = _payload(st, param == PAYLOAD_STEP and j == len(order) + 1, robot)
    omega = st.number("omega", None, above=0, hi=MAX_OMEGA, unit="(deg or mm)")
    if param is None or points is None or via is None or not st.present:
        return None
    return Step(param, points, via, omega, kg, com)


def _payload(st: Table, payload: bool, robot: Robot) -> tuple[float, tuple[float, float, float]]:
    """Read a step's ``payload_kg`` and ``payload_com_mm``: the payload step's, and only its."""
    kg = st.number("payload_kg", None, above=0, hi=MAX_MASS_KG, unit="kg")
    com = read_com(st, "payload_com_mm")
    if not payload:
        for key in ("payload_kg", "payload_com_mm"):
            if key in st.keys():
                st.add(key, f"only the payload step (parameter = {PAYLOAD_STEP!r}, last) has one")
        return 0.0, (0.0, 0.0, 0.0)
    if kg is None:
        st.add("payload_kg", "the payload step needs its mass (kg)")
    else:
        _check_payload(st, kg, robot)
    xyz = (0.0, 0.0, 0.0) if com is None else (float(com[0]), float(com[1]), float(com[2]))
    return float(kg or 0.0), xyz


def _check_payload(st: Table, kg: float, robot: Robot) -> None:
    """Refuse a payload step the robot file does not ask for or whose mass it cannot take."""
    if not robot.compliances or robot.masses is None:
        st.add(
            "payload_kg",
            "the payload step is for compliances: the robot file lists none in [calibration] "
            "compliances; use the matching robot file or remove the step",
        )
    elif robot.rated_payload_kg is None:
        st.add(
            "payload_kg",
            "the robot file states no rated payload: add [calibration] rated_payload_kg (the "
            "data sheet's), so that the mass is checked against it",
        )
    elif kg + robot.masses.payload_mass_kg > robot.rated_payload_kg:
        st.add(
            "payload_kg",
            f"{kg:g} kg with the tool's {robot.masses.payload_mass_kg:g} kg exceeds the arm's "
            f"rated payload {robot.rated_payload_kg:g} kg (robot file); use a lighter mass",
        )


def _check_limits(q: np.ndarray, robot: Robot, where: str, table: Table) -> None:
    lo, hi = robot.joint_min_deg, robot.joint_max_deg
    beyond = (q < lo) | (q > hi)
    if not beyond.any():
        return
    for i, row in enumerate(q, 1):
        for j in np.flatnonzero(beyond[i - 1]):
            label = where if q.shape[0] == 1 and where == "theta0_deg" else f"{where}[{i}]"
            table.problems.add(
                label, f"joint {j + 1} = {row[j]:g} deg is beyond its limits [{lo[j]:g}, {hi[j]:g}]"
            )


MIN_WIRE_MM = 1.0
"""Shortest wire length a plan point may have: at θ0 itself the wire has no direction, so
its derivatives (Ψ, the Jacobian) are undefined."""


def _check_wire(q: np.ndarray, theta0: np.ndarray, robot: Robot, where: str, table: Table) -> None:
    d = wire_lengths(robot.nominal, np.radians(q), np.radians(theta0))
    for i in np.flatnonzero(np.isnan(d)):  # only within a pulley's circle
        table.problems.add(
            f"{where}[{i + 1}]",
            "the tool point there is within the guide pulley's circle (encoder."
            "pulley_radius_mm), where no wire reaches it; move or remove the point",
        )
    for i in np.flatnonzero(d < MIN_WIRE_MM):
        table.problems.add(
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
    if plan.joint_only:
        lines.append("joint_only = true")
    lines.append(f"theta0_deg = {vec(plan.theta0_deg)}")
    lines.append("order = [" + ", ".join(json.dumps(o) for o in plan.order) + "]")
    for s in plan.steps:
        lines += ["", "[[step]]", f"parameter = {json.dumps(s.parameter)}"]
        if s.omega is not None:
            lines.append(f"omega = {_short(s.omega)}")
        if s.parameter == PAYLOAD_STEP:
            lines.append(f"payload_kg = {_short(s.payload_kg)}")
            lines.append(f"payload_com_mm = {vec(np.array(s.payload_com_mm))}")
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
