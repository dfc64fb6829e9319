"""Fault matrix: outputs never lose data, options are range-checked, no traceback.

Each case runs the command line in-process and asserts the exit status, the message and
that no output file appeared (nor a temporary file beside it).
"""

from __future__ import annotations

import errno
import os
import re
import subprocess
import sys
import time

import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats import fileio
from wirecal.formats.fileio import Outputs
from wirecal.solver.errors import WirecalError

from .conftest import VIPER

ROBOT = str(VIPER / "robot.toml")
PLAN = str(VIPER / "paper_plan.toml")
CLI = "import sys\nfrom wirecal.cli.main import main\nsys.argv[0] = 'wirecal'\nmain()\n"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def refused(r, message: str, status: int = 2) -> None:
    """Exit status, an ``error:`` line with the message, and no traceback."""
    assert r.exit_code == status, r.output
    assert r.exception is None or isinstance(r.exception, SystemExit), r.exception
    assert "Traceback" not in r.output
    assert re.search(r"^(error|Error): ", r.output, re.M), r.output
    assert message in r.output, r.output


def files(folder) -> set[str]:
    return {p.name for p in folder.iterdir()}


@pytest.fixture(scope="module")
def log(tmp_path_factory):
    folder = tmp_path_factory.mktemp("log")
    path = folder / "run.csv"
    r = run("simulate", ROBOT, PLAN, "-o", path, "--seed", 3)
    assert r.exit_code == 0, r.output
    return path


# -- outputs: all or none, atomic, never over an input, readable ------------------------


def test_disk_full_while_writing_leaves_nothing(tmp_path, monkeypatch):
    real_put = Outputs.put

    def full(self, path, text):
        if str(path).endswith(".truth.toml"):
            raise fileio.os_problem(path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
        return real_put(self, path, text)

    monkeypatch.setattr(Outputs, "put", full)
    out = tmp_path / "run.csv"
    r = run("simulate", ROBOT, PLAN, "-o", out)
    refused(r, f"error: {tmp_path / 'run.truth.toml'}: No space left on device")
    assert files(tmp_path) == set()
    monkeypatch.undo()  # the rerun is not refused because of an orphan
    assert run("simulate", ROBOT, PLAN, "-o", out).exit_code == 0
    assert files(tmp_path) == {"run.csv", "run.truth.toml"}


@pytest.mark.slow
def test_file_size_limit_real_write(tmp_path):
    """A real EFBIG from the kernel (RLIMIT_FSIZE), in a child process."""
    code = (
        "import resource, signal\n"
        "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
        "resource.setrlimit(resource.RLIMIT_FSIZE, (2000, 2000))\n" + CLI
    )
    out = tmp_path / "run.csv"
    r = subprocess.run(
        [sys.executable, "-c", code, "simulate", ROBOT, PLAN, "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 2, r.stderr
    assert f"error: {out}: File too large" in r.stderr
    assert "Traceback" not in r.stderr
    assert files(tmp_path) == set()


def test_patch_and_spec_table_appear_together(tmp_path, log, monkeypatch):
    real_put = Outputs.put

    def full(self, path, text):
        if str(path).endswith(".spec.txt"):
            raise fileio.os_problem(path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
        return real_put(self, path, text)

    monkeypatch.setattr(Outputs, "put", full)
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "--method", "stepwise", "-o", patch)
    refused(r, "patch.spec.txt: No space left on device")
    assert files(tmp_path) == set()


def test_unwritable_folder_found_before_the_work(tmp_path, monkeypatch):
    def denied(*a, **k):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    def design(*a, **k):
        raise AssertionError("designed before the output was checked")

    monkeypatch.setattr(fileio.tempfile, "mkstemp", denied)
    monkeypatch.setattr("wirecal.cli.plan.design", design)
    out = tmp_path / "plan.toml"
    refused(run("plan", ROBOT, "-o", out), f"error: {out}: Permission denied")
    assert files(tmp_path) == set()


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        refused(run("simulate", ROBOT, PLAN, "-o", ro / "run.csv"), "Permission denied")
        assert files(ro) == set()
    finally:
        ro.chmod(0o755)


def test_publish_is_atomic_between_concurrent_writers(tmp_path):
    """Two runs pass the up-front check together; the second to publish loses cleanly and
    the winner's log and truth stay a pair."""
    log, truth = tmp_path / "same.csv", tmp_path / "same.truth.toml"
    a, b = Outputs([log, truth]).__enter__(), Outputs([log, truth]).__enter__()
    for out, who in ((a, "A"), (b, "B")):
        out.put(log, f"log {who}\n")
        out.put(truth, f"truth {who}\n")
    a.__exit__(None, None, None)
    with pytest.raises(WirecalError, match=r"same\.csv: appeared while this command ran"):
        b.__exit__(None, None, None)
    assert (log.read_text(), truth.read_text()) == ("log A\n", "truth A\n")
    assert files(tmp_path) == {"same.csv", "same.truth.toml"}


def test_second_output_taken_meanwhile_withdraws_the_first(tmp_path):
    log, truth = tmp_path / "x.csv", tmp_path / "x.truth.toml"

    def publish_while_another_writes_the_truth():
        with Outputs([log, truth]) as out:
            out.put(log, "log\n")
            out.put(truth, "truth\n")
            truth.write_text("someone else's\n")

    with pytest.raises(WirecalError, match=r"x\.truth\.toml: appeared while"):
        publish_while_another_writes_the_truth()
    assert files(tmp_path) == {"x.truth.toml"}
    assert truth.read_text() == "someone else's\n"


@pytest.mark.slow
def test_concurrent_simulate_exactly_one_wins(tmp_path):
    out = tmp_path / "same.csv"
    procs = [
        subprocess.Popen(
            [
                sys.executable,
                "-c",
                CLI,
                "simulate",
                ROBOT,
                PLAN,
                "-o",
                str(out),
                "--seed",
                f"{seed}",
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for seed in range(4)
    ]
    results = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    winners = [seed for seed, (rc, _) in enumerate(results) if rc == 0]
    assert len(winners) == 1, results
    for rc, err in results:
        if rc:
            assert rc == 2
            assert "Traceback" not in err
            assert "exists" in err or "appeared while this command ran" in err, err
    assert files(tmp_path) == {"same.csv", "same.truth.toml"}
    # the surviving truth belongs to the surviving log: same seed, same bytes
    again = tmp_path / "again" / "x.csv"
    again.parent.mkdir()
    assert run("simulate", ROBOT, PLAN, "-o", again, "--seed", winners[0]).exit_code == 0
    assert again.read_bytes() == out.read_bytes()
    assert f"seed = {winners[0]}\n" in out.with_suffix(".truth.toml").read_text()


def test_output_equal_to_input_refused_even_with_force(tmp_path, log):
    copy = tmp_path / "run.csv"
    copy.write_bytes(log.read_bytes())
    r = run("solve", ROBOT, PLAN, copy, "-o", copy, "--force")
    refused(r, f"error: {copy}: is also an input ({copy}); write the output to another name")
    assert copy.read_bytes() == log.read_bytes()
    assert files(tmp_path) == {"run.csv"}


def test_plan_over_its_robot_file_refused(tmp_path):
    robot = tmp_path / "robot.toml"
    robot.write_bytes((VIPER / "robot.toml").read_bytes())
    refused(run("plan", robot, "-o", robot, "--force"), "is also an input")
    assert robot.read_bytes() == (VIPER / "robot.toml").read_bytes()


@pytest.mark.parametrize("umask", [0o022, 0o027, 0o077])
def test_outputs_follow_the_umask(tmp_path, umask):
    old = os.umask(umask)
    try:
        assert run("simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv").exit_code == 0
    finally:
        os.umask(old)
    for name in ("run.csv", "run.truth.toml"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o666 & ~umask, name


def test_replaced_file_keeps_its_mode(tmp_path):
    out = tmp_path / "run.csv"
    out.write_text("old\n")
    out.chmod(0o640)
    assert run("simulate", ROBOT, PLAN, "-o", out, "--force").exit_code == 0
    assert out.read_text().startswith("# wirecal-log 2")
    assert out.stat().st_mode & 0o777 == 0o640
    assert files(tmp_path) == {"run.csv", "run.truth.toml"}


def test_force_only_overwrites_accept_foreign_accepts(tmp_path, log):
    robot = tmp_path / "robot.toml"
    robot.write_text((VIPER / "robot.toml").read_text().replace("0.025488", "0.0255"))
    r = run("solve", robot, PLAN, log, "--method", "stepwise", "--force")
    refused(r, "use the matching robot file, or --accept-foreign")
    r = run("solve", robot, PLAN, log, "--method", "stepwise", "--accept-foreign")
    assert r.exit_code == 0, r.output


def test_existing_output_refused_before_planning(tmp_path, monkeypatch):
    out = tmp_path / "plan.toml"
    out.write_text("mine\n")

    def design(*a, **k):
        raise AssertionError("designed before the output was checked")

    monkeypatch.setattr("wirecal.cli.plan.design", design)
    refused(run("plan", ROBOT, "-o", out), f"error: {out}: exists; choose another name")
    assert out.read_text() == "mine\n"


def test_demo_failure_leaves_no_folder(tmp_path, monkeypatch):
    def fail(out, folder, *a):
        out.put(folder / "truth.toml", "x\n")
        raise WirecalError("the twin's measurement run stopped: test")

    monkeypatch.setattr("wirecal.app.demo._run", fail)
    folder = tmp_path / "demo"
    refused(run("demo", "-o", folder), "the twin's measurement run stopped")
    assert not folder.exists()


def test_gen_failure_removes_the_folder_it_made(tmp_path, monkeypatch):
    def denied(*a, **k):
        raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))

    monkeypatch.setattr(fileio.tempfile, "mkstemp", denied)
    folder = tmp_path / "out"
    refused(run("gen", ROBOT, PLAN, "-o", folder), "WIRECAL.V2: Permission denied")
    assert not folder.exists()


# -- options ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["solve", ROBOT, PLAN, "LOG", "--zero-tol", "nan"], "'nan' is not a finite number"),
        (["solve", ROBOT, PLAN, "LOG", "--joint-tol", "nan"], "'nan' is not a finite number"),
        (["solve", ROBOT, PLAN, "LOG", "--spread-tol", "-0.1"], "is not in the range x>0"),
        (["solve", ROBOT, PLAN, "LOG", "--omega", "inf"], "'inf' is not a finite number"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--noise-mm", "nan"], "not a finite number"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--noise-mm", "-1"], "is not in the range x>=0"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--outlier-mm", "nan"], "not a finite number"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--seed", "-5"], "is not in the range"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--slip", "11:0.5"], "has steps 1–10"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--counter-start", "1e300"], "holds -8388608…"),
        (["simulate", ROBOT, PLAN, "-o", "OUT", "--samples", "1000000000"], "1<=x<=1000"),
        (["gen", ROBOT, PLAN, "-o", "OUT", "--zero-tol", "nan"], "not a finite number"),
        (["gen", ROBOT, PLAN, "-o", "OUT", "--margin", "-1"], "is not in the range x>=0"),
        (["plan", ROBOT, "-o", "OUT", "--tol", "nan"], "not a finite number"),
        (["psi", ROBOT, PLAN, "--tol", "nan"], "not a finite number"),
        (["demo", "-o", "OUT", "--scale", "-1"], "is not in the range 0.0<=x<=2.5"),
        (["demo", "-o", "OUT", "--scale", "20"], "is not in the range 0.0<=x<=2.5"),  # NG08
        (["demo", "-o", "OUT", "--seed", "-5"], "is not in the range"),
    ],
)
def test_bad_numbers_refused(tmp_path, log, args, message):
    args = [{"LOG": log, "OUT": tmp_path / "out"}.get(a, a) for a in args]
    refused(run(*args), message)
    assert files(tmp_path) == set()


def _seven_joint_robot(tmp_path):
    text = (VIPER / "robot.toml").read_text()
    text = text.replace(  # a seventh row after the sixth (its comment stays on the line)
        "    [  90.0,    0.0,  0.0,  80.0],",
        "    [  90.0,    0.0,  0.0,  80.0], [0.0, 50.0, 0.0, 0.0],",
    )
    text = text.replace("-120.0, -360.0]", "-120.0, -360.0, -90.0]")
    text = text.replace("120.0,  360.0]", "120.0,  360.0, 90.0]")
    text = text.replace("375.0, 600.0]", "375.0, 600.0, 300.0]")
    text = text.replace("45.0, 37.0]", "45.0, 37.0, 35.0]")  # link_radius_mm
    path = tmp_path / "seven.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("command", ["simulate", "solve"])
def test_other_than_six_joints_said_up_front(tmp_path, log, command):
    robot = _seven_joint_robot(tmp_path)
    args = ["-o", tmp_path / "out.csv"] if command == "simulate" else [log]
    r = run(command, robot, PLAN, *args)
    refused(r, "7 joints; the controller programs and the log format are for 6-joint arms")
    assert r.output.count("error:") == 1
    assert files(tmp_path) == {"seven.toml"}


def test_plan_notes_other_than_six_joints(tmp_path, monkeypatch):
    robot = _seven_joint_robot(tmp_path)

    def design(*a, **k):
        raise WirecalError("stop here")

    monkeypatch.setattr("wirecal.cli.plan.design", design)
    r = run("plan", robot)
    refused(r, "stop here")
    assert "note: " in r.output
    assert "for 6-joint arms" in r.output
    assert r.output.index("note: ") < r.output.index("error: ")


# -- tracebacks that were ---------------------------------------------------------------


def test_plan_narrow_joint_range(tmp_path):
    robot = tmp_path / "narrow.toml"
    robot.write_text(
        (VIPER / "robot.toml")
        .read_text()
        .replace("-190.0, -120.0, -360.0]", "-190.0, 100.0, -360.0]")
        .replace("190.0,  120.0,  360.0]", "190.0,  108.0,  360.0]")
    )
    t = time.perf_counter()
    r = run("plan", robot, "-o", tmp_path / "plan.toml")
    # the robot file states the planner's rule, so the file itself is refused
    refused(
        r,
        "kinematics.joint_max_deg: joint 5: range [100, 108] spans 8 deg, no more than 10 deg: "
        "no room for plan points 5 deg inside both limits",
    )
    assert time.perf_counter() - t < 10
    assert files(tmp_path) == {"narrow.toml"}


@pytest.mark.parametrize("command", ["psi", "solve"])
def test_plan_point_at_theta0(tmp_path, log, command):
    text = PLAN_TEXT = (VIPER / "paper_plan.toml").read_text()
    first = PLAN_TEXT.index("points_deg = [\n") + len("points_deg = [\n")
    plan = tmp_path / "plan.toml"
    plan.write_text(text[:first] + "    [0, -90, 210, -90, 0, -90],\n" + text[first:])
    args = [log] if command == "solve" else []
    refused(
        run(command, ROBOT, plan, *args),
        "step[1].points_deg[1]: the wire length there is 0 mm (below 1 mm)",
    )


def _validation_log(path, kind, rows):
    head = ["# wirecal-validation 1", f"# kind: {kind}", "# robot: Adept Viper s650"]
    head += ["# setup: test", "# mm_per_count: 0.025488"]
    columns = (
        "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread"
        if kind == "configuration"
        else "row,col,x,y,z"
    )
    path.write_text("\n".join([*head, columns, *rows]) + "\n")
    return path


def test_validate_configuration_zero_before(tmp_path):
    rows = [f"1,{c},0,0,0,0,0,0,100,10,0" for c in (1, 2, 3, 4)]
    before = _validation_log(tmp_path / "b.csv", "configuration", rows)
    rows2 = [f"1,{c},0,0,0,0,0,0,{100 + c},10,0" for c in (1, 2, 3, 4)]
    after = _validation_log(tmp_path / "a.csv", "configuration", rows2)
    r = run("validate", "configuration", before, after, "--robot", ROBOT)
    assert r.exit_code == 0, r.output
    assert re.search(r"^reduction\s+–\s+–\s+–$", r.output, re.M), r.output
    r = run("validate", "configuration", before, after, "--json", "--robot", ROBOT)
    assert '"mean": null' in r.output


@pytest.mark.parametrize(
    ("rows", "what"),
    [
        (["1,1,0,0,5", "1,2,10,0,5"], "the log has 2 (2 distinct)"),
        (["1,1,0,0,5", "1,2,10,0,5", "1,3,20,0,5", "1,4,30,0,6"], "log has 4 (4 distinct), all"),
        ([f"1,{c},7,8,5" for c in range(1, 6)], "the log has 5 (1 distinct)"),
    ],
)
def test_validate_plane_needs_three_points_off_a_line(tmp_path, rows, what):
    path = _validation_log(tmp_path / "p.csv", "plane", rows)
    r = run("validate", "plane", path)
    refused(r, "the plane fit needs at least three probed points not on one line; the ")
    assert what in r.output


def test_slip_blames_one_step(tmp_path):
    out = tmp_path / "run.csv"
    assert run("simulate", ROBOT, PLAN, "-o", out, "--slip", "4:0.5").exit_code == 0
    r = run("solve", ROBOT, PLAN, out)
    refused(r, "zero reading at step 5 is +0.5")
    assert r.output.count("error:") == 1, r.output


def test_interrupt_leaves_nothing_and_folder_it_made_goes(tmp_path):
    folder = tmp_path / "new"

    def interrupted():
        with Outputs([folder / "a.txt"], folder=folder) as out:
            out.put(folder / "a.txt", "a\n")
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        interrupted()
    assert files(tmp_path) == set()


def test_force_replaces_all_or_restores_all(tmp_path, monkeypatch):
    a, b = tmp_path / "a.txt", tmp_path / "b.txt"
    a.write_text("old a\n")
    b.write_text("old b\n")
    real_replace = os.replace

    def fail_on_b(src, dst):
        if str(dst) == str(b):
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        return real_replace(src, dst)

    monkeypatch.setattr(fileio.os, "replace", fail_on_b)

    def replace_both():
        with Outputs([a, b], force=True) as out:
            out.put(a, "new a\n")
            out.put(b, "new b\n")

    with pytest.raises(WirecalError, match=r"b\.txt: Input/output error"):
        replace_both()
    assert (a.read_text(), b.read_text()) == ("old a\n", "old b\n")
    assert files(tmp_path) == {"a.txt", "b.txt"}


def test_filesystem_without_hard_links(tmp_path, monkeypatch):
    """FAT on a USB stick: publish by exclusive create; still never over another file."""

    def no_links(src, dst):
        raise OSError(errno.EPERM, os.strerror(errno.EPERM))

    monkeypatch.setattr(fileio.os, "link", no_links)
    out = tmp_path / "run.csv"
    assert run("simulate", ROBOT, PLAN, "-o", out).exit_code == 0
    assert out.read_text().startswith("# wirecal-log 2")
    refused(run("simulate", ROBOT, PLAN, "-o", out), "exists")
    out.chmod(0o600)
    assert run("simulate", ROBOT, PLAN, "-o", out, "--force", "--seed", 2).exit_code == 0
    assert out.stat().st_mode & 0o777 == 0o600
    assert files(tmp_path) == {"run.csv", "run.truth.toml"}
