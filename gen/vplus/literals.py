"""V+ literals written exactly, the joint-limit margin, and the line-length rule.

The language rules a controller checks on load (program format, declarations first,
15-character names, keywords, labels, type prefixes) are checked by the parser of the
digital twin (:mod:`wirecal.twin.vplus.parser`), which the generator runs on its own output.
wirecal also keeps lines within 80 characters (the terminal line limit, User's Guide
p. 202).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot

MAX_LINE = 80


def joint_literal(x: float) -> str:
    """Write a joint angle as the operator reads it: up to 4 decimals, no trailing zeros."""
    s = f"{x:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def ppoint(q: Iterable[float]) -> str:
    """Write a #PPOINT(...) literal of joint angles."""
    return "#PPOINT(" + ", ".join(joint_literal(x) for x in q) + ")"


def double_literal(x: float) -> str:
    """Write an exact-to-1e-15 DOUBLE constant from confirmed syntax only.

    A ``^D`` integer (UG p. 102) divided by a power of ten held in ``wc.p10[]``.
    """
    x = float(x)
    if x == 0:
        return "0"
    k = 15 - int(np.floor(np.log10(abs(x))))
    k = max(0, min(k, 22))
    m = round(x * 10.0**k)
    while abs(m) >= 10**16 and k > 0:  # keep the mantissa within 16 digits
        k -= 1
        m = round(x * 10.0**k)
    while m % 10 == 0 and k > 0:
        m //= 10
        k -= 1
    sign = "-" if m < 0 else ""
    if k == 0 and abs(m) < 2**24:
        return str(m)  # a whole number a REAL holds exactly
    return f"{sign}^D{abs(m)}/wc.p10[{k}]" if k else f"{sign}^D{abs(m)}"


def check_limits(robot: Robot, plan: Plan, margin_deg: float) -> None:
    """Refuse to generate motion to any configuration within ``margin_deg`` of a limit."""
    lo = robot.joint_min_deg + margin_deg
    hi = robot.joint_max_deg - margin_deg
    problems = []

    def check(q, where):
        for j in np.flatnonzero((q < lo) | (q > hi)):
            problems.append(
                f"{plan.source}: {where}: joint {j + 1} = {joint_literal(q[j])} deg is within "
                f"{margin_deg:g} deg of its limits [{robot.joint_min_deg[j]:g}, "
                f"{robot.joint_max_deg[j]:g}]; move the point or lower --margin"
            )

    check(plan.theta0_deg, "theta0_deg")
    for j, s in enumerate(plan.steps, 1):
        for i, q in enumerate(s.via_deg, 1):
            check(q, f"step {j} ({s.parameter}) via point {i}")
        for i, q in enumerate(s.points_deg, 1):
            check(q, f"step {j} ({s.parameter}) point {i}")
    if problems:
        raise WirecalError(problems)


def long_lines(text: str, source: str) -> list[str]:
    """Lines over :data:`MAX_LINE` characters."""
    return [
        f"{source}:{n}: line has {len(line)} characters (> {MAX_LINE})"
        for n, line in enumerate(text.split("\n"), 1)
        if len(line) > MAX_LINE
    ]
