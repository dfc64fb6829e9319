"""``wirecal receive`` over loopback with real sockets: a complete run, a drop mid-run, a
second sender refused, timeouts, and nothing received ever lost or overwritten."""

from __future__ import annotations

import socket
import threading
import time

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wirecal.app.receive import BUSY_LINE, END_MARKER, journal_path, receive, summary
from wirecal.cli.main import main
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.log import parse_log
from wirecal.solver.simulate import simulate_log


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    return simulate_log(viper, paper_plan, {}, seed=1, counter_start=1000.0)


class Server:
    """:func:`receive` in a background thread on a free loopback port."""

    def __init__(self, path, **kwargs):
        self.port: int | None = None
        self.ready = threading.Event()
        self.result = None
        self.error: BaseException | None = None

        def listening(port: int) -> None:
            self.port = port
            self.ready.set()

        def run() -> None:
            try:
                self.result = receive(0, path, on_listening=listening, **kwargs)
            except BaseException as exc:  # handed to the test thread
                self.error = exc
                self.ready.set()

        self.thread = threading.Thread(target=run, daemon=True)
        self.thread.start()
        assert self.ready.wait(5), "the server did not start listening"

    def connect(self) -> socket.socket:
        assert self.port is not None, self.error
        s = socket.create_connection(("127.0.0.1", self.port), timeout=5)
        return s

    def finish(self):
        self.thread.join(10)
        assert not self.thread.is_alive(), "the server did not stop"
        if self.error is not None:
            raise self.error
        return self.result


def _send_in_chunks(s: socket.socket, data: bytes, size: int = 97) -> None:
    for k in range(0, len(data), size):  # chunks that cut lines anywhere
        s.sendall(data[k : k + size])


def test_complete_run_published_at_the_end_marker(tmp_path, log_text):
    out = tmp_path / "run.csv"
    server = Server(out, timeout_s=5)
    with server.connect() as s:
        # CRLF line ends from the controller become LF in the log
        _send_in_chunks(s, (log_text + END_MARKER + "\n").replace("\n", "\r\n").encode())
    result = server.finish()
    assert result.complete
    assert result.refused == 0
    assert out.read_text() == log_text + END_MARKER + "\n"
    assert not journal_path(out).exists()
    assert len(parse_log(out.read_text(), str(out)).readings) == log_text.count("\npoint,") + (
        log_text.count("\nzero,")
    )


def test_drop_mid_run_keeps_every_line_and_names_missing_points(
    tmp_path, log_text, viper, paper_plan
):
    out = tmp_path / "run.csv"
    lines = log_text.splitlines(keepends=True)
    first_step_2 = next(k for k, ln in enumerate(lines) if ln.startswith("zero,2,"))
    sent = "".join(lines[:first_step_2]) + lines[first_step_2][:10]  # cut inside a line
    server = Server(out, timeout_s=5)
    with server.connect() as s:
        s.sendall(sent.encode())
    result = server.finish()
    assert not result.complete
    assert "closed the connection before the end marker" in result.stopped
    assert not out.exists()
    assert journal_path(out).read_text() == sent  # byte for byte, the cut line included
    n_steps = len(paper_plan.steps)
    text = "\n".join(summary(result, viper, paper_plan))
    assert str(journal_path(out)) in text
    assert f"missing points: steps 2–{n_steps} (all points)" in text


def test_second_sender_refused_while_one_is_connected(tmp_path, log_text):
    out = tmp_path / "run.csv"
    server = Server(out, timeout_s=5)
    with server.connect() as first:
        first.sendall(log_text[:200].encode())
        with server.connect() as second:
            assert second.recv(100) == BUSY_LINE
            assert second.recv(100) == b""  # closed by the server
        first.sendall((log_text[200:] + END_MARKER + "\n").encode())
    result = server.finish()
    assert result.complete
    assert result.refused == 1
    assert out.read_text() == log_text + END_MARKER + "\n"


def test_timeout_without_a_sender_writes_nothing(tmp_path):
    out = tmp_path / "run.csv"
    t0 = time.monotonic()
    result = receive(0, out, timeout_s=0.3)
    assert 0.3 <= time.monotonic() - t0 < 5
    assert not result.complete
    assert "no sender connected within 0.3 s" in result.stopped
    assert not out.exists()
    assert not journal_path(out).exists()
    assert "nothing received" in summary(result)[0]


def test_timeout_after_silence_keeps_the_rows(tmp_path, log_text):
    out = tmp_path / "run.csv"
    head = "".join(log_text.splitlines(keepends=True)[:8])
    server = Server(out, timeout_s=0.5)
    with server.connect() as s:
        s.sendall(head.encode())
        result = server.finish()  # the sender stays silent and connected
    assert "no line arrived within 0.5 s" in result.stopped
    assert journal_path(out).read_text() == head
    assert not out.exists()
    assert "rows, the last" in summary(result)[0]


def test_existing_journal_and_log_are_never_overwritten(tmp_path):
    out = tmp_path / "run.csv"
    journal_path(out).write_text("rows of an earlier run\n")
    with pytest.raises(WirecalError, match="earlier run"):
        receive(0, out, timeout_s=0.2)
    assert journal_path(out).read_text() == "rows of an earlier run\n"
    journal_path(out).unlink()
    out.write_text("old log\n")
    with pytest.raises(WirecalError, match="exists"):
        receive(0, out, timeout_s=0.2)
    assert out.read_text() == "old log\n"


def test_port_in_use_is_a_clear_error(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        with pytest.raises(WirecalError, match=f"port {port}: cannot listen"):
            receive(port, tmp_path / "run.csv", timeout_s=0.2)
    assert not journal_path(tmp_path / "run.csv").exists()


def test_cli_drop_exits_1_and_names_the_journal(tmp_path, log_text):
    with socket.socket() as probe:  # a free port for the command
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    out = tmp_path / "run.csv"

    def sender() -> None:
        for _ in range(100):  # until the command listens (bounded)
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                    s.sendall(log_text[:300].encode())
                return
            except ConnectionRefusedError:
                time.sleep(0.05)

    thread = threading.Thread(target=sender, daemon=True)
    thread.start()
    res = CliRunner().invoke(
        main, ["receive", "--port", str(port), "-o", str(out), "--timeout", "5"]
    )
    thread.join(5)
    assert res.exit_code == 1, res.output
    assert f"{out}.partial" in res.output
    assert "closed the connection" in res.output
    assert journal_path(out).read_text() == log_text[:300]


def test_cli_robot_without_plan_refused(tmp_path):
    res = CliRunner().invoke(
        main, ["receive", "--port", "9", "-o", str(tmp_path / "x.csv"), "--robot", "r.toml"]
    )
    assert res.exit_code == 2
    assert "--robot and --plan go together" in res.output


def test_ctrl_c_while_waiting_keeps_the_rows_and_says_so(tmp_path, log_text, monkeypatch):
    import selectors

    head = "".join(log_text.splitlines(keepends=True)[:6])
    out = tmp_path / "run.csv"

    class InterruptedSelector(selectors.DefaultSelector):  # type: ignore[misc,valid-type]
        def select(self, timeout=None):
            journal = journal_path(out)
            if journal.exists() and journal.stat().st_size == len(head):
                raise KeyboardInterrupt  # Ctrl-C once every sent line is in the journal
            return super().select(min(timeout or 0.05, 0.05))

    monkeypatch.setattr("wirecal.app.receive.selectors.DefaultSelector", InterruptedSelector)
    server = Server(out, timeout_s=5)
    with server.connect() as s:
        s.sendall(head.encode())
        result = server.finish()
    assert result.stopped == "interrupted (Ctrl-C)"
    assert journal_path(out).read_text() == head
    assert not out.exists()


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(cuts=st.lists(st.integers(1, 400), min_size=1, max_size=12), crlf=st.booleans())
def test_any_chunking_gives_the_same_log(tmp_path_factory, log_text, cuts, crlf):
    out = tmp_path_factory.mktemp("chunks") / "run.csv"
    data = (log_text + END_MARKER + "\n").encode()
    wire = data.replace(b"\n", b"\r\n") if crlf else data
    server = Server(out, timeout_s=5)
    with server.connect() as s:
        k = 0
        for size in cuts * (len(wire) // sum(cuts) + 1):
            if k >= len(wire):
                break
            s.sendall(wire[k : k + size])
            k += size
    result = server.finish()
    assert result.complete
    assert out.read_bytes() == data
