"""Read back the per-joint vectors of a language's file beside a patch (its patch companion).

A language whose companion holds per-joint vectors declares where
(:attr:`~wirecal.lang.base.Language.companion_vectors`: the table and its keys); URScript's
is UR's standard-DH deltas in calibration.conf's layout
(:mod:`wirecal.lang.urscript.calibration`, UNCONFIRMED key names from the ROS driver's
documentation).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wirecal.formats.fileio import read_toml
from wirecal.formats.toml_fields import document
from wirecal.lang.base import Language
from wirecal.solver.errors import WirecalError


def read_companion(path: str | Path, lang: Language, n_joints: int = 6) -> dict[str, np.ndarray]:
    """Read the companion's vectors back by key (the language's units: UR's m and rad).

    The file ``lang``'s :meth:`~wirecal.lang.base.Language.patch_section` writes. Each
    key a list of ``n_joints`` finite numbers; any other key or table is refused.
    """
    if lang.companion_vectors is None:
        raise WirecalError(f"{path}: the {lang.title} patch companion holds no joint vectors")
    name, keys = lang.companion_vectors
    what = f"{lang.title} patch companion"
    doc = document(read_toml(path, what), str(path), "patch companion", (name,))
    table = doc.table(name, keys)
    values = {key: table.vector(key, length=n_joints, labels="(one per joint)") for key in keys}
    doc.raise_if_any()
    return {key: np.asarray(v) for key, v in values.items()}
