"""Validation files: the setup of the paper's two validation procedures (TOML) and the
logs their controller programs write (CSV).

Setup file (TOML)::

    [configuration]
    encoder_mm = [900, 0, -100]   # encoder exit point, base frame, outside the workspace
    poses = 50
    seed = 1
    [plate]
    origin_mm = [220, -125, -200] # corner of the probed area on the plate's top face
    yaw_deg = 0                   # direction of the grid's first axis about base z
    size_mm = [400, 250]
    grid = [19, 11]
    approach_mm = 20              # start this far above the plate (search down to 2×)
    probe_mm = [0, 0, 100]        # probe tip in the flange frame
    signal = 1001                 # the probe's digital input
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.formats.csv_table import parse_table, read_source
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.validation import Setup


def load_setup(path: str | Path) -> Setup:
    data = read_toml(path, "validation setup")
    pr = Problems(str(path))
    cfg, plate = data.get("configuration", {}), data.get("plate", {})
    for name, table in (("configuration", cfg), ("plate", plate)):
        if not isinstance(table, dict) or not table:
            pr.add(name, f"the table [{name}] is missing")
    pr.raise_if_any()

    def vec(table, key, n, where, default=None):
        v = table.get(key, default)
        if (
            not isinstance(v, list)
            or len(v) != n
            or not all(isinstance(x, int | float) and math.isfinite(x) for x in v)
        ):
            pr.add(f"{where}.{key}", f"must be {n} finite numbers")
            return np.zeros(n)
        return np.asarray(v, dtype=float)

    def num(table, key, where, default, kind=float, lo=None):
        v = table.get(key, default)
        if (
            not isinstance(v, int | float)
            or isinstance(v, bool)
            or (kind is int and not isinstance(v, int))
            or (lo is not None and v < lo)
        ):
            pr.add(
                f"{where}.{key}",
                f"is {v!r}; give a {'whole ' if kind is int else ''}"
                f"number{'' if lo is None else f' ≥ {lo}'}",
            )
            return kind(default)
        return kind(v)

    setup = Setup(
        encoder_mm=vec(cfg, "encoder_mm", 3, "configuration"),
        poses=num(cfg, "poses", "configuration", 50, int, 1),
        seed=num(cfg, "seed", "configuration", 1, int, 0),
        plate_origin_mm=vec(plate, "origin_mm", 3, "plate"),
        plate_yaw_deg=num(plate, "yaw_deg", "plate", 0.0),
        plate_size_mm=tuple(vec(plate, "size_mm", 2, "plate", [400, 250])),
        grid=tuple(int(x) for x in vec(plate, "grid", 2, "plate", [19, 11])),
        approach_mm=num(plate, "approach_mm", "plate", 5.0, float, 0.5),
        probe_mm=vec(plate, "probe_mm", 3, "plate", [0, 0, 100]),
        signal=num(plate, "signal", "plate", 1001, int, 1),
        source=str(path),
    )
    if min(setup.grid) < 2:
        pr.add("plate.grid", "needs at least 2 × 2 points to fit a plane")
    pr.raise_if_any()
    return setup


@dataclass(frozen=True)
class ValidationLog:
    kind: str  # "configuration" or "plane"
    source: str
    robot: str
    setup: str
    mm_per_count: float
    rows: np.ndarray  # numbers, one row per reading, columns as COLUMNS[kind]


COLUMNS = {
    "configuration": (
        "pose",
        "config",
        "j1",
        "j2",
        "j3",
        "j4",
        "j5",
        "j6",
        "counts",
        "samples",
        "spread",
    ),
    "plane": ("row", "col", "x", "y", "z"),
}


def read_validation_log(path: str | Path, kind: str) -> ValidationLog:
    """Read a validation log; every problem as ``file:line: problem``."""
    text, source, _ = read_source(path, "validation log")

    def columns(header: dict[str, tuple[str, int]]) -> tuple[str, ...]:
        found, line = header.get("kind", (None, 2))
        if found != kind:
            raise WirecalError(f"{source}:{line}: a {found!r} log where a {kind!r} log is needed")
        return COLUMNS[kind]

    table = parse_table(
        text,
        source,
        magic="# wirecal-validation",
        version=1,
        what="validation log",
        columns=columns,
        keys=("kind", "robot", "setup", "mm_per_count"),
    )
    problems = [
        *table.problems,
        *table.missing(("robot", "setup") + (("mm_per_count",) if kind == "configuration" else ())),
    ]
    rows: list[list[float]] = []
    seen: dict[tuple[float, float], int] = {}
    for r in table.rows:
        try:
            row = [float(c) for c in r.cells]
        except ValueError:
            problems.append(f"{source}:{r.line}: a field is not a number: {','.join(r.cells)}")
            continue
        if not all(math.isfinite(x) for x in row):
            problems.append(f"{source}:{r.line}: a field is not finite")
            continue
        key = (row[0], row[1])
        if key in seen:
            problems.append(
                f"{source}:{r.line}: duplicate reading of {COLUMNS[kind][0]} "
                f"{row[0]:g}, {COLUMNS[kind][1]} {row[1]:g} (first on line "
                f"{seen[key]})"
            )
            continue
        if kind == "configuration" and row[1] not in (1, 2, 3, 4):
            problems.append(f"{source}:{r.line}: config {row[1]:g} is not 1–4")
            continue
        seen[key] = r.line
        rows.append(row)
    mpc_text, mpc_line = table.header.get("mm_per_count", ("nan", 0))
    try:
        mpc = float(mpc_text)
    except ValueError:
        problems.append(f"{source}:{mpc_line}: mm_per_count {mpc_text!r} is not a number")
    if problems:
        raise WirecalError(_first(problems))
    if not rows:
        raise WirecalError(f"{source}: no readings")
    return ValidationLog(
        kind, source, table.header["robot"][0], table.header["setup"][0], mpc, np.array(rows)
    )


def _first(problems: list[str], n: int = 12) -> list[str]:
    """The first problems and a count of the rest: a wrong file should not bury its cause."""
    if len(problems) <= n:
        return problems
    return [*problems[:n], f"… and {len(problems) - n} more problems of the same kinds"]
