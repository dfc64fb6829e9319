"""Read back the standard-DH deltas written beside a UR robot's patch.

The file's layout and what the deltas are: :mod:`wirecal.lang.urscript.calibration`
(UNCONFIRMED key names, from the ROS driver's documentation).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wirecal.lang.urscript.calibration import KEYS
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.formats.toml_fields import document


def read_ur_calibration(path: str | Path, n_joints: int = 6) -> dict[str, np.ndarray]:
    """Read the deltas back (m, rad): the ``[mounting]`` table the patch companion holds.

    The file :func:`~wirecal.lang.urscript.calibration.calibration_text` writes. Each key
    a list of ``n_joints`` finite numbers; any other key or table is refused.
    """
    doc = document(
        read_toml(path, "UR calibration file"), str(path), "UR calibration file", ("mounting",)
    )
    table = doc.table("mounting", KEYS)
    values = {key: table.vector(key, length=n_joints, labels="(one per joint)") for key in KEYS}
    doc.raise_if_any()
    return {key: np.asarray(v) for key, v in values.items()}
