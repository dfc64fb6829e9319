"""The generators, one per registered language: ``GENERATOR`` in ``wirecal.gen.<key>``.

Every generator is a :class:`Generator`: its :meth:`~Generator.programs` refuses the
request fields the language does not take, runs the pre-flight
(:func:`~wirecal.gen.preflight.preflight`), then the language's rendering
(:meth:`~Generator.render`), then the language's own checker over the output
(:func:`~wirecal.gen.preflight.output_problems`). A language writes the rendering only and
cannot skip a duty. :func:`generator` imports the package of a key the registry knows;
adding a language adds ``gen/<key>/`` and never edits a list.
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from collections.abc import Iterable
from pathlib import Path
from typing import ClassVar, final

from wirecal.gen.preflight import output_problems, preflight
from wirecal.gen.request import GenRequest, refuse_unsupported, with_slip_tolerance
from wirecal.lang.base import Language
from wirecal.lang.registry import language
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import RunParameters


class Generator(ABC):
    """A language's program generator: deterministic texts from a robot, a plan, a request."""

    key: ClassVar[str]  # the language key
    refuses: ClassVar[frozenset[str]]  # GenRequest fields it does not take
    default_run: ClassVar[RunParameters]  # the run when the request gives none
    payload_step: ClassVar[bool] = False  # its programs prompt for a plan's payload step

    def __init_subclass__(cls, **kwargs: object) -> None:
        """Refuse a language's generator that replaces :meth:`programs` (and its duties)."""
        super().__init_subclass__(**kwargs)
        if "programs" in vars(cls):
            raise TypeError(
                f"{cls.__name__}: a language's generator renders only (render()); "
                "programs() and its pre-flight and checks are the base's"
            )

    @property
    def language(self) -> Language:
        """The registered language this generator writes."""
        return language(self.key)

    @final
    def programs(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return file name → program text (deterministic), every duty done.

        Refuses the request's fields the language does not take (by option), then a plan
        the pre-flight refuses, then programs its own checker refuses. The zero readings'
        slip check takes the arm's declared repeatability (:func:`with_slip_tolerance`).
        """
        lang = self.language
        refuse_unsupported(request, self.refuses, lang.title)
        if plan.payload_step is not None and not self.payload_step:
            raise WirecalError(
                f"{plan.source}: the plan has a payload step (a mass mounted at the flange); "
                f"the {lang.title} programs do not prompt for it: plan without "
                "[calibration] payload_kg for this controller"
            )
        preflight(robot, plan, request, lang)
        out = self.render(robot, plan, with_slip_tolerance(robot, plan, request))
        problems = output_problems(robot, out, lang)
        if problems:
            raise WirecalError(self.checker_problems(robot, problems))
        return out

    @abstractmethod
    def render(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return the programs by file name for a plan the pre-flight passed: rendering only."""

    def checker_problems(self, robot: Robot, problems: list[str]) -> list[str]:
        """Return what to tell of the checker's problems with the rendered programs.

        By default a generator defect; a language whose checker refuses what the declared
        software lacks names those as the user's problem instead.
        """
        head = f"internal error: the generated {self.language.title} programs break its rules"
        return [f"{head} (please report):", *problems[:20]]

    @abstractmethod
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

    @abstractmethod
    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return the warnings about the robot file the programs depend on."""

    @abstractmethod
    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return what to do with the written programs (after "wrote FILES: ")."""


def generator(key: str) -> Generator:
    """Return the generator of the registered language ``key`` (WirecalError if unknown)."""
    lang = language(key)
    found: Generator = importlib.import_module(f"wirecal.gen.{lang.key}").GENERATOR
    return found
