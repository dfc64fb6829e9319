"""Truth files: the error offsets of a simulated robot (deg, mm). They never go into a log.

Format::

    robot = "Adept Viper s650"      # optional
    seed = 3                        # optional, how they were drawn
    [errors]
    th2 = 0.675
    a2 = 0.105
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.robot import Robot


def load_errors(path: str | Path, robot: Robot) -> dict[str, float]:
    """The ``[errors]`` table of a truth file, validated against the robot."""
    data = read_toml(path, "errors file")
    pr = Problems(str(path))
    table = data.get("errors")
    if not isinstance(table, dict):
        raise WirecalError(f"{path}: errors: missing table [errors] of name = offset (deg or mm)")
    out: dict[str, float] = {}
    for name, value in table.items():
        try:
            P.parse(name, robot.n_joints)
        except ValueError as exc:
            pr.add(f"errors.{name}", str(exc))
            continue
        if (
            not isinstance(value, int | float)
            or isinstance(value, bool)
            or not math.isfinite(value)
        ):
            pr.add(f"errors.{name}", f"is {value!r}; give a finite offset (deg or mm)")
            continue
        out[name] = float(value)
    pr.raise_if_any()
    return out


def random_errors(robot: Robot, scale: float, rng: np.random.Generator) -> dict[str, float]:
    """Offsets uniform within ±scale (deg for angles, mm for lengths) for the robot's
    calibration parameters."""
    values = rng.uniform(-scale, scale, len(robot.parameters))
    return {n: float(v) for n, v in zip(robot.parameters, values, strict=True)}


def truth_text(robot: Robot, errors: dict[str, float], seed: int | None) -> str:
    lines = [
        "# wirecal truth: the simulated robot's true error offsets (deg, mm).",
        "# Kept apart from the log; compare a solve's result against it.",
        f"robot = {json.dumps(robot.name, ensure_ascii=False)}",
    ]
    if seed is not None:
        lines.append(f"seed = {seed}")
    lines += ["", "[errors]"]
    lines += [f"{name} = {value!r}" for name, value in errors.items()]
    return "\n".join(lines) + "\n"
