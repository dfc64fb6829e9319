"""The Hypothesis profiles of tests/hypothesis_profiles.py: ``ci`` draws the same examples on every
run, ``explore`` new ones."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

PROPERTY = """
import os
from hypothesis import given, strategies as st

@given(st.integers())
def test_draw(x):
    with open(os.environ["DRAWS"], "a") as f:
        f.write(f"{x}\\n")
"""


def draws(folder: Path, profile: str, run: int) -> list[str]:
    out = folder / f"{profile}{run}.txt"
    env = {**os.environ, "HYPOTHESIS_PROFILE": profile, "DRAWS": str(out)}
    subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_draw.py"],
        cwd=folder,
        env=env,
        check=True,
        capture_output=True,
    )
    return out.read_text().split()


@pytest.fixture
def folder(tmp_path):
    shutil.copy(Path(__file__).with_name("hypothesis_profiles.py"), tmp_path / "conftest.py")
    (tmp_path / "test_draw.py").write_text(PROPERTY)
    return tmp_path


@pytest.mark.slow
def test_ci_profile_draws_the_same_examples_every_run(folder):
    first = draws(folder, "ci", 1)
    assert len(first) == 100  # Hypothesis's default count: the profile leaves it
    assert draws(folder, "ci", 2) == first


@pytest.mark.slow
def test_explore_profile_draws_new_examples(folder):
    first = draws(folder, "explore", 1)
    assert len(first) == 1000
    assert draws(folder, "explore", 2) != first


def test_ci_profile_keeps_no_database_and_no_deadline():
    """No replay of a failure found elsewhere, no timing flakes on a loaded machine."""
    from hypothesis import settings

    from . import hypothesis_profiles  # noqa: F401  (registers the profiles)

    ci = settings.get_profile("ci")
    assert (ci.derandomize, ci.database, ci.deadline) == (True, None, None)
