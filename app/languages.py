"""The registered controller languages as app/ and cli/ use them: one place to dispatch.

Nothing above this module compares a language key with a name: it asks :func:`registered`
for the robot's language, its generator and its twin adapter.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from wirecal.gen.backends import Generator, generator
from wirecal.lang.base import Language
from wirecal.lang.registry import language
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.adapters import TwinAdapter, adapter

if TYPE_CHECKING:  # the receiver only when a twin run needs it
    from wirecal.app.receive import Received


@dataclass(frozen=True)
class Registered:
    """A registered language with its generator and its twin adapter."""

    language: Language
    generator: Generator

    @property
    def adapter(self) -> TwinAdapter:
        """The language's twin adapter (:func:`wirecal.twin.adapters.adapter`)."""
        return adapter(self.language.key)

    def measure(
        self,
        robot: Robot,
        plan: Plan,
        truth: dict[str, float],
        folder: Path,
        programs: dict[str, str],
        *,
        timeout_s: float = 30.0,
        **options: Any,
    ) -> Any:
        """Run the programs in the twin with the PC's side: the adapter's measure.

        For a language that sends its log over TCP (``capabilities.sockets``), ``wirecal
        receive`` (:func:`wirecal.app.receive.receive`) listens on a free loopback port
        and the adapter routes the program's PC address there; otherwise the log is the
        file the programs write. ``options``: the adapter's (seed, faults, …).
        """
        if self.language.capabilities.sockets:
            from wirecal.app.receive import receive

            def listen(log: Path, on_listening: Callable[[int], None]) -> Received:
                return receive(0, log, robot, plan, timeout_s=timeout_s, on_listening=on_listening)

            options = {"listen": listen, "timeout_s": timeout_s, **options}
        return self.adapter.measure(robot, plan, truth, folder, programs, **options)


def registered(robot_or_key: Robot | str) -> Registered:
    """Return the language of a robot (its ``[controller] language``) or of a key, registered.

    A WirecalError names the known keys for an unknown one.
    """
    key = robot_or_key if isinstance(robot_or_key, str) else robot_or_key.controller.language
    return Registered(language(key), generator(key))


def language_mismatch(robot: Robot, key: str) -> str:
    """Return the one message for a language other than the robot file's (gen refuses it).

    The file's ``[encoder]`` interface and counter width belong to its language's programs
    (:attr:`~wirecal.lang.base.Capabilities.encoder_interfaces`), so another language cannot
    read the same encoder set-up.
    """
    enc = robot.encoder
    return (
        f"{robot.source}: [controller] language is {robot.controller.language!r} "
        f'(encoder interface "{enc.interface}", a {enc.counter_bits}-bit counter), not '
        f"{key!r}: the encoder set-up belongs to the language, so --language cannot "
        f"switch it. For {language(key).title}, write a robot file with language = "
        f'"{key}" and its encoder keys (import-urdf --language {key} does), or '
        "drop --language"
    )
