"""Receiving a measurement log over TCP from a controller program (the PC side).

A controller without file output (URScript) sends its log as lines over a socket: the
``wirecal-log`` header, the column line, the rows, and last the end marker
:data:`END_MARKER`, a line of its own. :func:`receive` listens on one address, accepts one
sender and writes what it sends so that nothing received is lost:

* ``LOG`` is reserved before listening (an :class:`~wirecal.solver.formats.fileio.Outputs`
  set: an existing file is refused unless ``force``) and published atomically only when
  the end marker arrived — a file under the log's own name is always a complete run;
* every line, as it arrives, is appended to the journal ``LOG.partial`` and flushed to
  disk (fsync per received chunk), so a dropped connection, a timeout or a killed
  ``wirecal`` still leaves every received row on disk. After a complete run the journal is
  removed; after an incomplete one it is kept, and is itself a wirecal log the solver reads
  (a last line cut short is ignored there). An existing journal is never overwritten: it
  holds the rows of an earlier run.

While one sender is connected, any other connection is accepted and closed at once with
the line ``# busy: one sender at a time`` (counted in the result). ``timeout_s`` bounds
the wait for the sender and every silence between two lines.
"""

from __future__ import annotations

import os
import selectors
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import Outputs, os_problem
from wirecal.solver.formats.log import parse_log
from wirecal.solver.measurements import check_log, describe_missing
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot

END_MARKER = "# end"
"""The last line a measurement program sends: the run is complete."""

BUSY_LINE = b"# busy: one sender at a time\n"
MAX_LINE_BYTES = 4096  # a log line is < 200 bytes; more without a newline is not a log


@dataclass
class Received:
    """What one :func:`receive` run got: ``complete`` when the end marker arrived."""

    log: Path
    journal: Path
    lines: list[str] = field(default_factory=list)
    complete: bool = False
    stopped: str = ""  # why an incomplete run stopped
    refused: int = 0  # other senders turned away
    journal_created: bool = False

    @property
    def text(self) -> str:
        """Return the received lines as one text."""
        return "".join(self.lines)


def journal_path(log: str | Path) -> Path:
    """Return the journal beside ``log``: ``<log>.partial``."""
    log = Path(log)
    return log.with_name(log.name + ".partial")


def receive(
    port: int,
    log: str | Path,
    *,
    timeout_s: float,
    force: bool = False,
    host: str = "127.0.0.1",
    on_listening: Callable[[int], None] | None = None,
) -> Received:
    """Listen on ``host:port`` and take one sender's log into ``log`` (module docstring).

    ``on_listening`` is called with the bound port (useful with ``port=0``). Raises
    :class:`WirecalError` when the log or its journal cannot be reserved or the port cannot
    be bound; a run that stops early is a result with ``complete`` False, not an error.
    """
    log = Path(log)
    journal = journal_path(log)
    result = Received(log=log, journal=journal)
    try:
        with Outputs([log], force=force) as out:
            with _listen(host, port) as srv:
                if on_listening is not None:
                    on_listening(srv.getsockname()[1])
                _take(srv, timeout_s, journal, result)
            if not result.complete:
                raise _Incomplete
            out.put(log, result.text)
    except _Incomplete:
        pass  # the reservation of LOG is withdrawn; the journal keeps the rows
    except BaseException:
        if result.journal_created and not result.lines:
            journal.unlink(missing_ok=True)  # an empty journal of ours, never an older one
        raise
    if result.complete or not result.lines:
        journal.unlink(missing_ok=True)
    return result


class _Incomplete(Exception):
    """Leaves the Outputs set without publishing."""


def _listen(host: str, port: int) -> socket.socket:
    srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    try:
        srv.bind((host, port))
        srv.listen(2)
    except OSError as exc:
        srv.close()
        raise WirecalError(
            f"port {port}: cannot listen on {host} ({exc.strerror or exc}); "
            "choose a free port (and the same one in the robot program)"
        ) from None
    srv.setblocking(False)
    return srv


def _take(srv: socket.socket, timeout_s: float, journal: Path, result: Received) -> None:
    """Create the journal and fill it from one sender (refusing others).

    Stops at the end marker, a drop, bad data or ``timeout_s`` of silence.
    """
    fd = _create_journal(journal)
    result.journal_created = True
    sel = selectors.DefaultSelector()
    sel.register(srv, selectors.EVENT_READ)
    sender: socket.socket | None = None
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as jf:
            pending = b""
            deadline = time.monotonic() + timeout_s
            while True:
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    waited = "no sender connected" if sender is None else "no line arrived"
                    result.stopped = f"{waited} within {timeout_s:g} s (--timeout)"
                    return
                try:
                    events = sel.select(remaining)
                except KeyboardInterrupt:  # Ctrl-C while waiting: keep what came, say so
                    _sync(jf)
                    result.stopped = "interrupted (Ctrl-C)"
                    return
                for key, _ in events:
                    if key.fileobj is srv:
                        if sender is None:
                            sender = _accept(srv, sel)
                            deadline = time.monotonic() + timeout_s
                        else:
                            _refuse(srv.accept()[0])
                            result.refused += 1
                        continue
                    data = _recv(sender)
                    if not data:
                        _dropped(jf, result, pending)
                        return
                    deadline = time.monotonic() + timeout_s
                    rest = _feed(jf, result, pending + data)
                    if rest is None:
                        return
                    pending = rest
    finally:
        if sender is not None:
            sender.close()
        sel.close()


def _create_journal(journal: Path) -> int:
    try:
        return os.open(journal, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except FileExistsError:
        raise WirecalError(
            f"{journal}: exists and holds the rows of an earlier run; keep it under another "
            "name (it is a wirecal log) or delete it, then start again"
        ) from None
    except OSError as exc:
        raise os_problem(journal, exc) from None


def _accept(srv: socket.socket, sel: selectors.BaseSelector) -> socket.socket:
    sender, _ = srv.accept()
    sender.setblocking(False)
    sel.register(sender, selectors.EVENT_READ)
    return sender


def _recv(sender: socket.socket | None) -> bytes:
    try:
        return sender.recv(65536) if sender is not None else b""
    except ConnectionError:
        return b""


def _keep(jf, result: Received, line: str) -> None:
    jf.write(line)
    result.lines.append(line)


def _dropped(jf, result: Received, pending: bytes) -> None:
    if pending:  # a line cut short: kept as it came, without newline
        _keep(jf, result, pending.decode("utf-8", errors="replace"))
    _sync(jf)
    result.stopped = "the sender closed the connection before the end marker"


def _feed(jf, result: Received, buffered: bytes) -> bytes | None:
    """Journal the whole lines of ``buffered``; the unfinished rest, or None when done."""
    *whole, pending = buffered.split(b"\n")
    for raw in whole:
        try:
            line = raw.rstrip(b"\r").decode("utf-8")
        except UnicodeDecodeError:
            _sync(jf)
            result.stopped = (
                f"line {len(result.lines) + 1} is not UTF-8 text: is the sender a wirecal program?"
            )
            return None
        _keep(jf, result, line + "\n")
        if line.strip() == END_MARKER:
            _sync(jf)
            result.complete = True
            return None
    _sync(jf)
    if len(pending) > MAX_LINE_BYTES:
        result.stopped = (
            f"more than {MAX_LINE_BYTES} bytes without a line end after line "
            f"{len(result.lines)}: is the sender a wirecal program?"
        )
        return None
    return pending


def _sync(f) -> None:
    f.flush()
    os.fsync(f.fileno())


def _refuse(other: socket.socket) -> None:
    try:
        other.sendall(BUSY_LINE)
    except OSError:
        pass
    other.close()


def summary(result: Received, robot: Robot | None = None, plan: Plan | None = None) -> list[str]:
    """Say what was received in words; with the robot and plan, name the missing points."""
    rows = _readable(result)
    lines = []
    if result.complete:
        lines.append(f"{result.log}: written, {rows} (run complete)")
    elif not result.lines:
        lines.append(f"{result.stopped}; nothing received, nothing written")
    else:
        lines.append(
            f"{result.stopped}; {len(result.lines)} lines received ({rows}) are kept in "
            f"{result.journal}; {result.log} not written (it is kept for complete runs)"
        )
    if result.refused:
        lines.append(f"refused {result.refused} other sender(s) while one was connected")
    if result.lines and robot is not None and plan is not None:
        try:
            m = check_log(parse_log(result.text, str(result.journal)), plan, robot)
        except WirecalError as exc:
            lines.append(f"cannot name the missing points: {exc.problems[0]}")
        else:
            lines.append(f"missing points: {describe_missing(m.missing, m.step, m.index)}")
    return lines


def _readable(result: Received) -> str:
    if not result.lines:
        return "no rows"
    try:
        log = parse_log(result.text, str(result.journal))
    except WirecalError as exc:
        return f"not a readable wirecal log: {exc.problems[0]}"
    if not log.readings:
        return "0 rows"
    last = log.readings[-1]
    return f"{len(log.readings)} rows, the last {last.kind} step {last.step} index {last.index}"
