"""A simulated run written as a log: the text the controller program would have written.

The simulation (:func:`~wirecal.solver.simulate.simulate_run`) returns the readings and the
header's facts; this module writes them in the log format (:mod:`~wirecal.formats.log`),
with a comment that the truth is kept elsewhere, and the last line cut mid-write when the
run's faults ask for it.
"""

from __future__ import annotations

from wirecal.formats.log import format_header, format_row
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, RunParameters
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    NO_FAULTS,
    EncoderTruth,
    Faults,
    SimulatedRun,
    Unmodelled,
    simulate_run,
)

SIMULATED_NOTE = "simulated by wirecal; the truth is kept in a separate file"
"""The comment in a simulated log's header."""


def simulate_log(
    robot: Robot,
    plan: Plan,
    errors: dict[str, float],
    *,
    seed: int,
    noise_mm: float = 0.01,
    samples: int = 10,
    faults: Faults = NO_FAULTS,
    counter_start: float | None = None,
    mm_per_count: float | None = None,
    encoder: EncoderTruth = IDEAL_ENCODER,
    run: RunParameters = DEFAULT_RUN,
    unmodelled: Unmodelled | None = None,
) -> str:
    """Return the text of the log a run of ``plan`` on the true robot would write.

    The true robot is ``robot`` with the offsets ``errors``; the parameters are
    :func:`~wirecal.solver.simulate.simulate_run`'s, whose run :func:`simulated_log_text`
    writes.
    """
    return simulated_log_text(
        simulate_run(
            robot,
            plan,
            errors,
            seed=seed,
            noise_mm=noise_mm,
            samples=samples,
            faults=faults,
            counter_start=counter_start,
            mm_per_count=mm_per_count,
            encoder=encoder,
            run=run,
            unmodelled=unmodelled,
        )
    )


def simulated_log_text(run: SimulatedRun) -> str:
    """Return the log's text of ``run``: its header and rows, the last cut if it asks."""
    rows = [format_row(r) for r in run.readings]
    text = format_header(
        run.robot, run.plan, run.mm_per_count, (SIMULATED_NOTE,), payload_kg=run.payload_kg
    )
    text += "\n".join(rows) + ("\n" if rows else "")
    if run.truncate_last and rows:
        text = text[: -(len(rows[-1]) // 2) - 1]
    return text
