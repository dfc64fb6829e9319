"""Read the public laser-tracker data sets (and any generic table) into a TrackerTable.

The layout is told by the header (:func:`read_tracker`):

* **Fraunhofer IPA, UR10** (github.com/christianlandgraf/ipa-robot-accuracy):
  ``;``-separated, decimal commas; ``shoulder_pan_joint`` … ``wrist_3_joint`` in
  **radians**; ``measurement_x``, ``_y``, ``_z`` (mm, the tracker's frame);
  ``measurement_temperature`` (°C).
* **Tsinghua, UR5 and Barrett WAM** (github.com/pauljac7700/serial_robots_datasets):
  ``joint_1`` … ``joint_n`` in degrees; the target ``x_t``, ``y_t``, ``z_t`` and the
  difference ``x_dif`` … (mm); the measured point is target − difference ("the
  difference between the target position and the actual achieved position"; the other sign
  mirrors the errors about the nominal target and gives the same calibration figures).
* otherwise the generic layout of :mod:`~wirecal.formats.tracker_table`.

The public sets are not in the repository: they are read as published (a git clone) or
as gzip-compressed copies, where :mod:`~wirecal.formats.tracker_published` finds them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wirecal.formats.tracker_table import Cells, cells, columns, read_generic, read_joints
from wirecal.solver.tracker.data import TrackerTable

IPA_JOINTS = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
IPA_POINT = ("measurement_x", "measurement_y", "measurement_z")
IPA_TEMPERATURE = "measurement_temperature"
TARGET = ("x_t", "y_t", "z_t")
DIFFERENCE = ("x_dif", "y_dif", "z_dif")


def read_ipa(source: str, header: tuple[str, ...], rows: Cells) -> TrackerTable:
    """Return the rows of an IPA UR10 series (module docstring)."""
    names = (*IPA_JOINTS, *IPA_POINT, IPA_TEMPERATURE)
    lines, v = columns(source, header, rows, names, decimal_comma=True)
    return TrackerTable(
        source,
        "IPA UR10 series (joints in rad, measurement_x/y/z in mm)",
        lines,
        np.degrees(v[:, :6]),
        v[:, 6:9],
        v[:, 9],
    )


def read_jacobi(source: str, header: tuple[str, ...], rows: Cells) -> TrackerTable:
    """Return the rows of a Tsinghua UR5 or WAM file (module docstring)."""
    n = sum(1 for h in header if h.startswith("joint_"))
    joints = tuple(f"joint_{i + 1}" for i in range(n))
    lines, v = columns(source, header, rows, (*joints, *TARGET, *DIFFERENCE))
    measured = v[:, n : n + 3] - v[:, n + 3 :]
    return TrackerTable(
        source,
        f"Tsinghua {n}-joint set (joints in deg, target − difference in mm)",
        lines,
        v[:, :n],
        measured,
    )


def read_tracker(path: str | Path) -> TrackerTable:
    """Read a tracker table of any known layout (module docstring)."""
    return _table(*cells(path))


def _table(source: str, header: tuple[str, ...], rows: Cells) -> TrackerTable:
    """Return the rows of the layout the header tells (module docstring)."""
    if IPA_JOINTS[0] in header:
        return read_ipa(source, header, rows)
    if DIFFERENCE[0] in header:
        return read_jacobi(source, header, rows)
    return read_generic(source, header, rows)


def read_pool(path: str | Path) -> tuple[str, np.ndarray, np.ndarray]:
    """Return a pool of configurations: its name, the rows' lines and joints (deg).

    A tracker table of any known layout, or the generic layout without x, y, z.
    """
    source, header, rows = cells(path)
    if IPA_JOINTS[0] in header or DIFFERENCE[0] in header or "x" in header:
        table = _table(source, header, rows)
        return table.source, table.lines, table.q_deg
    lines, q_deg = read_joints(source, header, rows)
    return source, lines, q_deg
