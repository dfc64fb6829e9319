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
* otherwise the generic layout of :mod:`~wirecal.solver.formats.tracker_table`.

The public sets are not in the repository: they are read where they are put
(:func:`tracker_data_dir`), one folder per set, the file names of
tests/data/tracker/<set>/PUBLISHED.md.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from wirecal.solver.formats.tracker_table import Cells, cells, columns, read_generic, read_joints
from wirecal.solver.tracker_data import TrackerTable

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
DATA_ENV = "WIRECAL_TRACKER_DATA"
# The files of each public set, as tests/data/tracker/<set>/PUBLISHED.md names them.
SET_FILES = {
    "ur10_ipa": (
        "series_b_joint_configurations.csv.gz",
        "series_c_random_poses.csv.gz",
        "series_d_iso_cubes.csv.gz",
    ),
    "ur5_jacobi": ("ur5_grid.csv.gz", "ur5_random.csv"),
    "wam_jacobi": ("wam_grid.csv.gz", "wam_random.csv"),
}


def tracker_data_dir(repo: Path, given: Path | None = None) -> Path:
    """Return the folder holding the public sets' folders (``ur10_ipa/`` …).

    ``given`` (a ``--data DIR``), else the environment's ``WIRECAL_TRACKER_DATA``, else
    ``<repo>/../shared/data/tracker`` (a copy of shared/ beside the clone).
    """
    if given is not None:
        return given
    env = os.environ.get(DATA_ENV)
    return Path(env) if env else repo.parent / "shared" / "data" / "tracker"


def missing_set(folder: Path, name: str, repo: Path) -> str | None:
    """Return why set ``name`` is not in ``folder`` and how to get it, or None.

    None when every file ``SET_FILES[name]`` lists is there.
    """
    absent = [f for f in SET_FILES[name] if not (folder / name / f).is_file()]
    if not absent:
        return None
    return (
        f"public tracker set {name!r} is not in {folder / name} (missing {', '.join(absent)}):"
        f" download it as {repo / 'tests' / 'data' / 'tracker' / name / 'PUBLISHED.md'} says,"
        f" or point --data DIR or {DATA_ENV}=DIR at the folder holding {name}/"
    )


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
