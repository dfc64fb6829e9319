"""The package layout: wirecal/<part> links to the top-level folder <part>, and setuptools finds
every package through the links, so a new package needs no edit of pyproject.toml.

The wheel holds the namespaced packages and their data, and nothing top-level generic.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from .conftest import ROOT

NOT_PACKAGED = {"tests"}
"""Top-level folders holding an ``__init__.py`` that are not parts of the package."""


def _packages(root: Path) -> set[str]:
    """The dotted names of the folders under ``root/wirecal`` holding an ``__init__.py``.

    The walk follows the links, as setuptools' package discovery does.
    """
    found = set()
    for folder, _, files in os.walk(root / "wirecal", followlinks=True):
        if "__init__.py" in files:
            found.add(".".join(Path(folder).relative_to(root).parts))
    return found


def test_every_top_level_package_folder_is_linked_into_wirecal():
    parts = {
        p.name for p in ROOT.iterdir() if (p / "__init__.py").is_file() and p.name != "wirecal"
    }
    linked = {p.name for p in (ROOT / "wirecal").iterdir() if p.is_symlink()}
    assert linked == parts - NOT_PACKAGED, (
        "a top-level package folder X needs the link wirecal/X -> ../X (ln -s ../X wirecal/X)"
    )
    for name in linked:
        assert os.readlink(ROOT / "wirecal" / name) == f"../{name}"  # relative: any checkout


def test_the_links_make_the_parts_subpackages():
    assert {"wirecal.formats", "wirecal.gen.vplus", "wirecal.twin.urscript"} <= _packages(ROOT)


@pytest.mark.slow
def test_wheel_holds_every_package_folder_and_a_new_one_with_no_pyproject_edit(tmp_path):
    # Build from a clean copy (a stale build/ folder could hide missing package data), with
    # the links kept as links, as in a checkout.
    src = tmp_path / "src"
    shutil.copytree(
        ROOT,
        src,
        symlinks=True,
        ignore=shutil.ignore_patterns(
            ".git", "build", "dist", "*.egg-info", "__pycache__", ".venv", ".*_cache"
        ),
    )
    # A new sub-package of a part, and a new part with its link: pyproject.toml is not touched.
    (src / "gen" / "newlang").mkdir()
    (src / "gen" / "newlang" / "__init__.py").write_text('"""A new backend."""\n')
    (src / "newpart").mkdir()
    (src / "newpart" / "__init__.py").write_text('"""A new part."""\n')
    (src / "wirecal" / "newpart").symlink_to("../newpart")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(tmp_path / "dist"),
            str(src),
        ],
        check=True,
    )
    wheel = next((tmp_path / "dist").glob("wirecal-*.whl"))
    names = zipfile.ZipFile(wheel).namelist()
    packaged = {n.removesuffix("/__init__.py").replace("/", ".") for n in names if "__init__" in n}
    assert packaged == _packages(src)
    assert {"wirecal.gen.newlang", "wirecal.newpart", "wirecal.lang.rapid"} <= packaged
    assert "wirecal/templates/text/psi.txt.j2" in names
    assert "wirecal/solver/kinematics.py" in names
    assert "wirecal/cli/main.py" in names
    assert "wirecal/lang/vplus/vplus.lark" in names
    assert "wirecal/gen/urscript/facts.py" in names
    assert "wirecal/app/receive.py" in names
    assert "wirecal/lang/vplus/keywords.csv" in names
    assert "wirecal/lang/urscript/parser.py" in names
    assert "wirecal/lang/urscript/urscript.lark" in names
    assert "wirecal/lang/urscript/functions.csv" in names
    assert "wirecal/py.typed" in names  # PEP 561: the package's type hints are for users too
    assert "wirecal/examples/viper_s650/robot.toml" in names
    assert "wirecal/examples/ur5e/robot.toml" in names
    assert "wirecal/templates/vplus/wirecal.v2.j2" in names
    top = {n.split("/")[0] for n in names}
    assert top <= {"wirecal", next(t for t in top if t.endswith(".dist-info"))}, top
