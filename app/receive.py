"""Receiving a measurement log over TCP from a controller program (the PC side).

A controller without file output (URScript) sends its log as lines over a socket: first
the run token (:mod:`wirecal.formats.run_token`), then the ``wirecal-log`` header,
the column line, the rows, and last the end marker :data:`END_MARKER`. :func:`receive`
listens on one address and takes one run so that nothing received is lost and nothing
but a checked, complete log is published — on a shop network too:

* ``LOG`` is reserved before listening (an :class:`~wirecal.formats.fileio.Outputs`
  set: an existing file is refused unless ``force``, and the robot file or plan is never
  an output, even with ``force``);
* a connection becomes the sender only when its first line presents the run's token
  within :data:`HANDSHAKE_S` seconds. A wrong token is answered :data:`REFUSED_LINE` and
  closed; a connection that sends nothing, or no line, in that time (a port probe, an
  idle client) is closed. Neither ends the run nor moves its deadline; at most
  :data:`MAX_CANDIDATES` wait at once (the oldest is closed for a new one). While a sender
  is connected, every other connection gets :data:`BUSY_LINE` and is closed;
* every line of the sender, as it arrives, is appended to the journal ``LOG.partial`` and
  flushed to disk (fsync per received chunk), so a dropped connection, a timeout or a
  killed ``wirecal`` still leaves every received row on disk. An existing journal is never
  overwritten: it holds the rows of an earlier run;
* at the end marker the received text is read as a log and checked against the plan and
  robot (:func:`~wirecal.solver.log.measurements.check_log`, every point and the closing zero
  reading): ``LOG`` is published atomically only when it passes, and the journal removed;
  otherwise the journal is kept and the problems are named.

``timeout_s`` bounds the wait for a sender that presents the token (from the start, not
reset by other connections) and the time between two complete lines of the sender (not
reset by single bytes: a sender trickling bytes without a line end is stopped).
"""

from __future__ import annotations

import errno
import os
import selectors
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from wirecal.formats.fileio import MAX_INPUT_BYTES, Outputs, os_problem
from wirecal.formats.log import parse_log
from wirecal.formats.run_token import PREFIX, presents, run_token
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log, describe_missing
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot

END_MARKER = "# end"
"""The last line a measurement program sends: the run is complete."""

BUSY_LINE = b"# busy: one sender at a time\n"
REFUSED_LINE = b"# refused: no valid run token\n"
MAX_LINE_BYTES = 4096  # a log line is < 200 bytes; more without a newline is not a log
HANDSHAKE_S = 5.0
"""How long a new connection may take to present the token (at most ``timeout_s``)."""
MAX_CANDIDATES = 8
"""Connections waiting to present the token at once; the oldest is closed for a new one."""


@dataclass
class Received:
    """What one :func:`receive` run got: ``complete`` when a checked log was published."""

    log: Path
    journal: Path
    lines: list[str] = field(default_factory=list)
    complete: bool = False
    stopped: str = ""  # why an incomplete run stopped
    refused: int = 0  # senders turned away while one was connected
    forged: int = 0  # connections that presented no valid token
    probes: int = 0  # connections that sent no line in time, or nothing at all
    problems: list[str] = field(default_factory=list)  # the log checks at the end marker
    journal_created: bool = False
    size: int = 0  # bytes of the lines received

    @property
    def text(self) -> str:
        """Return the received lines as one text."""
        return "".join(self.lines)

    @property
    def ended(self) -> bool:
        """Whether the end marker arrived (the log may still fail its checks)."""
        return bool(self.lines) and self.lines[-1].strip() == END_MARKER


def journal_path(log: str | Path) -> Path:
    """Return the journal beside ``log``: ``<log>.partial``."""
    log = Path(log)
    return log.with_name(log.name + ".partial")


def receive(
    port: int,
    log: str | Path,
    robot: Robot,
    plan: Plan,
    *,
    timeout_s: float,
    force: bool = False,
    host: str = "127.0.0.1",
    on_listening: Callable[[int], None] | None = None,
    on_refused: Callable[[str], None] | None = None,
) -> Received:
    """Listen on ``host:port`` and take one run of ``plan`` into ``log`` (module docstring).

    ``on_listening`` is called with the bound port (useful with ``port=0``), ``on_refused``
    with a sentence for each connection refused for its token, as it happens. Raises
    :class:`WirecalError` when the log or its journal cannot be reserved or the port cannot
    be bound; a run that stops early or fails its checks is a result with ``complete``
    False, not an error.
    """
    log = Path(log)
    journal = journal_path(log)
    result = Received(log=log, journal=journal)
    token = run_token(robot, plan.fingerprint())
    inputs = [robot.source, plan.source]
    try:
        with Outputs([log], force=force, inputs=inputs) as out:
            with _listen(host, port) as srv:
                if on_listening is not None:
                    on_listening(srv.getsockname()[1])
                _take(srv, timeout_s, journal, result, (token, on_refused))
            if result.ended:
                result.problems = log_problems(result.text, str(journal), robot, plan)
                result.complete = not result.problems
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


def log_problems(text: str, source: str, robot: Robot, plan: Plan) -> list[str]:
    """Return why ``text`` is not a complete log of ``plan`` (empty when it is one).

    Read as the program's own log, not a terminal capture: a line that is no row is an
    error here, so the published file holds only what a log holds.
    """
    try:
        m = check_log(parse_log(text, source, terminal=False), plan, robot)
    except WirecalError as exc:
        return exc.problems
    return [] if m.complete else [f"{source}: missing {m.missing_text()}"]


class _Incomplete(Exception):
    """Leaves the Outputs set without publishing."""


def _listen(host: str, port: int) -> socket.socket:
    srv = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    # a port a run just used is in TIME_WAIT for a minute: bind it again at once
    srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        srv.bind((host, port))
        srv.listen(MAX_CANDIDATES)
    except OSError as exc:
        srv.close()
        raise WirecalError(
            f"port {port}: cannot listen on {host} ({exc.strerror or exc}); choose a free "
            "port (and the same one in the robot program), and an address this PC has "
            "(--host; 0.0.0.0 listens on all)"
        ) from None
    srv.setblocking(False)
    return srv


def _take(
    srv: socket.socket,
    timeout_s: float,
    journal: Path,
    result: Received,
    token: tuple[str, Callable[[str], None] | None],
) -> None:
    """Create the journal and fill it from the one sender that presents the token.

    ``token``: the run token, and who to tell about a connection refused for it.
    """
    fd = _create_journal(journal)
    result.journal_created = True
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as jf:
            session = _Session(srv, timeout_s, token, jf, result)
            try:
                session.run()
            except KeyboardInterrupt:  # Ctrl-C while waiting: keep what came, say so
                result.stopped = "interrupted (Ctrl-C)"
            finally:
                try:
                    _sync(jf)
                finally:
                    session.close()
    except OSError as exc:
        if exc.errno not in _DISK_FULL:
            raise
        result.stopped = (  # the journal holds what could be written
            f"{journal}: {exc.strerror} after line {len(result.lines)} (the journal keeps the "
            "lines up to there, its last one possibly cut); free space and run again"
        )


_DISK_FULL = {errno.ENOSPC, errno.EDQUOT, errno.EFBIG}


@dataclass
class _Candidate:
    """A connection that has not presented the token yet."""

    deadline: float
    buffered: bytes = b""


class _Session:
    """One run's connections: candidates, the sender, the deadlines (module docstring)."""

    def __init__(
        self,
        srv: socket.socket,
        timeout_s: float,
        token: tuple[str, Callable[[str], None] | None],
        jf,
        result: Received,
    ):
        self.srv, self.timeout_s, self.jf, self.result = srv, timeout_s, jf, result
        self.token, self.tell = token
        self.sel = selectors.DefaultSelector()
        self.sel.register(srv, selectors.EVENT_READ)
        self.candidates: dict[socket.socket, _Candidate] = {}
        self.sender: socket.socket | None = None
        self.pending: bytes | None = b""
        self.deadline = time.monotonic() + timeout_s  # for the sender, then for each line
        self.done = False

    def run(self) -> None:
        while not self.done:
            now = time.monotonic()
            self._expire(now)
            if self.done:
                return
            wait = min([self.deadline, *(c.deadline for c in self.candidates.values())]) - now
            for key, _ in self.sel.select(max(wait, 0.0)):
                if self.done:
                    return
                self._event(key.fileobj)  # type: ignore[arg-type]

    def _event(self, conn: socket.socket) -> None:
        if conn is self.srv:
            self._accept()
        elif conn is self.sender:
            self._from_sender()
        elif conn in self.candidates:
            self._from_candidate(conn)

    def _expire(self, now: float) -> None:
        for conn in [c for c, cand in self.candidates.items() if cand.deadline <= now]:
            self._drop(conn)
            self.result.probes += 1
        if now < self.deadline:
            return
        if self.sender is None:
            self.result.stopped = (
                f"no sender presented the run token within {self.timeout_s:g} s (--timeout)"
            )
        else:
            self.result.stopped = (
                f"no complete line arrived within {self.timeout_s:g} s (--timeout) after "
                f"line {len(self.result.lines)}"
            )
        self.done = True

    def _accept(self) -> None:
        try:
            conn, _ = self.srv.accept()
        except OSError:
            return  # the client gave up between select and accept
        if self.sender is not None:
            _refuse(conn, BUSY_LINE)
            self.result.refused += 1
            return
        if len(self.candidates) >= MAX_CANDIDATES:
            self._drop(next(iter(self.candidates)))  # the oldest
            self.result.probes += 1
        conn.setblocking(False)
        self.sel.register(conn, selectors.EVENT_READ)
        handshake = min(HANDSHAKE_S, self.timeout_s)
        self.candidates[conn] = _Candidate(time.monotonic() + handshake)

    def _from_candidate(self, conn: socket.socket) -> None:
        cand = self.candidates[conn]
        data = _recv(conn)
        if data is None:
            return
        if not data:
            self._drop(conn)
            self.result.probes += 1
            return
        cand.buffered += data
        if b"\n" not in cand.buffered:
            if len(cand.buffered) > MAX_LINE_BYTES:
                self._forged(conn, "a line too long to be a token")
            return
        first, rest = cand.buffered.split(b"\n", 1)
        line = first.decode("utf-8", errors="replace").rstrip("\r")
        if not presents(line, self.token):
            self._forged(conn, "a wrong token" if line.startswith(PREFIX) else "no token")
            return
        if self.sender is not None:  # two presented it while waiting: the first one sends
            self._drop(conn, BUSY_LINE)
            self.result.refused += 1
            return
        del self.candidates[conn]
        self.sender = conn
        self.deadline = time.monotonic() + self.timeout_s
        self._lines(rest)

    def _forged(self, conn: socket.socket, what: str) -> None:
        try:
            peer = "{}:{}".format(*conn.getpeername()[:2])
        except OSError:
            peer = "a client"
        self._drop(conn, REFUSED_LINE)
        self.result.forged += 1
        if self.tell is not None:
            self.tell(
                f"refused {peer}: {what} (a program generated with another robot file key "
                "or plan? stop it: its rows would reach the log tab only)"
            )

    def _from_sender(self) -> None:
        data = _recv(self.sender)
        if data is None:
            return
        if not data:
            _dropped(self.jf, self.result, self.pending or b"")
            self.done = True
            return
        self._lines(data)

    def _lines(self, data: bytes) -> None:
        before = len(self.result.lines)
        self.pending = _feed(self.jf, self.result, (self.pending or b"") + data)
        if len(self.result.lines) > before:
            self.deadline = time.monotonic() + self.timeout_s  # per line, not per byte
        self.done = self.pending is None

    def _drop(self, conn: socket.socket, answer: bytes | None = None) -> None:
        self.candidates.pop(conn, None)
        self.sel.unregister(conn)
        if answer is None:
            conn.close()
        else:
            _refuse(conn, answer)

    def close(self) -> None:
        for conn in list(self.candidates):
            self._drop(conn)
        if self.sender is not None:
            self.sender.close()
        self.sel.close()


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


def _recv(conn: socket.socket | None) -> bytes | None:
    """Return what arrived: b"" when the peer closed, None when nothing was there after all."""
    try:
        return conn.recv(65536) if conn is not None else b""
    except BlockingIOError:
        return None
    except ConnectionError:
        return b""


def _keep(jf, result: Received, line: str) -> None:
    jf.write(line)
    result.lines.append(line)
    result.size += len(line)


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
        if result.size + len(raw) >= MAX_INPUT_BYTES:  # the bound of every other input
            _sync(jf)
            result.stopped = (
                f"more than {MAX_INPUT_BYTES // 2**20} MiB received after line "
                f"{len(result.lines)}: not a log (a run's log is well under 1 MiB); is the "
                "sender a wirecal program?"
            )
            return None
        _keep(jf, result, line + "\n")
        if line.strip() == END_MARKER:
            _sync(jf)
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


def _refuse(other: socket.socket, answer: bytes) -> None:
    try:
        other.sendall(answer)
    except OSError:
        pass
    other.close()


def summary(result: Received, robot: Robot, plan: Plan) -> list[str]:
    """Say what was received in words, with what is missing or wrong."""
    rows = _readable(result)
    lines = []
    if result.complete:
        lines.append(f"{result.log}: written, {rows} (run complete; the log checks passed)")
    elif not result.lines:
        lines.append(f"{result.stopped}; nothing received, nothing written")
    else:
        why = (
            "the end marker arrived but the log is incomplete or fails its checks"
            if result.ended
            else result.stopped
        )
        lines.append(
            f"{why}; {len(result.lines)} lines received ({rows}) are kept in "
            f"{result.journal}; {result.log} not written (it is kept for complete runs)"
        )
        lines += [f"  {p}" for p in result.problems]
    lines += _turned_away(result)
    if result.lines and not result.ended:
        try:
            m = check_log(parse_log(result.text, str(result.journal)), plan, robot)
        except WirecalError as exc:
            lines.append(f"cannot name the missing points: {exc.problems[0]}")
        else:
            lines.append(f"missing points: {describe_missing(m.missing, m.step, m.index)}")
    return lines


def _turned_away(result: Received) -> list[str]:
    counts = (
        (result.refused, "sender(s) refused while one was connected"),
        (result.forged, "connection(s) refused: no valid run token"),
        (result.probes, "connection(s) closed that sent no line in time (probes, idle clients)"),
    )
    return [f"{n} {what}" for n, what in counts if n]


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
