"""Validation files: the procedures' setup (TOML) and their logs (CSV).

Validation files: the setup of the paper's two validation procedures (TOML) and the
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
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.formats.csv_table import Row, parse_table, read_source
from wirecal.formats.fileio import read_toml
from wirecal.formats.robot_file import MAX_LENGTH_MM
from wirecal.formats.robot_values import not_metres
from wirecal.formats.toml_fields import MISSING, Table, document, valid
from wirecal.solver.errors import WirecalError, first_problems
from wirecal.solver.validation.analysis import ValidationLog
from wirecal.solver.validation.design import Setup

_SETUP_KEYS = {
    "": ("configuration", "plate"),
    "configuration": ("encoder_mm", "poses", "seed"),
    "plate": ("origin_mm", "yaw_deg", "size_mm", "grid", "approach_mm", "probe_mm", "signal"),
}


def load_setup(path: str | Path) -> Setup:
    """Read a validation setup (module docstring); every problem as ``file: key: problem``.

    Lengths within ±10 000 mm, as in the robot file; the grid at least 2 × 2 points.
    """
    doc = document(
        read_toml(path, "validation setup"), str(path), "validation setup", _SETUP_KEYS[""]
    )
    cfg = doc.table("configuration", _SETUP_KEYS["configuration"])
    plate = doc.table("plate", _SETUP_KEYS["plate"])
    encoder_mm = _mm(cfg, "encoder_mm")
    poses = cfg.integer("poses", 50, lo=1, hi=100_000)
    seed = cfg.integer("seed", 1, lo=0)
    origin = _mm(plate, "origin_mm")
    yaw = plate.number("yaw_deg", 0.0, lo=-360, hi=360, unit="deg")
    size = _mm(
        plate, "size_mm", [400, 250], length=2, labels="(along the grid's two axes)", above=0
    )
    grid = plate.vector(
        "grid", [19, 11], length=2, labels="(points along each axis)", integer=True, lo=1, hi=1000
    )
    if grid is not None and min(grid) < 2:
        plate.add("grid", "needs at least 2 × 2 points to fit a plane")
    approach = plate.number("approach_mm", 5.0, lo=0.5, hi=MAX_LENGTH_MM, unit="mm")
    probe = _mm(plate, "probe_mm", [0, 0, 100])
    signal = plate.integer("signal", 1001, lo=1)
    doc.raise_if_any()
    size, grid = valid(size), valid(grid)
    return Setup(
        encoder_mm=valid(encoder_mm),
        poses=valid(poses),
        seed=valid(seed),
        plate_origin_mm=valid(origin),
        plate_yaw_deg=valid(yaw),
        plate_size_mm=(float(size[0]), float(size[1])),
        grid=(int(grid[0]), int(grid[1])),
        approach_mm=valid(approach),
        probe_mm=valid(probe),
        signal=valid(signal),
        source=str(path),
    )


def _mm(
    table: Table,
    key: str,
    default: Any = MISSING,
    *,
    length: int = 3,
    labels: str = "(x, y, z)",
    above: float | None = None,
) -> np.ndarray | None:
    """Read lengths (mm) within ±:data:`MAX_LENGTH_MM` (above ``above`` if given), not metres."""
    lo = None if above is not None else -MAX_LENGTH_MM
    v = table.vector(
        key, default, length=length, labels=labels, lo=lo, hi=MAX_LENGTH_MM, above=above, unit="mm"
    )
    return not_metres(table, key, v)


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

    def columns(header: dict[str, tuple[str, int]], _version: int) -> tuple[str, ...]:
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
    rows = _readings(table.rows, source, kind, problems)
    mpc_text, mpc_line = table.header.get("mm_per_count", ("nan", 0))
    try:
        mpc = float(mpc_text)
    except ValueError:
        problems.append(f"{source}:{mpc_line}: mm_per_count {mpc_text!r} is not a number")
    if problems:
        raise WirecalError(first_problems(problems))
    if not rows:
        raise WirecalError(f"{source}: no readings")
    return ValidationLog(
        kind, source, table.header["robot"][0], table.header["setup"][0], mpc, np.array(rows)
    )


def _readings(
    table_rows: tuple[Row, ...], source: str, kind: str, problems: list[str]
) -> list[list[float]]:
    """Return the rows as numbers; add a problem for each bad or duplicate row, and skip it."""
    rows: list[list[float]] = []
    seen: dict[tuple[float, float], int] = {}
    for r in table_rows:
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
    return rows
