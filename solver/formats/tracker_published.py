"""Where the public laser-tracker sets are: a git clone as published, or compressed copies.

The sets are not in the repository (tests/data/tracker/<set>/PUBLISHED.md says where each
is published). A data folder (:func:`tracker_data_dir`) may hold, for each set:

* the publishing repository as cloned, ``<folder>/<repository>/<path there>``
  (``ipa-robot-accuracy/Series_B/measurements_joint_configurations.csv``), or the folder
  may be that clone itself (``<folder>/<path there>``);
* or the older compressed layout, ``<folder>/<set>/<name>.csv.gz`` (the same bytes, gzip
  compressed, under the names of :data:`PUBLISHED_SETS`).

:func:`locate_set` finds each file in that order; the readers take either
(:func:`~wirecal.solver.formats.tracker_sets.read_tracker`).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from wirecal.solver.errors import WirecalError

DATA_ENV = "WIRECAL_TRACKER_DATA"


@dataclass(frozen=True)
class PublishedSet:
    """One public set: the repository publishing it, the commit read, its files there.

    ``files`` pairs each file's path in the repository with its name in the compressed
    layout.
    """

    url: str
    commit: str
    files: tuple[tuple[str, str], ...]

    @property
    def clone(self) -> str:
        """Return the folder name ``git clone`` gives the repository."""
        return self.url.rsplit("/", 1)[1]


_JACOBI = "https://github.com/pauljac7700/serial_robots_datasets"
_JACOBI_COMMIT = "759068d85a8b95183cd71ff96d9dfc5173bc57fc"
PUBLISHED_SETS = {
    "ur10_ipa": PublishedSet(
        "https://github.com/christianlandgraf/ipa-robot-accuracy",
        "507fba69bdaf6c43c2faf306e70a7e37c5e39b89",
        (
            (
                "Series_B/measurements_joint_configurations.csv",
                "series_b_joint_configurations.csv.gz",
            ),
            ("Series_C/measurements_random_poses.csv", "series_c_random_poses.csv.gz"),
            ("Series_D/measurements_iso_cubes.csv", "series_d_iso_cubes.csv.gz"),
        ),
    ),
    "ur5_jacobi": PublishedSet(
        _JACOBI,
        _JACOBI_COMMIT,
        (
            ("UR5/3D_UR5_uncalibrated_grid_cleaned.csv", "ur5_grid.csv.gz"),
            ("UR5/3D_UR5_uncalibrated_random_cleaned.csv", "ur5_random.csv"),
        ),
    ),
    "wam_jacobi": PublishedSet(
        _JACOBI,
        _JACOBI_COMMIT,
        (
            ("WAM/3D_WAM_uncalibrated_grid_cleaned.csv", "wam_grid.csv.gz"),
            ("WAM/3D_WAM_uncalibrated_random_cleaned.csv", "wam_random.csv"),
        ),
    ),
}


def tracker_data_dir(repo: Path, given: Path | None = None) -> Path:
    """Return the folder holding the public sets (module docstring).

    ``given`` (a ``--data DIR``), else the environment's ``WIRECAL_TRACKER_DATA``, else
    ``<repo>/../shared/data/tracker`` (a copy of shared/ beside the clone).
    """
    if given is not None:
        return given
    env = os.environ.get(DATA_ENV)
    return Path(env) if env else repo.parent / "shared" / "data" / "tracker"


def locate_set(folder: Path, name: str, repo: Path) -> dict[str, Path]:
    """Return the files of public set ``name``, keyed by their path in its repository.

    Each file is taken from the first of: ``folder/<repository>/<path>``,
    ``folder/<path>``, ``folder/<name>/<compressed name>``.

    Raises
    ------
    WirecalError
        Naming the files missing, the ``git clone`` and commit that bring them, and the
        set's PUBLISHED.md under ``repo``.
    """
    published = PUBLISHED_SETS[name]
    found: dict[str, Path] = {}
    for path, packed in published.files:
        places = (folder / published.clone / path, folder / path, folder / name / packed)
        hit = next((p for p in places if p.is_file()), None)
        if hit is not None:
            found[path] = hit
    absent = [path for path, _ in published.files if path not in found]
    if not absent:
        return found
    clone = folder / published.clone
    raise WirecalError(
        f"public tracker set {name!r} is not in {folder} (missing {', '.join(absent)} of"
        f" {published.url}): clone it there as published,\n"
        f"    git clone {published.url} {clone}"
        f" && git -C {clone} checkout {published.commit}\n"
        f"  or point --data DIR or {DATA_ENV}=DIR at the folder holding {published.clone}/"
        f" ({repo / 'tests' / 'data' / 'tracker' / name / 'PUBLISHED.md'})"
    )
