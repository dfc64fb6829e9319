"""``wirecal simulate --controller``: the measurement programs run in the digital twin.

The generated programs of the robot's controller language run on a twin robot with the
true errors; what they log is the simulated log, and where they stopped (if they did) is
said in a line the command prints.
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

from wirecal.app.languages import registered
from wirecal.gen.request import GenRequest
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import EncoderTruth, declared_unmodelled
from wirecal.twin.run_moves import move_of_step, where_in_run
from wirecal.twin.world import Faults as TwinFaults


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
    *,
    echo: bool = False,
) -> tuple[str, str | None, list[str]]:
    """Run the measurement programs in the twin; the log text, why they stopped, the console.

    ``echo``: the run also shows every log row on the console where the language can
    choose (V+ ``gen --echo-log``; URScript's log tab and RAPID's FlexPendant always do),
    so the console is what an operator would copy and paste into ``wirecal solve -``.

    The robot's language's programs in its twin adapter (:func:`wirecal.app.languages.registered`):
    a log file on the controller's disk, or sent over a loopback socket to wirecal receive
    (the journal of an incomplete run).
    ``slip``: (step, mm) of a wire slip; ``samples``: readings averaged per point.
    """
    faults = TwinFaults()
    if slip is not None:
        faults = TwinFaults(slip_at_move=move_of_step(pl, slip[0]), slip_mm=slip[1])
    kw: dict[str, Any] = dict(
        seed=seed, noise_mm=noise_mm, counter_start=counter_start, faults=faults
    )
    reg = registered(rb)
    run = replace(reg.generator.default_run, readings=samples)  # as wirecal gen runs
    echo_log = echo and "echo_log" not in reg.generator.refuses
    programs = reg.generator.programs(rb, pl, GenRequest(run=run, echo_log=echo_log))
    if (unmodelled := declared_unmodelled(rb)) is not None:  # the arm lands as declared
        kw["unmodelled"] = unmodelled
    if reg.adapter.capabilities.encoder_truth:
        kw["encoder_truth"] = true_encoder
    with tempfile.TemporaryDirectory() as tmp:
        twin = reg.measure(rb, pl, errors, Path(tmp), programs, **kw)
        mount, outcome, world = twin.mount, twin.run, twin.world
        log, first = twin.log, mount.program
        text = log.read_text(encoding="ascii") if log.exists() else ""
    outcome = outcome or mount
    stopped = None
    if outcome.status != "completed":
        where = where_in_run(pl, world.moves) if outcome is not mount else first
        stopped = (
            f"{outcome.message} at {where} ({outcome.status} in {outcome.program} line "
            f"{outcome.line}): " + " / ".join(world.console[-4:])
        )
    return text, stopped, list(world.console)
