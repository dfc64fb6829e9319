"""A cable-length table taken without wirecal, as ``wirecal fit`` uses it (the data).

:class:`CableTable` holds the rows (joints in degrees, absolute lengths in mm, optionally the
controller's nominal x, y, z) with their file lines and resolutions; :class:`ColumnMap` says
which column held what. :mod:`~wirecal.formats.cable_table` reads CSV/TSV and
``.xlsx`` files into them; the fit (:mod:`~wirecal.solver.fit.result`) and the simulated
tables (:mod:`~wirecal.solver.fit.synth`) use them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AXES = ("x", "y", "z")
"""The map's keys of the controller's nominal position."""


@dataclass(frozen=True)
class ColumnMap:
    """Which column of the table holds each joint, the length and the nominal x, y, z."""

    joints: tuple[str, ...]
    length: str
    xyz: tuple[str, str, str] | None = None

    @property
    def columns(self) -> tuple[str, ...]:
        """Return every column the map names, joints first."""
        return (*self.joints, self.length, *(self.xyz or ()))


@dataclass(frozen=True)
class CableTable:
    """The rows of a cable-length table, in file order, with their file lines.

    ``lines`` are 1-based lines of a text file or row numbers of a sheet.
    """

    source: str
    sha256: str
    columns: ColumnMap
    lines: np.ndarray  # (N,) int
    q_deg: np.ndarray  # (N, n)
    length_mm: np.ndarray  # (N,)
    xyz_mm: np.ndarray | None  # (N, 3) the controller's nominal position, if given
    joint_resolution_deg: float
    length_resolution_mm: float
    xyz_resolution_mm: float | None = None

    def where(self, row: int) -> str:
        """Return ``file:line`` of data row ``row`` (0-based)."""
        return f"{self.source}:{int(self.lines[row])}"
