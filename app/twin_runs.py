"""Generate the V+ module, then run it in the digital twin.

The composition of ``gen`` and ``twin`` (the twin itself only runs the programs it is given).
"""

from __future__ import annotations

import socket
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.app.receive import Received, journal_path, receive
from wirecal.gen.urscript.program import UrOptions, pc_address, scripts
from wirecal.gen.vplus.program import GenOptions, module_text
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import IDEAL_ENCODER, EncoderTruth
from wirecal.twin.cell import Faults, RunResult, Unmodelled, run_measurement
from wirecal.twin.ur_cell import RAW, URCell, URPrograms, run_ur_programs


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
        proceed_on_pause=proceed_on_pause,
        encoder_truth=encoder_truth,
    )


@dataclass
class URRun:
    """A URScript measurement run in the twin: the programs' outcomes and what the PC got."""

    programs: URPrograms
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
    (:func:`wirecal.app.receive.receive`, the very function behind ``wirecal receive``)
    listens on a free loopback port in a thread and writes ``folder/run.csv``; the cell
    routes the program's PC address there, so the rows travel over a real TCP socket. With
    ``pc_listening`` False nobody listens (the connection is refused). ``pulse_inputs``:
    where the encoder is really wired (default: as the robot file says). ``counter_start``:
    the raw count at zero wire length (default: drawn over the whole int32 range).
    """
    options = options or UrOptions()
    texts = texts if texts is not None else scripts(robot, plan, options)
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / "run.csv"
    rng = np.random.default_rng([seed, 2])
    start = RAW.random_start(rng) if counter_start is None else counter_start
    enc = robot.encoder
    cell = URCell(
        robot,
        truth,
        plan.theta0_deg,
        folder,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=float(start),
        faults=faults or Faults(),
        pulse_inputs=pulse_inputs or enc.pulse_inputs,
        encoder_index=enc.channel,
        pc=pc_address(robot, options),
        unmodelled=unmodelled,
    )
    mount, run = texts["wc_mount.script"], texts["wc_run.script"]
    if not pc_listening:
        cell.receiver = ("127.0.0.1", _closed_port())
        return URRun(run_ur_programs(cell, mount, run), Received(log, journal_path(log)))
    listening = threading.Event()
    box: dict[str, object] = {}

    def on_listening(port: int) -> None:
        cell.receiver = ("127.0.0.1", port)
        listening.set()

    def serve() -> None:
        try:
            box["received"] = receive(
                0, log, robot, plan, timeout_s=timeout_s, on_listening=on_listening
            )
        except BaseException as exc:  # handed to the caller below
            box["error"] = exc
            listening.set()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    listening.wait(timeout_s)
    if "error" not in box:
        programs = run_ur_programs(cell, mount, run)
        if cell.lines_sent == 0 and cell.receiver is not None:
            _end_wait(cell.receiver)  # the program never connected: end the receiver's wait
        thread.join(timeout_s)
    if "error" in box:
        raise box["error"]  # type: ignore[misc]
    return URRun(programs, box["received"])  # type: ignore[arg-type]


def _closed_port() -> int:
    """Return a loopback port nobody listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _end_wait(address: tuple[str, int]) -> None:
    """Connect and close at once: the receiver stops waiting (nothing received)."""
    try:
        socket.create_connection(address, timeout=2.0).close()
    except OSError:
        pass
