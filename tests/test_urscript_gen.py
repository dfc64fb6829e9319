"""The URScript programs: golden bytes, determinism, limits, the rows they send, the CLI.

The row-formatting path (wc_run generated without wc_solve) is checked by running the
generated ``wc_run`` itself: the script
subset the generator emits (``def``/``while``/``if``/``elif``/``else``/``end``, ``local``,
lists) is close enough to Python that a line-by-line rewrite (``end`` dropped, ``local``
dropped) runs it, with the controller's functions replaced by stubs that play a
recorded encoder and joint readings. The lines it sends must parse with the project's
log reader and carry the stubbed numbers.
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.run_token import run_token, token_line
from wirecal.gen.urscript.program import UrOptions, scripts
from wirecal.solver.errors import WirecalError

ROOT = Path(__file__).resolve().parent.parent
UR5 = ROOT / "examples" / "ur5e"
VIPER = ROOT / "examples" / "viper_s650"
GOLDEN = Path(__file__).parent / "golden" / "ur5e"
NO_SOLVER = UrOptions(solver=False)  # the rewrite into Python runs the rows' path only; wc_solve
# runs in the URScript twin with 32-bit floats (tests/test_urscript_solver.py)


@pytest.fixture(scope="module")
def ur5():
    robot = load_robot(UR5 / "robot.toml")
    return robot, load_plan(UR5 / "plan.toml", robot)


def test_golden_scripts(ur5):
    """The shipped example's programs, byte for byte; WIRECAL_UPDATE_GOLDEN=1 rewrites them
    after an intended change (review the diff)."""
    out = scripts(*ur5)
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        for name, text in out.items():
            (GOLDEN / name).write_bytes(text.encode("ascii"))
    assert sorted(out) == sorted(p.name for p in GOLDEN.glob("*.script"))
    for name, text in out.items():
        assert text == (GOLDEN / name).read_text(encoding="ascii"), name


def test_deterministic_and_ascii(ur5):
    a, b = scripts(*ur5), scripts(*ur5)
    assert a == b
    for name, text in a.items():
        text.encode("ascii")
        lines = text.split("\n")
        assert lines[0].startswith("def wc_")  # def in column 1, the body indented, end last
        assert lines[-2] == "end"
        assert lines[-1] == ""
        assert all(line.startswith("  ") for line in lines[1:-2] if line), name


def test_targets_are_the_plan_in_radians(ur5):
    robot, plan = ur5
    run = scripts(robot, plan)["wc_run.script"]
    targets = [
        [float(x) for x in line.split("movej([")[1].split("]")[0].split(",")]
        for line in run.split("\n")
        if "movej([" in line
    ]
    expected = []
    for step in plan.steps:
        expected.append(plan.theta0_deg)
        expected += list(step.via_deg) + list(step.points_deg)
    expected.append(plan.theta0_deg)
    assert np.allclose(np.degrees(targets), expected, atol=1e-6)


def test_needs_pc_address(ur5):
    robot, plan = ur5
    bare = dataclasses.replace(robot, controller=dataclasses.replace(robot.controller, host=None))
    with pytest.raises(WirecalError, match=r"no PC address .* gen --host"):
        scripts(bare, plan)
    assert '"10.0.0.7", 50000' in scripts(bare, plan, UrOptions(host="10.0.0.7"))["wc_run.script"]


# -- running wc_run's own text ------------------------------------------------------------


def _python(script: str) -> str:
    """Rewrite the emitted URScript subset as Python (``end`` and ``local`` dropped)."""
    out = []
    for line in script.split("\n"):
        body = line.strip()
        if body == "end":
            continue
        indent = line[: len(line) - len(line.lstrip())]
        if body.startswith("local "):
            body = body[len("local ") :]
        if body == "halt":
            body = "raise SystemExit('halt')"
        out.append(indent + body)
    return "\n".join(out) + "\nwc_run()\n"


def _str_cat(a, b) -> str:
    def text(x):
        assert isinstance(x, (str, int)), f"str_cat of a {type(x).__name__}: {x!r}"
        return str(x)

    return text(a) + text(b)


class _Controller:
    """Stubs of the controller functions wc_run calls: a recorded encoder and joints."""

    def __init__(self, counts, joints_rad, times_ns=None):
        self.counts = iter(counts)
        self.joints = iter(joints_rad)
        self.times = iter(times_ns if times_ns is not None else [0] * (len(joints_rad) + 1))
        self.sent: list[str] = []
        self.log: list[str] = []
        self.popups: list[str] = []

    def names(self) -> dict:
        return {
            "floor": math.floor,
            "str_cat": _str_cat,
            "str_len": len,
            "sleep": lambda t: None,
            "movej": lambda q, a, v: None,
            "encoder_enable_pulse_decode": lambda i, kind, a, b: None,
            "encoder_get_tick_count": lambda i, opt="": next(self.counts),
            "get_actual_joint_positions": lambda: next(self.joints),
            "socket_open": lambda host, port, name: True,
            "socket_close": lambda name: None,
            "socket_send_line": lambda line, name: self.sent.append(line) or True,
            "textmsg": lambda a, b="": self.log.append(f"{a}{b}"),
            "popup": lambda s, **kw: self.popups.append(s),
            "time": self.time,
        }

    def time(self, mode):
        assert mode == 0
        ns = next(self.times)
        return SimpleNamespace(sec=ns // 10**9, nanosec=ns % 10**9)


def test_rows_sent_parse_with_the_log_reader(ur5):
    robot, plan = ur5
    run = scripts(robot, plan, NO_SOLVER)["wc_run.script"]
    rows = plan.n_points + len(plan.steps) + 1
    samples = 10
    rng = np.random.default_rng(3)
    base = 2**31 - 40_000 + rng.integers(-2000, 2000, rows)  # near the int32 top
    zeros = np.cumsum([0] + [1 + len(s.points_deg) for s in plan.steps])
    base[zeros] = base[0]  # the zero readings agree: no slip
    noise = rng.integers(0, 3, (rows, samples))  # a spread of up to 2 counts
    counts = (base[:, None] + noise).ravel().tolist()
    joints = rng.uniform(-6.2, 6.2, (rows, 6))
    start_ns = 123_456 * 10**9 + 999_999_000  # the controller has run for 34 h
    times = start_ns + np.cumsum(rng.integers(10**8, 2 * 10**10, rows + 1))
    times[0] = start_ns
    ctl = _Controller(counts, joints.tolist(), times.tolist())
    exec(compile(_python(run), "wc_run.script", "exec"), ctl.names())
    assert ctl.sent[-1] == "# end"
    # first the run token, which 'wirecal receive' checks and the log tab never shows
    assert ctl.sent[0] == token_line(run_token(robot, plan.fingerprint()))
    assert not any(run_token(robot, plan.fingerprint()) in line for line in ctl.log)
    assert set(ctl.sent[1:]) <= set(ctl.log)  # every log line sent is in the log tab too
    log = parse_log("\n".join(ctl.sent[1:-1]) + "\n", "sent")
    assert log.plan == plan.fingerprint()
    assert log.robot == robot.name
    assert len(log.readings) == rows
    for k, r in enumerate(log.readings):
        expected = base[k] + noise[k, 0] + (noise[k] - noise[k, 0]).mean()
        assert r.counts == pytest.approx(expected, abs=5e-5)
        assert r.spread == noise[k].max() - noise[k].min()
        assert r.samples == samples
        assert np.allclose(r.joints_deg, np.degrees(joints[k]), atol=6e-5)
        assert r.t_s == math.floor((times[k + 1] - start_ns) / 10**6) / 1000
        assert r.settle_s == 3.0
    kinds = [(r.kind, r.step, r.index) for r in log.readings]
    assert kinds[0] == ("zero", 1, 0)
    assert kinds[-1] == ("zero", len(plan.steps) + 1, 0)
    assert ctl.popups == []  # no spread above 0.1 mm, no slip


def test_slip_raises_a_popup(ur5):
    robot, plan = ur5
    run = scripts(robot, plan, NO_SOLVER)["wc_run.script"]
    rows = plan.n_points + len(plan.steps) + 1
    counts = [1000] * (rows * 10)
    second_zero = (1 + len(plan.steps[0].points_deg)) * 10
    counts[second_zero:] = [1010] * (len(counts) - second_zero)  # 0.25 mm: the wire slipped
    ctl = _Controller(counts, [[0.0] * 6] * rows)
    exec(compile(_python(run), "wc_run.script", "exec"), ctl.names())
    assert len(ctl.popups) == 1
    assert "slipped" in ctl.popups[0]
    assert "during step 1" in ctl.popups[0]


def test_a_slow_drift_raises_no_popup(ur5):
    """Each zero reading 2 counts (0.05 mm) above the last: 0.5 mm from the first by the
    closing zero, but no jump between two zeros: a drift for the PC to fit, not a slip."""
    robot, plan = ur5
    run = scripts(robot, plan, NO_SOLVER)["wc_run.script"]
    zero_rows = np.cumsum([0] + [1 + len(s.points_deg) for s in plan.steps])
    rows = plan.n_points + len(plan.steps) + 1
    level = np.cumsum(np.isin(np.arange(rows), zero_rows)) * 2  # +2 counts at each zero
    ctl = _Controller([int(1000 + c) for c in np.repeat(level, 10)], [[0.0] * 6] * rows)
    exec(compile(_python(run), "wc_run.script", "exec"), ctl.names())
    assert ctl.popups == []


# -- the command line ---------------------------------------------------------------------


def _gen(*args):
    return CliRunner().invoke(main, ["gen", *map(str, args)])


def test_gen_writes_the_scripts_of_the_robot_files_language(tmp_path):
    r = _gen(UR5 / "robot.toml", UR5 / "plan.toml", "-o", tmp_path / "out", "--port", 50123)
    assert r.exit_code == 0, r.output
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == ["wc_check.script", "wc_mount.script", "wc_run.script"]
    assert '192.168.1.10", 50123' in (tmp_path / "out" / "wc_run.script").read_text()


def test_gen_language_other_than_the_robot_files_is_refused_with_one_message(tmp_path):
    """--language is a check: both directions give the same one message and write nothing."""
    r = _gen(UR5 / "robot.toml", UR5 / "plan.toml", "-o", tmp_path / "v", "--language", "vplus")
    assert r.exit_code == 2
    lines = [x for x in r.output.splitlines() if x.startswith("error:")]
    assert lines == [
        f"error: {UR5 / 'robot.toml'}: [controller] language is 'urscript' (encoder interface "
        "\"pulse\", a 32-bit counter), not 'vplus': the encoder set-up belongs to the language, "
        "so --language cannot switch it. For Adept/Omron V+ and eV+, write a robot file with "
        'language = "vplus" and its encoder keys (import-urdf --language vplus does), or drop '
        "--language"
    ]
    r = _gen(
        VIPER / "robot.toml",
        VIPER / "paper_plan.toml",
        "-o",
        tmp_path / "u",
        "--language",
        "urscript",
    )
    assert r.exit_code == 2
    assert r.output.count("error:") == 1
    assert (
        "language is 'vplus' (encoder interface \"belt\", a 24-bit counter), not 'urscript'"
        in r.output
    )
    assert not (tmp_path / "u").exists()
    assert not (tmp_path / "v").exists()
    r = _gen(UR5 / "robot.toml", UR5 / "plan.toml", "-o", tmp_path / "w", "--language", "urscript")
    assert r.exit_code == 0, r.output  # the file's own language: a check that passes


def test_gen_refuses_v_plus_options_for_urscript(tmp_path):
    r = _gen(UR5 / "robot.toml", UR5 / "plan.toml", "-o", tmp_path / "o", "--lf")
    assert r.exit_code == 2
    assert "--lf: not taken by the Universal Robots URScript programs" in r.output
    r = _gen(VIPER / "robot.toml", VIPER / "paper_plan.toml", "-o", tmp_path / "p", "--port", 5)
    assert r.exit_code == 2
    assert "--port: not taken by the Adept/Omron V+ and eV+ programs" in r.output


@pytest.fixture(scope="module")
def helpers(ur5) -> dict:
    """The number helpers of wc_check, defined by running the script's own text."""
    check = scripts(*ur5)["wc_check.script"]
    head = check.split("  wc_enable()\n")[0] + "  return [wc_split, wc_fix]\n"
    names = {"floor": math.floor, "str_cat": _str_cat, "str_len": len}
    exec(compile(_python(head).replace("wc_run()", "found = wc_check()"), "h", "exec"), names)
    return dict(zip(("split", "fix"), names["found"], strict=True))


@settings(max_examples=200, deadline=None)
@given(n=st.integers(-(2**31), 2**31 - 1), nd=st.sampled_from([3, 4]))
def test_number_text_is_exact(helpers, n, nd):
    h = helpers
    p = 10**nd
    ip, fr = h["split"](n, p)
    assert ip * p + fr == n
    assert 0 <= fr < p
    sign = "-" if n < 0 else ""
    expected = f"{sign}{abs(n) // p}.{abs(n) % p:0{nd}d}"  # written from the integer itself
    assert h["fix"](ip, fr, nd, p) == expected


def test_check_shows_counts_and_mm(ur5):
    check = scripts(*ur5)["wc_check.script"]
    counts = [7, 7, 7 + 3923, 7 - 1] + [7] * 57
    ctl = _Controller(counts, [])
    exec(compile(_python(check).replace("wc_run()", "wc_check()"), "c", "exec"), ctl.names())
    assert ctl.log[:3] == [
        "counts 0   mm 0.0000",
        "counts 3923   mm 99.9894",
        "counts -1   mm -0.0255",
    ]
    assert len(ctl.log) == 60


def test_socket_refused_stops_before_any_motion(ur5):
    run = scripts(*ur5)["wc_run.script"]
    ctl = _Controller([], [])
    names = ctl.names()
    moves = []
    names["socket_open"] = lambda host, port, name: False
    names["movej"] = lambda q, a, v: moves.append(q)
    with pytest.raises(SystemExit, match="halt"):
        exec(compile(_python(run), "wc_run.script", "exec"), names)
    assert moves == []
    assert ctl.sent == []
    assert "Start 'wirecal receive --robot ROBOT --plan PLAN -o LOG'" in ctl.popups[0]


def test_connection_lost_mid_run_keeps_the_rows_in_the_log_tab(ur5):
    robot, plan = ur5
    run = scripts(robot, plan, NO_SOLVER)["wc_run.script"]
    rows = plan.n_points + len(plan.steps) + 1
    ctl = _Controller([500] * (rows * 10), [[0.1] * 6] * rows)
    names = ctl.names()
    names["socket_send_line"] = lambda line, name: (
        len(ctl.sent) < 20 and (ctl.sent.append(line) or True)
    )
    exec(compile(_python(run), "wc_run.script", "exec"), names)
    assert len(ctl.sent) == 20
    lost = [line for line in ctl.log if line.startswith("# *** not sent to the PC")]
    # 6 header lines, the rows and "# end", less the 19 sent after the token
    assert len(lost) == 6 + rows + 1 - 19
    log = parse_log("\n".join(ctl.log) + "\n", "pasted")  # the whole log tab
    assert len(log.readings) == rows
