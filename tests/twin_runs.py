"""The tests' language-specific twin runs: V+'s module and URScript's scripts with their options.

``measure_in_twin`` (V+: ``GenOptions``, a module's text, the operator at a PAUSE, the
encoder's truth) and ``measure_ur_in_twin`` (URScript: ``UrOptions``, where the encoder is
wired, nobody listening, what ``wirecal receive`` got). The public, language-neutral run is
:func:`wirecal.app.twin_runs.measure_in_twin`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from wirecal.app.receive import Received, journal_path, receive
from wirecal.gen.urscript.program import UrOptions, pc_address, scripts
from wirecal.gen.vplus.program import MODULE_NAME, GenOptions, module_text
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import IDEAL_ENCODER, EncoderTruth, Unmodelled
from wirecal.twin.urscript.runs import ADAPTER as UR_ADAPTER
from wirecal.twin.vplus.runs import run_measurement
from wirecal.twin.world import Faults, TwinRun

_GENERATED: dict[tuple, tuple[Robot, Plan, Any]] = {}


def generated(render: Callable[[Robot, Plan, Any], Any], robot: Robot, plan: Plan, options):
    """Return ``render(robot, plan, options)``, generated once a session for these objects.

    A generator gives the same text for the same robot, plan and options (test_gen.py's
    ``test_deterministic`` checks it); the tests share it instead of generating it again.
    The robot and plan are kept with the text, so their ids stay theirs.
    """
    key = (render, id(robot), id(plan), repr(options))
    hit = _GENERATED.get(key)
    if hit is None:
        hit = _GENERATED[key] = (robot, plan, render(robot, plan, options))
    return hit[2]


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
    proceed_on_pause: bool = False,
    encoder_truth: EncoderTruth = IDEAL_ENCODER,
) -> TwinRun:
    """Run wc.mount and wc.run of a generated module on a twin robot.

    wc.mount (answered 1) and wc.run of the module generated with ``options`` (or of
    ``text``, generated with those options) on a twin robot with true offsets ``truth``.
    """
    options = options or GenOptions()
    text = text if text is not None else generated(module_text, robot, plan, options)
    return run_measurement(
        robot,
        plan,
        truth,
        disk,
        {MODULE_NAME: text},
        log_file=options.log_file,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=counter_start,
        faults=faults,
        proceed_on_pause=proceed_on_pause,
        encoder_truth=encoder_truth,
    )


@dataclass
class URRun:
    """A URScript measurement run in the twin: the programs' run and what the PC got."""

    programs: TwinRun
    received: Received

    @property
    def log(self) -> Path:
        """Return the log: the complete one, or the journal of an incomplete run."""
        return self.received.log if self.received.complete else self.received.journal


def measure_ur_in_twin(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    folder: Path,
    *,
    options: UrOptions | None = None,
    texts: dict[str, str] | None = None,
    seed: int = 0,
    noise_mm: float = 0.01,
    counter_start: float | None = None,
    faults: Faults | None = None,
    pulse_inputs: tuple[int, int] | None = None,
    pc_listening: bool = True,
    timeout_s: float = 30.0,
    unmodelled: Unmodelled | None = None,
) -> URRun:
    """Run wc_mount and wc_run on a twin UR with ``wirecal receive`` taking the log.

    The programs are ``texts`` (by file name), or generated with ``options``. The receiver
    listens on a free loopback port in a thread and writes ``folder/run.csv``; the twin
    routes the program's PC address there, so the rows travel over a real TCP socket.
    With ``pc_listening`` False nobody listens (the connection is refused).
    ``pulse_inputs``: where the encoder is really wired (default: as the robot file says).
    ``counter_start``: the raw count at zero wire length (default: drawn over the whole
    int32 range).
    """
    options = options or UrOptions()
    texts = texts if texts is not None else dict(generated(scripts, robot, plan, options))
    got: list[Received] = []

    def listen(log: Path, on_listening: Callable[[int], None]) -> Received:
        got.append(receive(0, log, robot, plan, timeout_s=timeout_s, on_listening=on_listening))
        return got[0]

    run = UR_ADAPTER.measure(
        robot,
        plan,
        truth,
        folder,
        texts,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=counter_start,
        faults=faults,
        unmodelled=unmodelled,
        pulse_inputs=pulse_inputs,
        pc=pc_address(robot, options),
        listen=listen if pc_listening else None,
        timeout_s=timeout_s,
    )
    received = got[0] if got else Received(run.log, journal_path(run.log))
    return URRun(run, received)
