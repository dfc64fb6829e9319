"""A toy controller language, registered only in the tests: what a fourth language writes.

Its declaration (:class:`Toy`: capabilities and a checker), its rendering
(:class:`ToyGenerator`: ``render``, ``write``, ``notes``, ``next_steps``) and its twin
(:class:`ToyAdapter`: an interpreter of ``MOVE``/``READ`` lines over the world's one move
protocol). Everything else — the pre-flight, the checker run over the output, the twin's
limits, collisions and wire checks, the run factory — it gets from the shared code;
:func:`registered_toy` registers it for the length of a test module.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from wirecal.gen.backends import Generator
from wirecal.gen.request import GenRequest
from wirecal.gen.targets import joint_literal
from wirecal.lang import registry
from wirecal.lang.base import Capabilities, Language
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN
from wirecal.twin.adapters import TwinAdapter
from wirecal.twin.machine import Outcome, RunError
from wirecal.twin.world import (
    BeyondLimit,
    Collision,
    Faults,
    TwinRun,
    WireOverspeed,
    World,
    measurement_world,
    mount_then_run,
    stop_reason,
)

KEY = "toy"
MOUNT, RUN = "mount.toy", "run.toy"
SPEED_PCT = 5.0
"""The toy controller's one speed: slow enough for the examples' wire limits."""


class Toy(Language):
    """The toy language: a program is ``MOVE <deg> …`` and ``READ`` lines."""

    key = KEY
    title = "Toy"
    suffix = ".toy"
    live_check = MOUNT
    capabilities = Capabilities(
        int_bits=None,
        float_bits=64,
        file_io=True,
        sockets=False,
        encoder_interfaces=("toy",),
        counter_bits=32,
        software_lines={},
    )

    def lint(
        self, text: str, source: str, software: str | None = None, *, external_calls: bool = False
    ) -> list[str]:
        """Return a problem per line that is neither ``MOVE`` with numbers nor ``READ``."""
        problems = []
        for n, line in enumerate(text.splitlines(), 1):
            word, *args = line.split()
            if not (line == "READ" or (word == "MOVE" and args and all(map(_number, args)))):
                problems.append(f"{source}:{n}: not MOVE <deg>… or READ: {line!r}")
        return problems


def _number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _move(q_deg: np.ndarray) -> str:
    return "MOVE " + " ".join(joint_literal(x) for x in q_deg)


class ToyGenerator(Generator):
    """The toy's rendering: the run's moves in plan order, a READ at each stop."""

    key = KEY
    refuses = frozenset(
        {"solver", "patch", "validation", "host", "port", "log_file", "echo_log", "crlf"}
    )
    default_run = DEFAULT_RUN

    def render(self, robot: Robot, plan: Plan, request: GenRequest) -> dict[str, str]:
        """Return the mounting program (to θ0) and the run (θ0, vias, points per step, θ0)."""
        home = _move(plan.theta0_deg)
        lines = []
        for step in plan.steps:
            lines += [home, "READ", *map(_move, step.via_deg)]
            lines += [x for q in step.points_deg for x in (_move(q), "READ")]
        lines += [home, "READ"]
        return {MOUNT: home + "\n", RUN: "\n".join(lines) + "\n"}

    def write(
        self,
        out_dir: str | Path,
        programs: dict[str, str],
        request: GenRequest,
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
    ) -> list[Path]:
        """Write the programs as they are."""
        paths = [Path(out_dir) / name for name in programs]
        for path, text in zip(paths, programs.values(), strict=True):
            path.write_text(text, encoding="ascii")
        return paths

    def notes(self, robot: Robot, robot_path: str) -> list[str]:
        """Return nothing: the toy depends on no controller fact."""
        return []

    def next_steps(
        self, robot: Robot, plan: Plan, request: GenRequest, robot_path: str, plan_path: str
    ) -> str:
        """Return the order to run the programs in."""
        return f"run {MOUNT}, then {RUN}"


def _execute(world: World, text: str, name: str) -> Outcome:
    """Run a toy program on the world: each refusal is the toy controller's own stop."""
    for n, line in enumerate(text.splitlines(), 1):
        word, *args = line.split()
        try:
            if word == "READ":
                world.read_count()
                continue
            q = np.array([float(a) for a in args])
            match world.move(q, SPEED_PCT):
                case BeyondLimit(joint=j):
                    return Outcome("error", name, n, f"TOY STOP: joint {j + 1} beyond its limit")
                case Collision(where=where):
                    return Outcome("error", name, n, f"TOY STOP: collision: {where}")
                case WireOverspeed(move=move, why=why):
                    return Outcome("error", name, n, f"TOY STOP: {move}: {why}")
        except RunError as exc:
            return Outcome("error", name, n, exc.message)
    return Outcome("completed", name)


class ToyAdapter(TwinAdapter):
    """The toy's twin: its programs, line by line, on the run factory's world."""

    key = KEY

    def measure(
        self,
        robot: Robot,
        plan: Plan,
        truth: dict[str, float],
        folder: Path,
        programs: dict[str, str],
        *,
        seed: int = 0,
        noise_mm: float = 0.01,
        counter_start: float | None = None,
        faults: Faults | None = None,
        unmodelled: Any = None,
    ) -> TwinRun:
        """Run the mounting program, then the run."""
        world = measurement_world(
            robot,
            plan,
            truth,
            folder,
            robot.encoder.counter,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=counter_start,
            faults=faults,
            unmodelled=unmodelled,
        )
        mount, run = mount_then_run(
            world,
            lambda: _execute(world, programs[MOUNT], MOUNT),
            lambda: _execute(world, programs[RUN], RUN),
        )
        stopped = stop_reason(mount, run)
        return TwinRun(folder / "toy.log", stopped is None, stopped, world, mount, run)

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        lengths_mm: np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Return nothing: the toy has no controller solver."""
        return {}


@contextmanager
def registered_toy() -> Iterator[None]:
    """Register the toy (language, generator, twin adapter) for the block; then remove it."""
    registry.languages()  # the real ones first
    modules = {
        f"wirecal.gen.{KEY}": SimpleNamespace(GENERATOR=ToyGenerator()),
        f"wirecal.twin.{KEY}": SimpleNamespace(ADAPTER=ToyAdapter()),
    }
    registry.register(Toy)
    sys.modules.update(modules)  # type: ignore[arg-type]
    importlib.invalidate_caches()
    try:
        yield
    finally:
        del registry._REGISTERED[KEY]
        for name in modules:
            del sys.modules[name]
