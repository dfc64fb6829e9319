"""Joint angles and a laser tracker's measured tool points: the data of a tracker replay.

:class:`TrackerTable` holds the rows of a public data set or of any table with joints
j1…jn (degrees) and x, y, z (mm); :mod:`~wirecal.formats.tracker_table` and
:mod:`~wirecal.formats.tracker_sets` read files into it, the replay
(``bench/bench_tracker_replay.py``) and ``wirecal plan --pool`` use it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TrackerTable:
    """Rows in file order: joints (deg), the measured tool point (mm, the tracker's frame).

    ``lines`` are the 1-based file lines of the rows; ``temperature_c`` the air temperature
    of each row when the data set gives one.
    """

    source: str
    kind: str  # the data set's layout, in words
    lines: np.ndarray  # (N,) int
    q_deg: np.ndarray  # (N, n)
    xyz_mm: np.ndarray  # (N, 3)
    temperature_c: np.ndarray | None = None  # (N,)

    @property
    def n_joints(self) -> int:
        """Return the number of joint columns."""
        return int(self.q_deg.shape[1])

    def where(self, row: int) -> str:
        """Return ``file:line`` of data row ``row`` (0-based)."""
        return f"{self.source}:{int(self.lines[row])}"
