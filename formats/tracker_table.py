"""Read a table of joint angles and tracker-measured tool points (``plan --pool``, replay).

A CSV, TSV or semicolon-separated text, optionally gzip-compressed (``.gz``), with one
header line; blank lines and lines starting with ``#`` are skipped. The generic layout:
columns ``j1`` … ``jn`` (the joint angles, **degrees**) and ``x``, ``y``, ``z`` (the
measured tool point, **mm**, in any fixed frame), other columns ignored. A table whose
every joint stays within ±2π reads as radians and one whose x, y, z span less than 5 units
as metres: both are refused, naming the columns, rather than guessed. A pool of
configurations (``plan --pool``) may leave out x, y, z.

The public data sets' own layouts are :mod:`~wirecal.formats.tracker_sets`; this
module holds what they share: the bounded text, the named columns as numbers.
"""

from __future__ import annotations

import gzip
import io
import zlib
from pathlib import Path

import numpy as np

from wirecal.formats.cable_table import _text_cells, column_index, column_numbers
from wirecal.formats.fileio import MAX_INPUT_BYTES, decode_text, read_input
from wirecal.solver.angle_units import TURN_RAD, within_a_turn
from wirecal.solver.errors import WirecalError
from wirecal.solver.tracker.data import TrackerTable

Cells = list[tuple[int, tuple[str, ...]]]

METRE_SPAN = 5.0
"""x, y, z that all span less than this read as metres (refused by the mm layout)."""


def read_text(path: str | Path) -> tuple[str, str]:
    """Return a table's text and its name; a ``.gz`` file is inflated, both sizes bounded."""
    raw, source = read_input(path, "tracker table")
    if str(path).lower().endswith(".gz"):
        try:
            with gzip.GzipFile(fileobj=io.BytesIO(raw)) as f:
                raw = f.read(MAX_INPUT_BYTES + 1)
        except (OSError, EOFError, zlib.error) as exc:
            raise WirecalError(f"{source}: not a readable gzip file: {exc}") from None
        if len(raw) > MAX_INPUT_BYTES:
            raise WirecalError(
                f"{source}: inflates to more than {MAX_INPUT_BYTES // 2**20} MiB: not a "
                "tracker table; check the file name"
            )
    return decode_text(raw, source, "tracker table"), source


def cells(path: str | Path) -> tuple[str, tuple[str, ...], Cells]:
    """Return a table's name, its header and its data rows (line, cells)."""
    text, source = read_text(path)
    header, rows = _text_cells(text, source)
    return source, header, rows


def columns(
    source: str,
    header: tuple[str, ...],
    rows: Cells,
    names: tuple[str, ...],
    *,
    decimal_comma: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows' lines (N,) and the named columns as numbers (N, k).

    Raise naming every absent column, or every cell (``file:line``, at most ten) that is not
    a finite number; ``decimal_comma``: cells write 0,5 for 0.5.
    """
    index = column_index(names, header, source)
    return column_numbers(rows, names, index, source, decimal_comma=decimal_comma)


def joint_names(header: tuple[str, ...], source: str) -> tuple[str, ...]:
    """Return the generic layout's joint columns j1…jn (n ≥ 2, no gap)."""
    n = 0
    while f"j{n + 1}" in header:
        n += 1
    if n < 2:
        raise WirecalError(
            f"{source}: no joint columns j1, j2, …; the header has "
            f"{', '.join(map(repr, header))}: name the joint columns j1…jn (degrees) and the "
            "measured point x, y, z (mm)"
        )
    return tuple(f"j{i + 1}" for i in range(n))


def check_joint_units(source: str, q_deg: np.ndarray, joints: tuple[str, ...]) -> None:
    """Refuse joints that read as radians (module docstring)."""
    if len(q_deg) >= 10 and within_a_turn(q_deg):
        raise WirecalError(
            f"{source}: every joint ({', '.join(joints)}) stays within ±{TURN_RAD:.2f}: "
            "radians, not degrees? convert the joint columns to degrees"
        )


def check_point_units(source: str, xyz_mm: np.ndarray, names: tuple[str, ...]) -> None:
    """Refuse a measured point that reads as metres (module docstring)."""
    if len(xyz_mm) >= 10 and np.all(np.ptp(xyz_mm, axis=0) < METRE_SPAN):
        raise WirecalError(
            f"{source}: {', '.join(names)} span less than {METRE_SPAN:g} in every "
            "direction: metres, not mm? convert them to mm"
        )


def read_joints(source: str, header: tuple[str, ...], rows: Cells) -> tuple[np.ndarray, np.ndarray]:
    """Return the lines and the joints (deg) of the generic layout, without x, y, z."""
    joints = joint_names(header, source)
    lines, q_deg = columns(source, header, rows, joints)
    check_joint_units(source, q_deg, joints)
    return lines, q_deg


def read_generic(source: str, header: tuple[str, ...], rows: Cells) -> TrackerTable:
    """Return the rows of the generic layout: j1…jn in degrees, x, y, z in mm."""
    joints = joint_names(header, source)
    lines, values = columns(source, header, rows, (*joints, "x", "y", "z"))
    n = len(joints)
    check_joint_units(source, values[:, :n], joints)
    check_point_units(source, values[:, n:], ("x", "y", "z"))
    kind = "joints j1…jn (deg), x, y, z (mm)"
    return TrackerTable(source, kind, lines, values[:, :n], values[:, n:])
