"""``wirecal receive`` over loopback with real sockets: a complete run, a drop mid-run, a
second sender refused, timeouts, nothing received ever lost or overwritten — and a
receiver you can leave running on a shop network: a sender without the run token, a port
probe, an idle client or a trickling one neither ends nor holds the run; '# end' publishes
only a complete, checked log; the port binds again right after a run. Every wait in these
tests is bounded (socket timeouts, thread joins, counted retries)."""

from __future__ import annotations

import dataclasses
import socket
import threading
import time

import pytest
from click.testing import CliRunner
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from wirecal.app.receive import (
    BUSY_LINE,
    END_MARKER,
    REFUSED_LINE,
    journal_path,
    receive,
    summary,
)
from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.run_token import run_token, token_line
from wirecal.formats.simulated_log import simulate_log
from wirecal.solver.errors import WirecalError

from .conftest import ROOT

UR5 = ROOT / "examples" / "ur5e"
ROBOT, PLAN = str(UR5 / "robot.toml"), str(UR5 / "plan.toml")


@pytest.fixture(scope="module")
def ur5():
    return load_robot(ROBOT)


@pytest.fixture(scope="module")
def plan(ur5):
    return load_plan(PLAN, ur5)


@pytest.fixture(scope="module")
def log_text(ur5, plan):
    return simulate_log(ur5, plan, {}, seed=1, counter_start=1000.0)


@pytest.fixture(scope="module")
def hello(ur5, plan) -> bytes:
    """The run token's line, as the generated program sends it first."""
    return (token_line(run_token(ur5, plan.fingerprint())) + "\n").encode()


class Server:
    """:func:`receive` in a background thread on a free loopback port."""

    def __init__(self, path, robot, plan, port=0, **kwargs):
        self.port: int | None = None
        self.ready = threading.Event()
        self.result = None
        self.error: BaseException | None = None

        def listening(port: int) -> None:
            self.port = port
            self.ready.set()

        def run() -> None:
            try:
                self.result = receive(port, path, robot, plan, on_listening=listening, **kwargs)
            except BaseException as exc:  # handed to the test thread
                self.error = exc
                self.ready.set()

        self.thread = threading.Thread(target=run, daemon=True)
        self.thread.start()
        assert self.ready.wait(5), "the server did not start listening"

    def connect(self) -> socket.socket:
        assert self.port is not None, self.error
        return socket.create_connection(("127.0.0.1", self.port), timeout=5)

    def finish(self):
        self.thread.join(10)
        assert not self.thread.is_alive(), "the server did not stop"
        if self.error is not None:
            raise self.error
        return self.result


@pytest.fixture
def serve(tmp_path, ur5, plan):
    def start(name="run.csv", **kwargs) -> Server:
        kwargs.setdefault("timeout_s", 5)
        return Server(tmp_path / name, ur5, plan, **kwargs)

    return start


def _send_in_chunks(s: socket.socket, data: bytes, size: int = 97) -> None:
    for k in range(0, len(data), size):  # chunks that cut lines anywhere
        s.sendall(data[k : k + size])


def test_complete_run_published_at_the_end_marker(serve, tmp_path, log_text, hello):
    out = tmp_path / "run.csv"
    server = serve()
    with server.connect() as s:
        # CRLF line ends from the controller become LF in the log; the token is not logged
        _send_in_chunks(s, hello + (log_text + END_MARKER + "\n").replace("\n", "\r\n").encode())
    result = server.finish()
    assert result.complete
    assert (result.refused, result.forged, result.probes) == (0, 0, 0)
    assert out.read_text() == log_text + END_MARKER + "\n"
    assert not journal_path(out).exists()
    assert len(parse_log(out.read_text(), str(out)).readings) == log_text.count("\npoint,") + (
        log_text.count("\nzero,")
    )


def test_drop_mid_run_keeps_every_line_and_names_missing_points(
    serve, tmp_path, log_text, hello, ur5, plan
):
    out = tmp_path / "run.csv"
    lines = log_text.splitlines(keepends=True)
    first_step_2 = next(k for k, ln in enumerate(lines) if ln.startswith("zero,2,"))
    sent = "".join(lines[:first_step_2]) + lines[first_step_2][:10]  # cut inside a line
    server = serve()
    with server.connect() as s:
        s.sendall(hello + sent.encode())
    result = server.finish()
    assert not result.complete
    assert "closed the connection before the end marker" in result.stopped
    assert not out.exists()
    assert journal_path(out).read_text() == sent  # byte for byte, the cut line included
    text = "\n".join(summary(result, ur5, plan))
    assert str(journal_path(out)) in text
    assert f"missing points: steps 2–{len(plan.steps)} (all points)" in text


def test_second_sender_refused_while_one_is_connected(serve, tmp_path, log_text, hello):
    out = tmp_path / "run.csv"
    server = serve()
    with server.connect() as first:
        first.sendall(hello + log_text[:200].encode())
        time.sleep(0.2)  # the first is the sender before the second connects
        with server.connect() as second:
            assert second.recv(100) == BUSY_LINE
            assert second.recv(100) == b""  # closed by the server
        first.sendall((log_text[200:] + END_MARKER + "\n").encode())
    result = server.finish()
    assert result.complete
    assert result.refused == 1
    assert out.read_text() == log_text + END_MARKER + "\n"


def test_forged_senders_and_probes_neither_end_nor_hold_the_run(
    serve, tmp_path, log_text, hello, ur5, plan
):
    """Before the robot connects: a port probe (connect, close), a sender with a wrong
    token, one with no token (a log straight away), an idle client that stays connected
    and a trickler that never ends its line. None of them is journaled; the real sender
    then delivers the run, which is published."""
    out = tmp_path / "run.csv"
    server = serve(timeout_s=3)
    with server.connect():
        pass  # a port scanner's probe
    with server.connect() as wrong:
        wrong.sendall(b"# wirecal-token " + b"0" * 32 + b"\n" + log_text.encode())
        assert wrong.recv(100) == REFUSED_LINE
    with server.connect() as bare:
        bare.sendall((log_text + END_MARKER + "\n").encode())  # no token: refused
        assert bare.recv(100) == REFUSED_LINE
    idle, trickle = server.connect(), server.connect()
    trickle.sendall(b"# wirecal")  # and then nothing
    with server.connect() as robot:
        robot.sendall(hello + (log_text + END_MARKER + "\n").encode())
    result = server.finish()
    idle.close()
    trickle.close()
    assert result.complete
    assert out.read_text() == log_text + END_MARKER + "\n"
    assert result.forged == 2
    assert result.probes >= 1  # the probe (the idle ones may still be waiting at the end)
    assert "connection(s) refused: no valid run token" in "\n".join(summary(result, ur5, plan))


def test_idle_clients_are_closed_after_the_handshake_time(serve, tmp_path, monkeypatch):
    monkeypatch.setattr("wirecal.app.receive.HANDSHAKE_S", 0.3)
    server = serve(timeout_s=1.5)
    with server.connect() as idle:
        idle.settimeout(3)
        t0 = time.monotonic()
        assert idle.recv(100) == b""  # closed by the server, not by its own timeout
        assert 0.25 < time.monotonic() - t0 < 1.4
    result = server.finish()
    assert result.probes == 1
    assert "no sender presented the run token within 1.5 s" in result.stopped
    assert not journal_path(tmp_path / "run.csv").exists()


def test_a_sender_trickling_bytes_is_stopped_by_the_line_timeout(serve, tmp_path, log_text, hello):
    """Slowloris: one byte every 0.1 s, never a line end; the per-line timeout (0.6 s)
    stops it although bytes keep coming."""
    out = tmp_path / "run.csv"
    head = "".join(log_text.splitlines(keepends=True)[:6])
    server = serve(timeout_s=0.6)
    t0 = time.monotonic()
    with server.connect() as s:
        s.sendall(hello + head.encode())
        for _ in range(40):  # at most 4 s
            try:
                s.sendall(b"7")
            except OSError:
                break
            if not server.thread.is_alive():
                break
            time.sleep(0.1)
        result = server.finish()
    assert time.monotonic() - t0 < 3
    assert result.stopped == "no complete line arrived within 0.6 s (--timeout) after line 6"
    assert journal_path(out).read_text() == head
    assert not out.exists()


def test_an_early_end_marker_publishes_nothing(serve, tmp_path, log_text, hello, ur5, plan):
    """'# end' after step 3: the journal keeps the rows, the missing points are named."""
    out = tmp_path / "run.csv"
    lines = log_text.splitlines(keepends=True)
    cut = next(k for k, ln in enumerate(lines) if ln.startswith("zero,4,"))
    sent = "".join(lines[:cut]) + END_MARKER + "\n"
    server = serve()
    with server.connect() as s:
        s.sendall(hello + sent.encode())
    result = server.finish()
    assert not result.complete
    assert not out.exists()
    assert journal_path(out).read_text() == sent
    text = summary(result, ur5, plan)
    assert text[0].startswith("the end marker arrived but the log is incomplete or fails")
    assert text[1] == f"  {journal_path(out)}: missing steps 4–{len(plan.steps)} (all points)"


def test_an_end_marker_after_a_log_that_fails_its_checks(serve, tmp_path, log_text, hello):
    """A complete log of another plan ('# plan:' changed) ends with '# end': refused."""
    out = tmp_path / "run.csv"
    other = log_text.replace("# plan: ", "# plan: 0", 1)
    server = serve()
    with server.connect() as s:
        s.sendall(hello + (other + END_MARKER + "\n").encode())
    result = server.finish()
    assert not result.complete
    assert "the log was taken with another plan" in result.problems[0]
    assert journal_path(out).exists()
    assert not out.exists()


def test_the_port_binds_again_right_after_a_run(serve, log_text, hello):
    """The server closes the sender first, so its port is in TIME_WAIT: SO_REUSEADDR."""
    first = serve("a.csv")
    with first.connect() as s:
        s.sendall(hello + (log_text + END_MARKER + "\n").encode())
    assert first.finish().complete
    second = serve("b.csv", port=first.port, timeout_s=0.2)
    assert second.port == first.port
    assert "no sender" in second.finish().stopped


def test_timeout_without_a_sender_writes_nothing(tmp_path, ur5, plan):
    out = tmp_path / "run.csv"
    t0 = time.monotonic()
    result = receive(0, out, ur5, plan, timeout_s=0.3)
    assert 0.3 <= time.monotonic() - t0 < 5
    assert not result.complete
    assert "no sender presented the run token within 0.3 s" in result.stopped
    assert not out.exists()
    assert not journal_path(out).exists()
    assert "nothing received" in summary(result, ur5, plan)[0]


def test_timeout_after_silence_keeps_the_rows(serve, tmp_path, log_text, hello, ur5, plan):
    out = tmp_path / "run.csv"
    head = "".join(log_text.splitlines(keepends=True)[:8])
    server = serve(timeout_s=0.5)
    with server.connect() as s:
        s.sendall(hello + head.encode())
        result = server.finish()  # the sender stays silent and connected
    assert "no complete line arrived within 0.5 s" in result.stopped
    assert journal_path(out).read_text() == head
    assert not out.exists()
    assert "rows, the last" in summary(result, ur5, plan)[0]


def test_existing_journal_and_log_are_never_overwritten(tmp_path, ur5, plan):
    out = tmp_path / "run.csv"
    journal_path(out).write_text("rows of an earlier run\n")
    with pytest.raises(WirecalError, match="earlier run"):
        receive(0, out, ur5, plan, timeout_s=0.2)
    assert journal_path(out).read_text() == "rows of an earlier run\n"
    journal_path(out).unlink()
    out.write_text("old log\n")
    with pytest.raises(WirecalError, match="exists"):
        receive(0, out, ur5, plan, timeout_s=0.2)
    assert out.read_text() == "old log\n"


def test_the_robot_file_and_plan_are_never_the_output(tmp_path, ur5, plan):
    robot = tmp_path / "robot.toml"
    robot.write_text((UR5 / "robot.toml").read_text())
    rob = dataclasses.replace(ur5, source=str(robot))
    for target in (robot, plan.source):
        before = open(target).read()
        with pytest.raises(WirecalError, match="input"):
            receive(0, target, rob, plan, timeout_s=0.2, force=True)
        assert open(target).read() == before


def test_port_in_use_is_a_clear_error(tmp_path, ur5, plan):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        with pytest.raises(WirecalError, match=f"port {port}: cannot listen"):
            receive(port, tmp_path / "run.csv", ur5, plan, timeout_s=0.2)
    assert not journal_path(tmp_path / "run.csv").exists()


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _sender(port: int, data: bytes, forged: bytes | None = None) -> threading.Thread:
    """Send ``data`` once the command listens; first ``forged`` on a connection of its own."""

    def send() -> None:
        for _ in range(100):  # until the command listens (bounded: 5 s)
            try:
                if forged is not None:
                    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                        s.sendall(forged)
                        s.recv(100)  # the refusal, before the real sender connects
                with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                    s.sendall(data)
                return
            except ConnectionRefusedError:
                time.sleep(0.05)

    thread = threading.Thread(target=send, daemon=True)
    thread.start()
    return thread


def _cli_receive(port: int, out, *extra: str):
    return CliRunner().invoke(
        main,
        [
            *("receive", "--robot", ROBOT, "--plan", PLAN, "--host", "127.0.0.1"),
            *("--port", str(port), "-o", str(out), "--timeout", "5", *extra),
        ],
    )


def test_cli_complete_run(tmp_path, log_text, hello):
    """A program with another token first (told at once on stderr), then the run."""
    port, out = _free_port(), tmp_path / "run.csv"
    wrong = b"# wirecal-token " + b"f" * 32 + b"\n"
    thread = _sender(port, hello + (log_text + END_MARKER + "\n").encode(), forged=wrong)
    res = _cli_receive(port, out)
    thread.join(5)
    assert res.exit_code == 0, res.output
    assert "[controller] key is not set" in res.stderr  # the example has no key
    assert "warning: refused 127.0.0.1:" in res.stderr
    assert ": a wrong token (a program generated with another robot file key" in res.stderr
    assert "1 connection(s) refused: no valid run token" in res.stdout
    assert f"{out}: written, " in res.stdout
    assert "(run complete; the log checks passed)" in res.stdout
    assert out.read_text() == log_text + END_MARKER + "\n"


def test_cli_drop_exits_1_and_names_the_journal(tmp_path, log_text, hello):
    port, out = _free_port(), tmp_path / "run.csv"
    thread = _sender(port, hello + log_text[:300].encode())
    res = _cli_receive(port, out)
    thread.join(5)
    assert res.exit_code == 1, res.output
    assert f"{out}.partial" in res.output
    assert "closed the connection" in res.output
    assert journal_path(out).read_text() == log_text[:300]


def test_cli_refuses_a_vplus_robot_and_needs_the_plan(tmp_path):
    viper = str(ROOT / "examples" / "viper_s650" / "robot.toml")
    res = CliRunner().invoke(
        main,
        ["receive", "--robot", viper, "--plan", PLAN, "-o", str(tmp_path / "x.csv")],
    )
    assert res.exit_code == 2
    res = CliRunner().invoke(main, ["receive", "--robot", ROBOT, "-o", str(tmp_path / "x.csv")])
    assert res.exit_code == 2
    assert "--plan" in res.output


def test_ctrl_c_while_waiting_keeps_the_rows_and_says_so(serve, tmp_path, log_text, hello):
    import selectors

    head = "".join(log_text.splitlines(keepends=True)[:6])
    out = tmp_path / "run.csv"

    class InterruptedSelector(selectors.DefaultSelector):  # type: ignore[misc,valid-type]
        def select(self, timeout=None):
            journal = journal_path(out)
            if journal.exists() and journal.stat().st_size == len(head):
                raise KeyboardInterrupt  # Ctrl-C once every sent line is in the journal
            return super().select(min(timeout or 0.05, 0.05))

    monkeypatch = pytest.MonkeyPatch()
    monkeypatch.setattr("wirecal.app.receive.selectors.DefaultSelector", InterruptedSelector)
    try:
        server = serve()
        with server.connect() as s:
            s.sendall(hello + head.encode())
            result = server.finish()
    finally:
        monkeypatch.undo()
    assert result.stopped == "interrupted (Ctrl-C)"
    assert journal_path(out).read_text() == head
    assert not out.exists()


@settings(
    max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(cuts=st.lists(st.integers(1, 400), min_size=1, max_size=12), crlf=st.booleans())
def test_any_chunking_gives_the_same_log(tmp_path_factory, ur5, plan, log_text, hello, cuts, crlf):
    out = tmp_path_factory.mktemp("chunks") / "run.csv"
    data = (log_text + END_MARKER + "\n").encode()
    wire = hello + (data.replace(b"\n", b"\r\n") if crlf else data)
    server = Server(out, ur5, plan, timeout_s=5)
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


def test_the_token_follows_the_key_and_the_plan(tmp_path, ur5, plan):
    """Derived, not drawn: the same robot file and plan give the same token (a program
    generated again and a receiver started again agree); another key or plan does not."""
    keyed = dataclasses.replace(ur5, controller=dataclasses.replace(ur5.controller, key="k" * 16))
    tokens = {
        run_token(ur5, plan.fingerprint()),
        run_token(keyed, plan.fingerprint()),
        run_token(keyed, "0" * 64),
    }
    assert len(tokens) == 3
    assert all(len(t) == 32 and int(t, 16) >= 0 for t in tokens)
    assert run_token(keyed, plan.fingerprint()) == run_token(keyed, plan.fingerprint())
    text = (UR5 / "robot.toml").read_text()
    short = tmp_path / "short.toml"
    short.write_text(text.replace("port = 50000", 'port = 50000\nkey = "too short"'))
    with pytest.raises(WirecalError, match=r"key: has 9 characters; give 16 or more"):
        load_robot(short)
    good = tmp_path / "good.toml"
    good.write_text(text.replace("port = 50000", 'port = 50000\nkey = "' + "k" * 16 + '"'))
    assert load_robot(good).controller.key == "k" * 16


def test_gen_writes_and_names_the_token_receive_expects(tmp_path, ur5, plan):
    """The program generated twice holds the same token line, the one receive checks;
    gen names its first digits and the receive command to run."""
    token = run_token(ur5, plan.fingerprint())
    texts = []
    for folder in ("a", "b"):
        r = CliRunner().invoke(main, ["gen", ROBOT, PLAN, "-o", str(tmp_path / folder)])
        assert r.exit_code == 0, r.output
        texts.append((tmp_path / folder / "wc_run.script").read_text())
    assert texts[0] == texts[1]
    assert f'  socket_send_line("{token_line(token)}", "wc")\n' in texts[0]
    assert f"'wirecal receive {ROBOT} {PLAN} -o LOG'" in r.stdout
    assert f"(it listens on 192.168.1.10:50000, run token {token[:6]}…)" in r.stdout
    assert "[controller] key is not set" in r.stderr


def test_two_connections_with_the_token_the_first_sends(serve, tmp_path, log_text, hello):
    """Both connect before either presents the token: the first to present it is the
    sender, the second is told busy (it cannot take over the run)."""
    out = tmp_path / "run.csv"
    server = serve()
    first, second = server.connect(), server.connect()
    with first, second:
        first.sendall(hello)
        time.sleep(0.2)
        second.sendall(hello + b"zero,1,0,forged\n")
        assert second.recv(100) == BUSY_LINE
        first.sendall((log_text + END_MARKER + "\n").encode())
        result = server.finish()
    assert result.complete
    assert result.refused == 1
    assert out.read_text() == log_text + END_MARKER + "\n"


def test_a_sent_log_with_text_that_is_no_row_is_not_published(serve, tmp_path, log_text, hello):
    """A program's own log holds only rows and '#' lines: terminal text in it (which a
    paste would set aside) keeps it from being published."""
    out = tmp_path / "run.csv"
    lines = log_text.splitlines(keepends=True)
    sent = "".join([*lines[:8], "Step 1 of 10\n", *lines[8:]]) + END_MARKER + "\n"
    server = serve()
    with server.connect() as s:
        s.sendall(hello + sent.encode())
    result = server.finish()
    assert not result.complete
    assert result.problems == [f"{journal_path(out)}:9: has 1 fields; expected 14"]
    assert not out.exists()
