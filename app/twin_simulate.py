"""``wirecal simulate --controller``: the measurement programs run in the digital twin.

The generated programs of the robot's controller language run on a twin robot with the
true errors; what they log is the simulated log, and where they stopped (if they did) is
said in a line the command prints.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import RunParameters
from wirecal.solver.simulate import EncoderTruth
from wirecal.twin.run_moves import move_of_step, where_in_run
from wirecal.twin.world import Faults as TwinFaults
from wirecal.twin.world import World


def simulate_in_twin(
    rb: Robot,
    pl: Plan,
    errors: dict[str, float],
    seed: int,
    noise_mm: float,
    samples: int,
    slip: tuple[int, float] | None,
    counter_start: float | None,
    true_encoder: EncoderTruth,
) -> tuple[str, str | None]:
    """Run the measurement programs in the twin; return the log text and why they stopped.

    V+: wc.mount and wc.run write the log on the cell's disk. URScript: wc_mount and wc_run
    send it over a loopback socket to wirecal receive (the journal of an incomplete run).
    ``slip``: (step, mm) of a wire slip; ``samples``: readings averaged per point.
    """
    faults = TwinFaults()
    if slip is not None:
        faults = TwinFaults(slip_at_move=move_of_step(pl, slip[0]), slip_mm=slip[1])
    run = RunParameters(readings=samples)
    kw: dict[str, Any] = dict(
        seed=seed, noise_mm=noise_mm, counter_start=counter_start, faults=faults
    )
    world: World  # keeps the moves and the console
    with tempfile.TemporaryDirectory() as tmp:
        if rb.controller.language == "urscript":
            from wirecal.app.twin_runs import measure_ur_in_twin
            from wirecal.gen.urscript.program import UrOptions

            ur = measure_ur_in_twin(rb, pl, errors, Path(tmp), options=UrOptions(run=run), **kw)
            mount, outcome, world = ur.programs.mount, ur.programs.run, ur.programs.world
            log, first = ur.log, "wc_mount"
        else:
            from wirecal.app.twin_runs import measure_in_twin
            from wirecal.gen.vplus.program import GenOptions

            vp = measure_in_twin(
                rb,
                pl,
                errors,
                Path(tmp),
                options=GenOptions(run=run),
                encoder_truth=true_encoder,
                **kw,
            )
            mount, outcome, world = vp.mount, vp.run, vp.world
            log, first = vp.log, "wc.mount"
        text = log.read_text(encoding="ascii") if log.exists() else ""
    outcome = outcome or mount
    stopped = None
    if outcome.status != "completed":
        where = where_in_run(pl, world.moves) if outcome is not mount else first
        stopped = (
            f"{outcome.message} at {where} ({outcome.status} in {outcome.program} line "
            f"{outcome.line}): " + " / ".join(world.console[-4:])
        )
    return text, stopped
