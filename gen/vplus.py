"""V+ language rules the generator enforces, and exact literal formatting.

Rules (V+ Language User's Guide v17: program format p. 35–36, names p. 99–100,
numbers p. 102): ``.PROGRAM name()`` … ``.END``; AUTO/LOCAL/GLOBAL before the first
executable step; names start with a letter, hold letters, digits, '.' and '_', and
only their first 15 characters count; labels are integers 0–65535; string literals hold
ASCII 32–126 without '"'. wirecal keeps lines within 80 characters (the terminal line
limit, p. 202) and writes no keyword of other dialects (Kawasaki's JMOVE, named labels).
"""

from __future__ import annotations

import re
from collections.abc import Iterable

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot

SIGNIFICANT = 15
MAX_LINE = 80
NAME = re.compile(r"^[A-Za-z][A-Za-z0-9._]*$")
FOREIGN = re.compile(r"\b(JMOVE|LMOVE|JAPPRO|LAPPRO|TWAIT|C1MOVE|C2MOVE|HOME)\b")
DECLARATION = re.compile(r"^\s*(AUTO|LOCAL|GLOBAL)\b")
PROGRAM = re.compile(r"^\.PROGRAM\s+([A-Za-z][A-Za-z0-9._]*)\((.*)\)\s*(;.*)?$")
IDENT = re.compile(r"(?<![A-Za-z0-9._^\"])[$#%]?([A-Za-z][A-Za-z0-9._]*)")


def joint_literal(x: float) -> str:
    """A joint angle as the operator reads it: up to 4 decimals, no trailing zeros."""
    s = f"{x:.4f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def ppoint(q: Iterable[float]) -> str:
    return "#PPOINT(" + ", ".join(joint_literal(x) for x in q) + ")"


def double_literal(x: float) -> str:
    """An exact-to-1e-15 DOUBLE constant from confirmed syntax only: a ``^D`` integer
    (UG p. 102) divided by a power of ten held in ``wc.p10[]``."""
    x = float(x)
    if x == 0:
        return "0"
    k = 15 - int(np.floor(np.log10(abs(x))))
    k = max(0, min(k, 22))
    m = round(x * 10.0 ** k)
    while abs(m) >= 10 ** 16 and k > 0:  # keep the mantissa within 16 digits
        k -= 1
        m = round(x * 10.0 ** k)
    while m % 10 == 0 and k > 0:
        m //= 10
        k -= 1
    sign = "-" if m < 0 else ""
    if k == 0 and abs(m) < 2 ** 24:
        return str(m)                  # a whole number a REAL holds exactly
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
                f"{robot.joint_max_deg[j]:g}]; move the point or lower --margin")

    check(plan.theta0_deg, "theta0_deg")
    for j, s in enumerate(plan.steps, 1):
        for i, q in enumerate(s.via_deg, 1):
            check(q, f"step {j} ({s.parameter}) via point {i}")
        for i, q in enumerate(s.points_deg, 1):
            check(q, f"step {j} ({s.parameter}) point {i}")
    if problems:
        raise WirecalError(problems)


def lint(text: str, source: str = "<module>") -> list[str]:
    """Problems of a generated module against the rules above (empty when clean)."""
    problems: list[str] = []
    names: dict[str, str] = {}
    in_program = None
    executable = False
    labels: set[str] = set()
    gotos: list[tuple[int, str]] = []
    for n, line in enumerate(text.split("\n"), 1):
        where = f"{source}:{n}"
        if len(line) > MAX_LINE:
            problems.append(f"{where}: line has {len(line)} characters (> {MAX_LINE})")
        code = _strip_comment(line).strip()
        if not code:
            continue
        if FOREIGN.search(code):
            problems.append(f"{where}: keyword of another dialect: {code}")
        if code.startswith(".PROGRAM"):
            m = PROGRAM.match(line.strip())
            if not m:
                problems.append(f"{where}: malformed .PROGRAM line")
                continue
            if in_program:
                problems.append(f"{where}: .PROGRAM inside {in_program} (missing .END)")
            in_program, executable = m.group(1), False
            labels, gotos = set(), []
            _register(m.group(1), names, where, problems)
            continue
        if code == ".END":
            if not in_program:
                problems.append(f"{where}: .END without .PROGRAM")
            for gl, target in gotos:
                if target not in labels:
                    problems.append(f"{source}:{gl}: GOTO {target}: no such label in "
                                    f"{in_program}")
            in_program = None
            continue
        if not in_program:
            problems.append(f"{where}: code outside a program: {code}")
            continue
        m = re.match(r"^(\d+)(\s|$)", code)
        if m:
            labels.add(m.group(1))
            if int(m.group(1)) > 65535:
                problems.append(f"{where}: label {m.group(1)} above 65535")
            code = code[m.end():].strip()
            if not code:
                continue
        if DECLARATION.match(code):
            if executable:
                problems.append(f"{where}: declaration after executable steps: {code}")
        else:
            executable = True
        g = re.match(r"^GOTO\s+(\S+)$", code)
        if g:
            if not g.group(1).isdigit():
                problems.append(f"{where}: GOTO needs a numeric label, not {g.group(1)}")
            gotos.append((n, g.group(1)))
        for s in re.findall(r'"([^"]*)"', code):
            if any(not 32 <= ord(ch) <= 126 for ch in s):
                problems.append(f"{where}: string literal with characters outside ASCII "
                                "32–126")
        for ident in IDENT.findall(re.sub(r'"[^"]*"', '""', code)):
            if "." in ident or "_" in ident:
                _register(ident, names, where, problems)
    if in_program:
        problems.append(f"{source}: missing .END after {in_program}")
    return problems


def _strip_comment(line: str) -> str:
    out, quoted = [], False
    for ch in line:
        if ch == '"':
            quoted = not quoted
        if ch == ";" and not quoted:
            break
        out.append(ch)
    return "".join(out)


def _register(name: str, names: dict[str, str], where: str, problems: list[str]) -> None:
    key = name.lower()[:SIGNIFICANT]
    other = names.setdefault(key, name.lower())
    if other != name.lower():
        problems.append(f"{where}: {name!r} and {other!r} share their first {SIGNIFICANT} "
                        "characters")
