"""Generate the V+ module, then run it in the digital twin.

The composition of ``gen`` and ``twin`` (the twin itself only runs the programs it is given).
"""

from __future__ import annotations

from pathlib import Path

from wirecal.gen.vplus.program import GenOptions, module_text
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.twin.cell import Faults, RunResult, run_measurement


def measure_in_twin(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    disk: Path,
    *,
    options: GenOptions | None = None,
    text: str | None = None,
    seed: int = 0,
    noise_mm: float = 0.01,
    counter_start: float | None = None,
    faults: Faults | None = None,
) -> RunResult:
    """Run wc.mount and wc.run of a generated module on a twin robot.

    wc.mount (answered 1) and wc.run of the module generated with ``options`` (or of
    ``text``, generated with those options) on a twin robot with true offsets ``truth``.
    """
    options = options or GenOptions()
    text = text if text is not None else module_text(robot, plan, options)
    return run_measurement(
        robot,
        plan,
        truth,
        disk,
        text,
        log_file=options.log_file,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=counter_start,
        faults=faults or Faults(),
    )
