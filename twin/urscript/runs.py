"""The URScript programs run in the twin, and URScript's twin adapter.

wc_mount, then wc_run, on a :class:`~wirecal.twin.urscript.controller.URController`; the
log travels over a real TCP socket to a receiver the caller provides (``wirecal
receive``, an application workflow the twin does not import), and :data:`ADAPTER`
(:class:`~wirecal.twin.adapters.TwinAdapter`).
"""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Protocol

import numpy as np

from wirecal.lang.urscript.parser import parse_program
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import Measurements
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled
from wirecal.twin.adapters import AdapterCapabilities, TwinAdapter, program_text
from wirecal.twin.controller_run import ControllerRun, readings_for_lengths
from wirecal.twin.machine import Outcome
from wirecal.twin.urscript.controller import RAW, URController
from wirecal.twin.urscript.interp import Interpreter
from wirecal.twin.urscript.solver_run import controller_solve
from wirecal.twin.world import Faults, TwinRun, measurement_world, mount_then_run, stop_reason

MOUNT, RUN = "wc_mount.script", "wc_run.script"


class Reception(Protocol):
    """What a receiver got of a run (``wirecal receive``'s result)."""

    log: Path  # the checked log, published when complete
    journal: Path  # the lines of an incomplete run
    complete: bool
    stopped: str  # why an incomplete run stopped


Listen = Callable[[Path, Callable[[int], None]], Reception]
"""A receiver: listens on a free loopback port for the log ``Path``, calls back with the
port once listening, and returns what it received."""


def run_ur_programs(
    controller: URController, mount_text: str, run_text: str
) -> tuple[Outcome, Outcome | None]:
    """Run ``wc_mount`` (the operator mounts the encoder and continues), then ``wc_run``.

    Each is checked against the controller's declared software first: a call its manual
    pages do not document is refused by name before anything runs
    (:mod:`wirecal.lang.urscript.versions`). The controller closes the program's sockets
    when it ends, however it ends.
    """
    software = controller.software
    mount_program = parse_program(mount_text, MOUNT, software)
    run_program = parse_program(run_text, RUN, software)
    mount, run = mount_then_run(
        controller.world,
        Interpreter(mount_program, controller).execute,
        lambda: Interpreter(run_program, controller).execute(),
    )
    controller.close_all()
    return mount, run


def _script(programs: dict[str, str], name: str) -> str:
    """Return the program file ``name`` of a URScript generation (WirecalError if absent)."""
    return program_text(programs, name, "URScript")


class URScriptAdapter(TwinAdapter):
    """URScript's twin adapter: wc_mount and wc_run on a twin UR, the log sent to a receiver."""

    key = "urscript"
    capabilities = AdapterCapabilities(controller_runs=True)

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
        unmodelled: Unmodelled | None = None,
        pulse_inputs: tuple[int, int] | None = None,
        pc: tuple[str, int] | None = None,
        listen: Listen | None = None,
        timeout_s: float = 30.0,
    ) -> TwinRun:
        """Run wc_mount and wc_run on a twin UR; ``listen`` takes the log in a thread.

        The controller routes the program's PC address (``pc``; None: any) to the port
        ``listen`` reports, so the rows travel over a real TCP socket; without ``listen``
        nobody listens (the connection is refused) and the log is ``folder/run.csv``,
        never written. ``pulse_inputs``: where the encoder is really wired (default: as
        the robot file says). ``counter_start``: the raw count at zero wire length
        (default: drawn over the whole int32 range).
        """
        world = measurement_world(
            robot,
            plan,
            truth,
            folder,
            RAW,
            seed=seed,
            noise_mm=noise_mm,
            counter_start=counter_start,
            faults=faults,
            unmodelled=unmodelled,
        )
        enc = robot.encoder
        ctl = URController(
            world,
            pulse_inputs or enc.pulse_inputs,
            encoder_index=enc.channel,
            pc=pc,
            software=robot.controller.software,
        )
        log = folder / "run.csv"
        if listen is None:
            ctl.receiver = ("127.0.0.1", _closed_port())
            mount, run = run_ur_programs(ctl, _script(programs, MOUNT), _script(programs, RUN))
            stopped = stop_reason(mount, run) or "nobody received the log"
            return TwinRun(log, False, stopped, world, mount, run, ctl)
        return _with_receiver(ctl, programs, log, listen, timeout_s)

    def controller_solve(
        self,
        robot: Robot,
        plan: Plan,
        lengths_mm: np.ndarray,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, dict[str, float]]:
        """Run wc_solve (step by step: no polish) on the plan points' wire lengths.

        ``lengths_mm``: mm from the zero reading at θ0, plan order; the readings as wc_run
        would keep them on the raw int32 count
        (:func:`~wirecal.twin.controller_run.readings_for_lengths`).
        """
        readings = readings_for_lengths(robot, plan, lengths_mm, RAW)
        run = controller_solve(robot, plan, readings, folder / "stepwise", _script(programs, RUN))
        return {"stepwise": run.offsets}

    def controller_runs(
        self,
        robot: Robot,
        plan: Plan,
        measured: Measurements,
        folder: Path,
        programs: dict[str, str],
    ) -> dict[str, ControllerRun]:
        """Run wc_solve on a checked log's own readings, with its operation and sync counts."""
        text = _script(programs, RUN)
        return {
            "stepwise": controller_solve(
                robot, plan, measured.log.readings, folder / "stepwise", text
            )
        }


RECEIVER_GRACE_S = 30.0
"""How much longer than its own wait the receiver's thread may take to end.

The receiver ends by itself within its timeout once the programs have ended (or at once,
the wait ended for a program that never connected); joining it for just that timeout raced
it on a busy machine (the join returned first, the reception not yet handed over)."""


def _with_receiver(
    ctl: URController, programs: dict[str, str], log: Path, listen: Listen, timeout_s: float
) -> TwinRun:
    """Run the programs while ``listen`` receives the log in a thread."""
    listening = threading.Event()
    box: dict[str, object] = {}

    def on_listening(port: int) -> None:
        ctl.receiver = ("127.0.0.1", port)
        listening.set()

    def serve() -> None:
        try:
            box["received"] = listen(log, on_listening)
        except BaseException as exc:  # handed to the caller below
            box["error"] = exc
            listening.set()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    listening.wait(timeout_s)
    if "error" not in box:
        mount, run = run_ur_programs(ctl, _script(programs, MOUNT), _script(programs, RUN))
        if ctl.lines_sent == 0 and ctl.receiver is not None:
            _end_wait(ctl.receiver)  # the program never connected: end the receiver's wait
        thread.join(timeout_s + RECEIVER_GRACE_S)
    if thread.is_alive():
        raise WirecalError(
            f"the twin's receiver did not end {timeout_s + RECEIVER_GRACE_S:g} s after the "
            "programs did (its own wait is bounded): a machine too busy? run it again"
        )
    if "error" in box:
        raise box["error"]  # type: ignore[misc]
    got: Reception = box["received"]  # type: ignore[assignment]
    stopped = None if got.complete else _why_stopped(mount, run, got.stopped)
    return TwinRun(
        got.log if got.complete else got.journal, got.complete, stopped, ctl.world, mount, run, ctl
    )


def _why_stopped(mount: Outcome, run: Outcome | None, received: str) -> str:
    """Return why an incomplete run stopped.

    The program's own reason first (its error popup's text, or the last line it showed
    before a ``halt``), then what the receiver saw.
    """
    own = stop_reason(mount, run)
    if own is None:  # the programs completed: only the receiver knows what went wrong
        return received
    last = run or mount
    if last.status == "halted" and last.console:
        own += f" after: {last.console[-1]}"
    return f"{own} (wirecal receive: {received})" if received else own


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


ADAPTER = URScriptAdapter()
