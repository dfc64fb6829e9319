"""Shared fixtures: the shipped Viper s650 example and small helpers.

Importing :mod:`tests.hypothesis_profiles` selects the Hypothesis profile (``ci`` under
``CI=true``, or the one ``HYPOTHESIS_PROFILE`` names).

:mod:`wirecal.cli.main` is imported before anything imports numpy, so the tests run as the
``wirecal`` command does: one BLAS thread (numpy's default starts a thread per core, which
spin and cost CPU beside the tests' small matrices) and the command's garbage-collector
thresholds, also for the commands the tests run in-process.
"""

from __future__ import annotations

import gc
from pathlib import Path

import pytest

import wirecal.cli.main  # noqa: F401  (first: one BLAS thread, its GC thresholds; docstring)
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot

from . import hypothesis_profiles  # noqa: F401  (selects the profile on import)

ROOT = Path(__file__).resolve().parents[1]
VIPER = ROOT / "examples" / "viper_s650"
DATA = Path(__file__).resolve().parent / "data"


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """Keep pytest's second collection at the end from walking every object again.

    pytest collects the garbage twice at the end (``unraisableexception``: once in its own
    ``pytest_unconfigure``, which runs before this one, and once in its clean-up after all of
    them), each a full collection of everything the session still holds (0.3 s of CPU
    apiece). The first finds every cycle left and reports what their finalizers raise; after
    it, what is alive is frozen, so the second walks only what the clean-ups make.
    """
    gc.freeze()


@pytest.fixture(scope="session")
def viper():
    return load_robot(VIPER / "robot.toml")


@pytest.fixture(scope="session")
def paper_plan(viper):
    return load_plan(VIPER / "paper_plan.toml", viper)


@pytest.fixture(scope="session")
def printed_plan(viper):
    return load_plan(VIPER / "paper_plan_as_printed.toml", viper)


@pytest.fixture(scope="session")
def viper_module(viper, paper_plan) -> str:
    """The V+ module of the Viper's paper plan (the default options), generated once."""
    from wirecal.gen.vplus.program import GenOptions, module_text

    from .twin_runs import generated

    return generated(module_text, viper, paper_plan, GenOptions())


@pytest.fixture(scope="session")
def viper_setup():
    """The Viper's shipped validation set-up (``validation.toml``)."""
    from wirecal.formats.validation_files import load_setup

    return load_setup(VIPER / "validation.toml")


@pytest.fixture(scope="session")
def viper_validation_module(viper, paper_plan, viper_setup) -> str:
    """The V+ module of the Viper's paper plan with the validation programs, generated once."""
    from wirecal.gen.vplus.program import GenOptions, module_text

    from .twin_runs import generated

    return generated(module_text, viper, paper_plan, GenOptions(validation=viper_setup))


def _table5() -> dict[str, float]:
    from wirecal.formats.truth import load_errors

    return load_errors(VIPER / "paper_table5_errors.toml", load_robot(VIPER / "robot.toml"))


TABLE5 = _table5()
"""The paper's Table 5 offsets (deg, mm): the true errors of most simulated Viper tests."""


@pytest.fixture(scope="session")
def table5() -> dict[str, float]:
    return dict(TABLE5)
