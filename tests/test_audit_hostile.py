"""Issue 41's fresh hostile-input audit: each case (AU…) beside its valid neighbour.

docs/development.md lists the cases; each test here failed before its fix.
"""

from __future__ import annotations

import hashlib
import re
import socket
import tomllib

import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.robot_file import load_robot, robot_from_dict
from wirecal.formats.truth import load_errors
from wirecal.solver.errors import WirecalError

from .conftest import DATA, VIPER

ROBOT = VIPER / "robot.toml"
PLAN = VIPER / "paper_plan.toml"
THETA0 = "theta0_deg = [0, -90, 210, -90, 0, -90]"


def robot_from_text(text: str):
    return robot_from_dict(tomllib.loads(text), "robot.toml")


def refusal(text: str) -> str:
    """The message a robot file's text is refused with."""
    with pytest.raises(WirecalError) as exc:
        robot_from_text(text)
    return str(exc.value)


def _run(*args: object):
    return CliRunner().invoke(main, [str(a) for a in args])


def _plan(tmp_path, theta0: str):
    text = PLAN.read_text(encoding="utf-8")
    assert THETA0 in text
    path = tmp_path / "plan.toml"
    path.write_text(text.replace(THETA0, f"theta0_deg = {theta0}"), encoding="utf-8")
    return path


def test_au01_theta0_alone_in_radians_is_refused(tmp_path):
    """θ0 in radians, the points in degrees: psi and gen took it (exit 0), the encoder
    mounted at the zero pose and every point leaking."""
    plan = _plan(tmp_path, "[0, -1.5708, 3.6652, -1.5708, 0, -1.5708]")
    r = _run("psi", ROBOT, plan)
    assert r.exit_code == 2, r.output
    assert re.search(
        r"theta0_deg: θ0 is within ±2π while the points are not: θ0 looks like radians "
        r"\(in degrees \[0, -90, 210, -90, 0, -90\]",
        r.output,
    ), r.output


def test_au01_theta0_near_the_zero_pose_in_degrees_is_read(tmp_path):
    """The neighbour: a θ0 at the zero pose, or a few degrees from it (the points
    nearer it than its values times 57.3), is degrees."""
    for theta0 in ("[0, 0, 0, 0, 0, 0]", "[0, 0, 0, 0, 5, 0]", "[0, 0, 0, 0, 0.1, 0]"):
        r = _run("psi", ROBOT, _plan(tmp_path, theta0))
        assert r.exit_code == 0, r.output
        assert "radians" not in r.output


def test_au04_a_nan_range_margin_is_refused_where_it_is_given():
    """psi --range-margin nan printed a warning and exited 0 with the range check off
    (--strict: exit 1, "a check failed"); now click refuses it, status 2, as --tol nan."""
    for command in (["psi", ROBOT, PLAN], ["gen", ROBOT, PLAN, "-o", "out"]):
        r = _run(*command, "--range-margin", "nan")
        assert r.exit_code == 2, r.output
        assert "'--range-margin': 'nan' is not a finite number" in r.output


def test_au04_a_range_margin_is_read():
    r = _run("psi", ROBOT, PLAN, "--range-margin", "5", "--strict")
    assert r.exit_code == 0, r.output


def test_au05_import_urdf_refuses_a_non_finite_encoder_option_by_its_name(tmp_path):
    """--parallel-tol-deg nan, --range-mm nan were blamed on the robot file being written
    ('urdf.parallel_tol_deg: is nan'); the option is named now."""
    urdf = DATA / "twisted_arm.urdf"
    for option in ("--parallel-tol-deg", "--range-mm", "--mm-per-count"):
        r = _run("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml", option, "nan")
        assert r.exit_code == 2, r.output
        assert f"'{option}': 'nan' is not a finite number" in r.output


def _gauge_run(tmp_path):
    """The Viper's robot file with a 500 mm reference gauge and a simulated log of it."""
    robot = tmp_path / "gauge.toml"
    text = ROBOT.read_text(encoding="utf-8")
    robot.write_text(text.replace("[encoder]\n", "[encoder]\nreference_length_mm = 500.0\n"))
    log = tmp_path / "gauge.csv"
    r = _run("simulate", robot, PLAN, "-o", log, "--seed", 2)
    assert r.exit_code == 0, r.output
    return robot, log


def test_au02_refine_scale_with_the_stepwise_method_alone_is_refused(tmp_path):
    """solve --method stepwise --refine-scale ran the stepwise method and refined nothing,
    without a word (the scale is refined in the joint method only)."""
    robot, log = _gauge_run(tmp_path)
    r = _run("solve", robot, PLAN, log, "--method", "stepwise", "--refine-scale")
    assert r.exit_code == 2, r.output
    assert "error: --refine-scale refines the scale in the joint method; --method stepwise" in (
        " ".join(r.output.split())
    )


def test_au02_refine_scale_is_refused_before_the_log_is_read(tmp_path):
    """Without a gauge in the robot file the log is not read first (here: none there)."""
    r = _run("solve", ROBOT, PLAN, tmp_path / "absent.csv", "--refine-scale")
    assert r.exit_code == 2, r.output
    assert "declares no gauge ([encoder] reference_length_mm)" in r.output


def test_au02_refine_scale_runs_with_the_joint_method_and_a_gauge(tmp_path):
    robot, log = _gauge_run(tmp_path)
    for method in ("joint", "all"):
        r = _run("solve", robot, PLAN, log, "--method", method, "--refine-scale")
        assert r.exit_code == 0, r.output


def _twisted(tmp_path, xyz: str):
    text = (DATA / "twisted_arm.urdf").read_text(encoding="utf-8")
    assert '<origin xyz="0 0 0.3" rpy="0 0 0.2"/>' in text
    path = tmp_path / "arm.urdf"
    path.write_text(text.replace('<origin xyz="0 0 0.3"', f'<origin xyz="{xyz}"'))
    return path


def test_au06_a_joint_origin_reaching_beyond_10_m_is_millimetres(tmp_path):
    """The URDF's two unit rules (joint origins, link geometry) were twins: an origin was
    refused per coordinate, a shape by its distance; 8 m, 8 m, 0 (11.3 m away) passed.
    One rule now (urdf.check_reach): the distance from the frame's origin."""
    r = _run("import-urdf", _twisted(tmp_path, "8 8 0"), "--tip", "wire", "-o", tmp_path / "r.toml")
    assert r.exit_code == 2, r.output
    assert re.search(
        r"joint '\w+': origin xyz 8 8 0 is beyond 10 m: URDF lengths are metres; written in "
        r"millimetres\? Divide them by 1000 and import again",
        " ".join(r.output.split()),
    ), r.output


def test_au06_a_joint_origin_within_10_m_is_metres(tmp_path):
    r = _run(
        "import-urdf", _twisted(tmp_path, "0 0 0.5"), "--tip", "wire", "-o", tmp_path / "r.toml"
    )
    assert r.exit_code == 0, r.output


TABLE = VIPER / "simulated_cable_table.csv"


def _table_with(tmp_path, extra: str, value):
    """The shipped cable table with a column ``extra`` appended (``value(cells)`` per row)."""
    lines = TABLE.read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    out = [*lines[:first], f"{lines[first]},{extra}"]
    out += [f"{line},{value(line.split(','))}" for line in lines[first + 1 :]]
    path = tmp_path / "table.csv"
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path


def test_au07_a_column_named_twice_is_refused(tmp_path):
    """A second 'length' column (here 1.5 times the first) was ignored without a word:
    the first one fitted, exit 0; which one was meant is not known."""
    table = _table_with(tmp_path, "length", lambda c: f"{float(c[6]) * 1.5:.2f}")
    r = _run("fit", ROBOT, table)
    assert r.exit_code == 2, r.output
    assert (
        "the header names 'length' 2 times (columns 7, 11): which holds the values is not "
        "known; give the others other names in the header"
    ) in " ".join(r.output.split())


def test_au07_a_repeated_column_fit_does_not_read_is_no_matter(tmp_path):
    """The neighbour: two 'note' columns, neither read by the fit."""
    table = _table_with(tmp_path, "note,note", lambda c: "a,b")
    r = _run("fit", ROBOT, table)
    assert r.exit_code == 0, r.output


def _robot_with(tmp_path, old: str, new: str):
    text = ROBOT.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "robot.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    return path


def test_au08_wire_limits_in_metres_are_named(tmp_path):
    """max_wire_speed_mm_s = 1 (1 m/s) and max_wire_accel_mm_s2 = 49 (5 g in m/s²) were
    taken as 1 mm/s and 49 mm/s²: gen wrote programs crawling at the wire's pace, exit 0."""
    for old, new, message in (
        (
            "max_wire_speed_mm_s = 1000.0",
            "max_wire_speed_mm_s = 1.0",
            "encoder.max_wire_speed_mm_s: is 1: a wire limited to under 20 mm/s would take "
            "about a minute per metre; that looks like m/s (1000 mm/s); give mm/s",
        ),
        (
            "max_wire_accel_mm_s2 = 49000.0",
            "max_wire_accel_mm_s2 = 49.0",
            "encoder.max_wire_accel_mm_s2: is 49: under 1000 mm/s² (0.1 g); that looks like "
            "m/s² (49000 mm/s²) or g; give mm/s²",
        ),
    ):
        r = _run("psi", _robot_with(tmp_path, old, new), PLAN)
        assert r.exit_code == 2, r.output
        assert message in " ".join(r.output.split())


def test_au08_slow_wire_limits_in_mm_are_read(tmp_path):
    """The neighbours: 20 mm/s and 1000 mm/s² (0.1 g), the lowest read as given."""
    robot = _robot_with(tmp_path, "max_wire_speed_mm_s = 1000.0", "max_wire_speed_mm_s = 20.0")
    r = _run("psi", robot, PLAN)
    assert r.exit_code == 0, r.output
    robot = _robot_with(tmp_path, "max_wire_accel_mm_s2 = 49000.0", "max_wire_accel_mm_s2 = 1e3")
    r = _run("psi", robot, PLAN)
    assert r.exit_code == 0, r.output


UR5E = VIPER.parent / "ur5e" / "robot.toml"
PAYLOAD_ROBOT = DATA / "payload_viper_s650" / "robot.toml"


def test_au09_link_masses_in_grams_are_named():
    """The UR5e's link masses in grams (17.7 t of links) were read as kg, exit 0: the
    compliances identified from them would be a thousand times too small."""
    text = UR5E.read_text(encoding="utf-8")
    line = "link_mass_kg = [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]"
    assert line in text
    grams = text.replace(line, "link_mass_kg = [3761, 8058, 2846, 1370, 1300, 365]")
    assert (
        "gravity.link_mass_kg: the links weigh 17700 kg in all, more than 5000 kg per metre "
        "of the DH table's lengths: that looks like grams; give kg"
    ) in refusal(grams)
    assert robot_from_text(text).masses is not None  # the neighbour: the file as shipped


def test_au10_a_tool_heavier_than_the_rating_is_named():
    """A tool of 500 (grams, as kg) with a 5 kg rating: refused as 'use a lighter mass' for
    the payload step, and not at all without one; the tool and the rating are named now."""
    text = PAYLOAD_ROBOT.read_text(encoding="utf-8")
    assert "\n[gravity]\n" in text
    heavy = text.replace("\n[gravity]\n", "\n[gravity]\npayload_mass_kg = 500.0\n")
    assert (
        "calibration.rated_payload_kg: is 5 kg, less than the tool's own 500 kg ([gravity] "
        "payload_mass_kg): the arm cannot carry its tool"
    ) in refusal(heavy)
    light = text.replace("\n[gravity]\n", "\n[gravity]\npayload_mass_kg = 1.0\n")
    assert robot_from_text(light).masses.payload_mass_kg == 1.0


def test_au11_mass_centres_in_metres_are_named():
    """A tool's centre [-0.025, 0, 0.02] and the UR5e's link centres in metres were read as
    mm, exit 0 (the tool point, link radii and boxes already had the rule)."""
    text = UR5E.read_text(encoding="utf-8")
    line = "link_mass_kg = [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]"
    tool = text.replace(line, f"{line}\npayload_mass_kg = 1.0\npayload_com_mm = [-0.025, 0, 0.02]")
    assert (
        "gravity.payload_com_mm: [-0.025, 0, 0.02]: every value under 1 mm: that looks like "
        "metres; give it in mm"
    ) in refusal(tool)
    rows = re.search(r"link_com_mm = \[\n(.*?)\n\]", text, re.S)
    assert rows is not None
    metres = re.sub(r"-?\d+\.\d+", lambda m: f"{float(m.group(0)) / 1000:g}", rows.group(1))
    message = refusal(text.replace(rows.group(1), metres))
    assert "gravity.link_com_mm: [0, -0.00193, -0.02561, " in message


def test_au11_mass_centres_in_mm_are_read():
    text = UR5E.read_text(encoding="utf-8")
    line = "link_mass_kg = [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]"
    tool = text.replace(line, f"{line}\npayload_mass_kg = 1.0\npayload_com_mm = [-25, 0, 20]")
    assert list(robot_from_text(tool).masses.payload_com_mm) == [-25, 0, 20]


def _demo_result(before_mm: float, after_mm: float):
    from types import SimpleNamespace

    return SimpleNamespace(
        validations=[],
        tool_error_mm={"before": before_mm, "after": after_mm},
        predicted_mm=None,
        bound_mm=None,
        controller_difference=4.7e-7,
        total_s=9.0,
        folder="demo",
        outputs=["report.html"],
    )


def test_au12_demo_of_an_arm_without_errors_prints_no_reduction(monkeypatch, tmp_path):
    """demo --scale 0 (a perfect arm) ended in a ZeroDivisionError traceback after writing
    every output: the tool-point error before calibration is 0, its reduction undefined."""
    import wirecal.cli.demo as cli_demo

    monkeypatch.setattr(cli_demo, "run_demo", lambda folder, **o: _demo_result(0.0, 0.0714))
    r = _run("demo", "--scale", "0", "-o", tmp_path / "demo")
    assert r.exit_code == 0, r.output
    assert re.search(r"tool-point error vs truth, mean \(mm\) +0\.0000 +0\.0714 +—\n", r.output)


def test_au12_demo_prints_the_reduction_of_an_arm_with_errors(monkeypatch, tmp_path):
    import wirecal.cli.demo as cli_demo

    monkeypatch.setattr(cli_demo, "run_demo", lambda folder, **o: _demo_result(0.5, 0.05))
    r = _run("demo", "-o", tmp_path / "demo")
    assert r.exit_code == 0, r.output
    assert re.search(r"0\.5000 +0\.0500 +90%\n", r.output), r.output


def test_au13_receive_says_listening_only_once_it_listens(tmp_path):
    """'listening on …' was printed before the log was reserved and the port bound: then
    'error: … is also an input', or 'cannot listen on …', contradicted it."""
    plan = UR5E.parent / "plan.toml"
    r = _run("receive", UR5E, plan, "-o", UR5E, "--timeout", 1)
    assert r.exit_code == 2, r.output
    assert "is also an input" in r.output
    assert "listening on" not in r.output
    with socket.socket() as probe:  # a free port on the loopback
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    out = tmp_path / "run.csv"
    r = _run(
        "receive", UR5E, plan, "-o", out, "--timeout", 0.2, "--host", "127.0.0.1", "--port", port
    )
    assert r.exit_code == 1, r.output  # the neighbour: it listens, and says so, then times out
    assert f"listening on 127.0.0.1:{port} for the run of plan" in r.output


def _validation_log(path, rows, robot="Adept Viper s650", setup="test"):
    head = ["# wirecal-validation 1", "# kind: configuration", f"# robot: {robot}"]
    head += [f"# setup: {setup}", "# mm_per_count: 0.025488"]
    columns = "pose,config,j1,j2,j3,j4,j5,j6,counts,samples,spread"
    body = [f"1,{c},0,0,0,0,0,0,{counts},10,0" for c, counts in enumerate(rows, 1)]
    path.write_text("\n".join([*head, columns, *body]) + "\n", encoding="utf-8")
    return path


BEFORE = (100, 140, 120, 90)  # a discrepancy of 50 counts
AFTER = (100, 102, 101, 99)


def test_au14_the_same_run_as_before_and_after_is_refused(tmp_path):
    """validate … BEFORE BEFORE printed 'reduction 0%' with exit 0: the same readings,
    not a calibration's effect."""
    before = _validation_log(tmp_path / "b.csv", BEFORE)
    copy = _validation_log(tmp_path / "copy.csv", BEFORE)
    r = _run("validate", ROBOT, "configuration", before, copy)
    assert r.exit_code == 2, r.output
    assert f"{copy}: holds the readings of {before}, the same run" in " ".join(r.output.split())


def test_au15_a_validation_log_of_another_robot_is_refused(tmp_path):
    """A UR5e's robot file with the Viper's log was taken (its 32-bit counter unwrapping a
    24-bit count); the robot is named now, as solve names a measurement log's."""
    before = _validation_log(tmp_path / "b.csv", BEFORE)
    r = _run("validate", UR5E, "configuration", before)
    assert r.exit_code == 2, r.output
    assert (
        f"{before}: robot 'Adept Viper s650' differs from {UR5E} ('Universal Robots UR5e'); "
        "use the matching robot file"
    ) in " ".join(r.output.split())


def test_au16_before_and_after_of_two_setups_are_refused(tmp_path):
    """BEFORE and AFTER of two validation setups (other poses, another plate) gave a
    'reduction' that compares unlike runs, exit 0."""
    before = _validation_log(tmp_path / "b.csv", BEFORE, setup="one")
    after = _validation_log(tmp_path / "a.csv", AFTER, setup="two")
    r = _run("validate", ROBOT, "configuration", before, after)
    assert r.exit_code == 2, r.output
    assert "BEFORE and AFTER compare only when taken with one validation setup" in (
        " ".join(r.output.split())
    )


def test_au14_to_au16_before_and_after_of_one_setup_are_compared(tmp_path):
    before = _validation_log(tmp_path / "b.csv", BEFORE)
    after = _validation_log(tmp_path / "a.csv", AFTER)
    r = _run("validate", ROBOT, "configuration", before, after)
    assert r.exit_code == 0, r.output
    assert re.search(r"reduction +94%", r.output), r.output


def _import(tmp_path, *options):
    urdf = DATA / "twisted_arm.urdf"
    return _run("import-urdf", urdf, "--tip", "wire", "-o", tmp_path / "r.toml", *options)


def test_au17_import_urdf_refuses_host_and_port_for_a_language_without_sockets(tmp_path):
    """--host and --port ('URScript: …') with --language vplus were written into the V+
    robot file without a word; gen refuses them for V+, import-urdf now too."""
    r = _import(tmp_path, "--language", "vplus", "--host", "x", "--port", 50000)
    assert r.exit_code == 2, r.output
    assert (
        "--host and --port: the Adept/Omron V+ and eV+ programs (--language vplus) write their "
        "log to the controller's disk, not over TCP: leave them out"
    ) in " ".join(r.output.split())
    r = _import(tmp_path, "--language", "urscript", "--host", "192.168.1.10", "--port", 50000)
    assert r.exit_code == 0, r.output  # the neighbour: URScript sends its log over TCP


def test_au18_import_urdf_refuses_joint_speeds_in_rad_s(tmp_path):
    """--joint-speed-deg-s 3.14,… (rad/s) was written as 3.14 °/s, confirmed."""
    r = _import(tmp_path, "--joint-speed-deg-s", "3.14,3.14,3.14,3.14,3.14,3.14")
    assert r.exit_code == 2, r.output
    assert "--joint-speed-deg-s: every speed is within 2π (6.28 °/s, slower than any arm's" in (
        " ".join(r.output.split())
    )
    r = _import(tmp_path, "--joint-speed-deg-s", "20,20,20,30,30,30", "--force")
    assert r.exit_code == 0, r.output  # the neighbour: a heavy arm's slow joints, in °/s


def test_au20_a_resolution_far_coarser_than_the_values_is_refused():
    """fit --joint-resolution-deg 10 on joints logged to 0.1 deg: the gate then allowed a
    residual σ up to 27.7 mm ('passed'), a hundred times the table's own floor."""
    for option, value, steps in (
        ("--joint-resolution-deg", "10", "the joint values take steps of 0.1 deg"),
        ("--length-resolution-mm", "100", "the length values take steps of 0.01 mm"),
    ):
        r = _run("fit", ROBOT, TABLE, option, value)
        assert r.exit_code == 2, r.output
        assert f"{option} {value}: {steps}, more than 10 times finer" in " ".join(r.output.split())


def test_au20_a_resolution_a_few_times_the_values_steps_is_taken():
    """The neighbour: 0.5 deg on values printed to 0.1 deg (a controller's own steps)."""
    r = _run("fit", ROBOT, TABLE, "--joint-resolution-deg", "0.5")
    assert r.exit_code == 0, r.output
    assert "resolution: joints 0.5 deg" in r.output


MAP = "j1=j1,j2=j2,j3=j3,j4=j4,j5=j5,j6=j6,length=length"


def test_au19_one_column_mapped_to_two_keys_is_named():
    """--map j1=j1,j2=j1,…: refused only through its symptom ("'j1': 153 rows beyond joint
    2's limits … joints in another convention?"); the map itself is named now."""
    r = _run("fit", ROBOT, TABLE, "--map", MAP.replace("j2=j2", "j2=j1"))
    assert r.exit_code == 2, r.output
    assert "--map: column 'j1' is given for j1 and j2; each key needs its own column" in r.output
    r = _run("fit", ROBOT, TABLE, "--map", MAP)
    assert r.exit_code == 0, r.output  # the neighbour: each key its own column


WALL = '\n[[cell.half_space]]\nname = "wall"\npoint_mm = {}\nnormal = [-1.0, 0.0, 0.0]\n'


def test_au21_a_half_space_point_in_metres_is_named():
    """A wall at [0.9, 0, 0] (metres) was read as 0.9 mm: gen blamed the plan ('the tool
    fixture and the wall: 494 mm into each other'); boxes and housings had the rule."""
    text = ROBOT.read_text(encoding="utf-8")
    assert "\n[gravity]" in text
    metres = text.replace("\n[gravity]", WALL.format("[0.9, 0.0, 0.0]") + "\n[gravity]", 1)
    assert (
        "cell.half_space[1].point_mm: [0.9, 0, 0]: every value under 1 mm: that looks like "
        "metres; give it in mm"
    ) in refusal(metres)
    mm = text.replace("\n[gravity]", WALL.format("[900.0, 0.0, 0.0]") + "\n[gravity]", 1)
    assert robot_from_text(mm).cell.half_spaces[0].point_mm[0] == 900.0


def test_au22_more_outliers_than_points_is_refused(tmp_path):
    """simulate --outliers 1000 on the 69-point plan wrote 69 outliers without a word."""
    r = _run("simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv", "--outliers", 1000)
    assert r.exit_code == 2, r.output
    assert "--outliers 1000: the plan has 69 points; give at most 69" in r.output
    r = _run("simulate", ROBOT, PLAN, "-o", tmp_path / "all.csv", "--outliers", 69)
    assert r.exit_code == 0, r.output  # the neighbour: every point an outlier


def test_au23_a_stop_after_the_end_of_the_run_is_refused(tmp_path):
    """simulate --stop-after 100000 (a fault: the run stops) wrote the complete run."""
    r = _run("simulate", ROBOT, PLAN, "-o", tmp_path / "run.csv", "--stop-after", 100000)
    assert r.exit_code == 2, r.output
    assert "--stop-after 100000: the run writes 80 readings, so it would not stop" in r.output
    r = _run("simulate", ROBOT, PLAN, "-o", tmp_path / "cut.csv", "--stop-after", 79)
    assert r.exit_code == 0, r.output  # the neighbour: the closing zero is cut
    assert "(69 points)" in r.output


def test_au24_a_theta0_beyond_a_limit_is_said_to_be_beyond(tmp_path):
    """plan --theta0 …,500,…: 'joint 3 = 500 deg is within 5 deg of its limits [-29, 256]'."""
    for value, words in (("500", "is beyond its limits"), ("253", "is within 5 deg of its limits")):
        theta0 = f"0,-90,{value},-90,0,-90"
        r = _run("plan", ROBOT, "--theta0", theta0, "-o", tmp_path / "plan.toml")
        assert r.exit_code == 2, r.output
        assert f"theta0: joint 3 = {value} deg {words} [-29, 256]" in r.output


def _lengths_over(tmp_path, divisor: float):
    """The shipped table with its lengths divided by ``divisor`` (mm to another unit)."""
    lines = TABLE.read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    out = lines[: first + 1]
    for line in lines[first + 1 :]:
        cells = line.split(",")
        cells[6] = f"{float(cells[6]) / divisor:.6f}"
        out.append(",".join(cells))
    path = tmp_path / "table.csv"
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path


def test_au25_lengths_in_inches_are_not_called_metres_alone(tmp_path):
    """Lengths in inches were refused as 'they look like metres; give mm'."""
    r = _run("fit", ROBOT, _lengths_over(tmp_path, 25.4))
    assert r.exit_code == 2, r.output
    assert "they look like metres (or inches: under 1/50 of it); give mm" in (
        " ".join(r.output.split())
    )


def test_au26_the_truth_of_another_run_is_refused_by_report(tmp_path):
    """report --truth with the truth of another simulation showed its offsets beside this
    log's estimates as 'the true offsets', exit 0."""
    for name, seed in (("a", 1), ("b", 2)):
        r = _run("simulate", ROBOT, PLAN, "-o", tmp_path / f"{name}.csv", "--seed", seed)
        assert r.exit_code == 0, r.output
    out = tmp_path / "r.html"
    args = ("report", ROBOT, PLAN, tmp_path / "a.csv", "-o", out, "--truth")
    r = _run(*args, tmp_path / "b.truth.toml")
    assert r.exit_code == 2, r.output
    assert "log_sha256: the truth was written with another log" in r.output
    assert not out.exists()
    # the neighbour: the truth written beside this log (its bytes' sha256) is read
    sha = hashlib.sha256((tmp_path / "a.csv").read_bytes()).hexdigest()
    robot = load_robot(ROBOT)
    assert load_errors(tmp_path / "a.truth.toml", robot, sha)


def test_au27_lint_names_a_file_of_wirecal_s_own_that_is_no_program():
    """lint robot.toml read it as V+ ('no language has this suffix') and listed 95 problems,
    one per line of the robot file."""
    r = _run("lint", ROBOT)
    assert r.exit_code == 2, r.output
    assert (
        f"{ROBOT}: a TOML file (a robot file, plan, patch, truth or validation setup), not a "
        "program"
    ) in " ".join(r.output.split())
    r = _run("lint", "--language", "vplus", ROBOT)  # the neighbour: asked to read it as V+
    assert r.exit_code == 1, r.output


def _pool(tmp_path, rows: int, times: int):
    """The shipped table's first ``rows`` configurations, each ``times`` over, as a pool."""
    lines = TABLE.read_text(encoding="utf-8").splitlines()
    first = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    joints = [",".join(line.split(",")[:6]) for line in lines[first + 1 : first + 1 + rows]]
    path = tmp_path / f"pool{times}.csv"
    path.write_text("\n".join(["j1,j2,j3,j4,j5,j6", *joints * times]) + "\n", encoding="utf-8")
    return path


def test_au28_a_pool_of_few_distinct_configurations_says_so(tmp_path):
    """3 configurations 50 times over: 40 'poses' planned, 24 of them one configuration,
    without a word beyond the predicted error."""
    r = _run("plan", ROBOT, "--pool", _pool(tmp_path, 3, 50), "--points", 40)
    assert r.exit_code == 0, r.output
    assert "note: the pool's 150 rows hold 3 distinct configurations" in r.output
    r = _run("plan", ROBOT, "--pool", _pool(tmp_path, 30, 1), "--points", 20)
    assert r.exit_code == 0, r.output  # the neighbour: every row its own configuration
    assert "distinct configurations" not in r.output
