"""The generators, one per registered language: ``GENERATOR`` in ``wirecal.gen.<key>``.

:func:`generator` imports the package of a key the registry knows; adding a language adds
``gen/<key>/`` and never edits a list.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol

from wirecal.gen.request import GenRequest
from wirecal.lang.registry import language
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import RunParameters


class Generator(Protocol):
    """A language's program generator: deterministic texts from a robot, a plan, a request."""

    key: str  # the language key
    refuses: frozenset[str]  # GenRequest fields it does not take
    default_run: RunParameters  # the run when the request gives none

    def programs(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return file name → program text (deterministic); refuse unsupported fields by name."""
        ...

    def write(
        self,
        out_dir: str | Path,
        programs: dict[str, str],
        request: GenRequest,
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
    ) -> list[Path]:
        """Write ``programs`` into ``out_dir`` as the controller takes them; all or none."""
        ...

    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return the warnings about the robot file the programs depend on."""
        ...

    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return what to do with the written programs (after "wrote FILES: ")."""
        ...


def generator(key: str) -> Generator:
    """Return the generator of the registered language ``key`` (WirecalError if unknown)."""
    lang = language(key)
    found: Generator = importlib.import_module(f"wirecal.gen.{lang.key}").GENERATOR
    return found
