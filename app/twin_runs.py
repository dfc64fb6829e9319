"""Generate a controller's programs, then run them in the digital twin, in any language.

The composition of ``gen`` and ``twin`` (the twin itself only runs the programs it is
given), through the registry: the robot file's language's generator and twin adapter
(:func:`wirecal.app.languages.registered`); a language that sends its log over a socket
has it taken by :func:`wirecal.app.receive.receive`, the very function behind ``wirecal
receive``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from wirecal.app.languages import registered
from wirecal.gen.request import GenRequest
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.world import TwinRun


def generate(robot: Robot, plan: Plan, request: GenRequest | None = None) -> dict[str, str]:
    """Return the programs of the robot file's language by file name, as ``wirecal gen``.

    Every duty done (:meth:`wirecal.gen.backends.Generator.programs`: the pre-flight, the
    rendering, the language's own checker); a WirecalError names what is refused.
    """
    return registered(robot).generator.programs(robot, plan, request or GenRequest())


def write_programs(
    robot: Robot,
    out_dir: str | Path,
    programs: dict[str, str],
    request: GenRequest | None = None,
    *,
    force: bool = False,
) -> list[Path]:
    """Write ``programs`` into ``out_dir`` as the robot's controller takes them; all or none."""
    gen = registered(robot).generator
    return gen.write(out_dir, programs, request or GenRequest(), force=force)


def measure_in_twin(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    folder: Path,
    programs: dict[str, str] | None = None,
    *,
    request: GenRequest | None = None,
    timeout_s: float = 30.0,
    **options: Any,
) -> TwinRun:
    """Run the mounting and measurement programs on a twin robot with true offsets ``truth``.

    ``programs``: the generated ones (default: :func:`generate` with ``request``);
    ``options``: the twin adapter's (``seed``, ``noise_mm``, ``counter_start``,
    ``faults``, ``unmodelled``, and what a language's adapter declares,
    :class:`~wirecal.twin.adapters.AdapterCapabilities`). The log is ``TwinRun.log``.
    """
    reg = registered(robot)
    if programs is None:
        programs = generate(robot, plan, request)
    return reg.measure(robot, plan, truth, folder, programs, timeout_s=timeout_s, **options)
