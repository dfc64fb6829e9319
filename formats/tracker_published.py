"""Where the public laser-tracker sets are: a git clone as published, or compressed copies.

The sets are not in the repository (tests/data/tracker/<set>/PUBLISHED.md says where each
is published). A data folder (:func:`tracker_data_dir`) may hold, for each set:

* the publishing repository as cloned, ``<folder>/<repository>/<path there>``
  (``ipa-robot-accuracy/Series_B/measurements_joint_configurations.csv``), or the folder
  may be that clone itself (``<folder>/<path there>``);
* or the older compressed layout, ``<folder>/<set>/<name>.csv.gz`` (the same bytes, gzip
  compressed, under the names of :data:`PUBLISHED_SETS`).

:func:`locate_set` finds each file in that order; the readers take either
(:func:`~wirecal.formats.tracker_sets.read_tracker`).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path

from wirecal.formats.tracker_table import read_text
from wirecal.solver.errors import WirecalError

DATA_ENV = "WIRECAL_TRACKER_DATA"


@dataclass(frozen=True)
class PublishedSet:
    """One public set: the repository publishing it, the commit read, its files there.

    ``files``: each file's path in the repository, its name in the compressed layout and
    its git blob id at ``commit`` (``git ls-tree``: the SHA-1 of its bytes, see
    :func:`unpublished`).
    """

    url: str
    commit: str
    files: tuple[tuple[str, str, str], ...]

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
                "be2de9e38f0d656687078b6ecf4b3fa8972eb5e7",
            ),
            (
                "Series_C/measurements_random_poses.csv",
                "series_c_random_poses.csv.gz",
                "2c3da0a57afb9419c03f8cc5642662d609906b98",
            ),
            (
                "Series_D/measurements_iso_cubes.csv",
                "series_d_iso_cubes.csv.gz",
                "0b1c786d99513fc6cb58d1efb4ba3d368193e8ce",
            ),
        ),
    ),
    "ur5_jacobi": PublishedSet(
        _JACOBI,
        _JACOBI_COMMIT,
        (
            (
                "UR5/3D_UR5_uncalibrated_grid_cleaned.csv",
                "ur5_grid.csv.gz",
                "258137a56aae5b1ab7b1de39991d99d28ecb8301",
            ),
            (
                "UR5/3D_UR5_uncalibrated_random_cleaned.csv",
                "ur5_random.csv",
                "ed302f8a4e17ec1b63ca2e07e537383d67d8a05e",
            ),
        ),
    ),
    "wam_jacobi": PublishedSet(
        _JACOBI,
        _JACOBI_COMMIT,
        (
            (
                "WAM/3D_WAM_uncalibrated_grid_cleaned.csv",
                "wam_grid.csv.gz",
                "d70786b21ceeca64f133ce3dbfd5d1b8742b06a3",
            ),
            (
                "WAM/3D_WAM_uncalibrated_random_cleaned.csv",
                "wam_random.csv",
                "9f048adc6704de8bbeb06b1670befbac3d82cd76",
            ),
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
    for path, packed, _blob in published.files:
        places = (folder / published.clone / path, folder / path, folder / name / packed)
        hit = next((p for p in places if p.is_file()), None)
        if hit is not None:
            found[path] = hit
    absent = [path for path, *_ in published.files if path not in found]
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


def unpublished(name: str, files: dict[str, Path]) -> list[str]:
    """Return the files of set ``name`` whose bytes are not those published at its commit.

    ``files`` as :func:`locate_set` returns them; each differing one as ``path there (file
    here)``. The bytes (inflated when compressed) are hashed as git hashes a blob (SHA-1
    of ``blob <size>``, a NUL byte, the bytes) and compared with the blob id there.
    Another commit, an edited copy or line endings converted on checkout differ: the
    figures in docs/benchmarks.md were measured on the published bytes.
    """
    blobs = {path: blob for path, _packed, blob in PUBLISHED_SETS[name].files}
    differ = []
    for path, file in files.items():
        raw = read_text(file)[0].encode("utf-8")
        if hashlib.sha1(b"blob %d\0" % len(raw) + raw).hexdigest() != blobs[path]:
            differ.append(f"{path} ({file})")
    return differ
