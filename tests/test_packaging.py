"""The wheel holds the namespaced packages and the templates, and nothing top-level generic."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile

import pytest

from .conftest import ROOT


@pytest.mark.slow
def test_wheel_contains_templates_under_the_namespace(tmp_path):
    # Build from a clean copy: a stale build/ folder could hide missing package data.
    src = tmp_path / "src"
    shutil.copytree(
        ROOT,
        src,
        ignore=shutil.ignore_patterns(
            ".git", "build", "dist", "*.egg-info", "__pycache__", ".venv", ".*_cache"
        ),
    )
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
    assert "wirecal/templates/text/psi.txt.j2" in names
    assert "wirecal/templates/__init__.py" in names
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
    assert "wirecal/__init__.py" in names
    assert "wirecal/examples/viper_s650/robot.toml" in names
    assert "wirecal/examples/ur5/robot.toml" in names
    assert "wirecal/templates/vplus/wirecal.v2.j2" in names
    top = {n.split("/")[0] for n in names}
    assert top <= {"wirecal", next(t for t in top if t.endswith(".dist-info"))}, top
