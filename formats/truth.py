"""Truth files: the error offsets of a simulated robot (deg, mm). They never go into a log.

Format::

    robot = "Adept Viper s650"      # optional; must match the robot file
    seed = 3                        # optional, how they were drawn (a whole number ≥ 0)
    log_sha256 = "…"                # optional: the log simulated with them (its bytes')
    [errors]
    th2 = 0.675
    a2 = 0.105
    c2 = 5.2                        # a compliance, µrad/(N·m) (needs the robot's [gravity])
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from wirecal.formats.fileio import read_toml
from wirecal.formats.robot_file import MAX_DH_ANGLE_DEG, MAX_LENGTH_MM
from wirecal.formats.robot_gravity import MAX_COMPLIANCE_URAD_PER_NM
from wirecal.formats.toml_fields import document
from wirecal.solver import params as P
from wirecal.solver.compliance import COMPLIANCE_RANGE_URAD_PER_NM
from wirecal.solver.robot import Robot

_KEYS = ("robot", "seed", "log_sha256", "errors")


def load_errors(path: str | Path, robot: Robot, log_sha256: str | None = None) -> dict[str, float]:
    """Return the ``[errors]`` table of a truth file, validated against the robot.

    Offsets are bounded like the robot file's values (±360 deg, ±10 000 mm); a truth file
    for another robot is refused, and, given the ``log_sha256`` of the log it is compared
    with, one written with another log.
    """
    doc = document(read_toml(path, "truth file"), str(path), "truth file", _KEYS)
    name = doc.string("robot", None)
    if name is not None and name != robot.name:
        doc.add(
            "robot",
            f"the truth is for {name!r} but the robot file describes {robot.name!r}; "
            "use the matching robot file",
        )
    written = doc.string("log_sha256", None)
    if written is not None and log_sha256 is not None and written != log_sha256:
        doc.add(
            "log_sha256",
            f"the truth was written with another log ({written[:12]}…, this one is "
            f"{log_sha256[:12]}…); give the truth file simulate wrote beside this log",
        )
    doc.integer("seed", None, lo=0)
    table = doc.table("errors", None)
    out: dict[str, float] = {}
    for name in table.keys():
        try:
            p = P.parse(name, robot.n_joints)
        except ValueError as exc:
            table.add(name, str(exc))
            continue
        if p.kind == "c" and robot.masses is None:
            table.add(name, "a compliance needs the robot file's [gravity] table (the masses)")
            continue
        bound = MAX_DH_ANGLE_DEG if p.angular else MAX_LENGTH_MM
        bound = MAX_COMPLIANCE_URAD_PER_NM if p.kind == "c" else bound
        value = table.number(name, lo=-bound, hi=bound, unit=p.unit)
        if value is not None:
            out[name] = value
    doc.raise_if_any()
    return out


TRUE_COMPLIANCE_URAD_PER_NM = COMPLIANCE_RANGE_URAD_PER_NM
"""Range (µrad/(N·m)) a simulated arm's compliances are drawn from: the stated range the
error budget takes for one the points do not identify (issue 30's independent model of a
Viper-sized arm, "joints 2–4 yielding 2–8 µrad/N·m under gravity"; its compliance terms
took the wire's error on real IRB 120 tracker data down by a fifth)."""


def random_errors(robot: Robot, scale: float, rng: np.random.Generator) -> dict[str, float]:
    """Draw uniform offsets for the robot's calibration parameters.

    Offsets uniform within ±scale (deg for angles, mm for lengths) for the robot's
    calibration parameters; then, when the robot file lists ``compliances``, each of them
    uniform in :data:`TRUE_COMPLIANCE_URAD_PER_NM` (the true compliance less the file's).
    """
    values = rng.uniform(-scale, scale, len(robot.parameters))
    out = {n: float(v) for n, v in zip(robot.parameters, values, strict=True)}
    for name in robot.compliances:
        out[name] = float(rng.uniform(*TRUE_COMPLIANCE_URAD_PER_NM)) - robot.nominal_value(name)
    return out


def truth_text(
    robot: Robot, errors: dict[str, float], seed: int | None, log_sha256: str | None = None
) -> str:
    """Return the text of a truth file holding ``errors`` (deg, mm), of the log ``log_sha256``."""
    lines = [
        "# wirecal truth: the simulated robot's true error offsets (deg, mm).",
        "# Kept apart from the log; compare a solve's result against it.",
        f"robot = {json.dumps(robot.name, ensure_ascii=False)}",
    ]
    if seed is not None:
        lines.append(f"seed = {seed}")
    if log_sha256 is not None:
        lines.append(f'log_sha256 = "{log_sha256}"')
    lines += ["", "[errors]"]
    lines += [f"{name} = {value!r}" for name, value in errors.items()]
    return "\n".join(lines) + "\n"
