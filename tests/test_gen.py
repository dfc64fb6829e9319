"""``wirecal gen``: golden file, V+ rules on every generated variant (the twin's parser),
exact tables, the targets of the run against the plan, refusals."""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.robot_file import robot_from_dict
from wirecal.gen.tables import build_tables
from wirecal.gen.vplus.literals import double_literal
from wirecal.gen.vplus.program import GenOptions, line_ends, module_text
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError
from wirecal.solver.run_parameters import RunParameters

from .conftest import VIPER

GOLDEN = VIPER.parents[1] / "tests" / "golden" / "viper_s650" / "WIRECAL.V2"


@pytest.fixture(scope="module")
def module(viper_module):
    return viper_module


def test_golden_file(module):
    """The Viper module is byte-for-byte the reviewed one, CRLF line ends included (ACE
    writes V+ files so); WIRECAL_UPDATE_GOLDEN=1 rewrites it after an intended change
    (review the diff)."""
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        GOLDEN.write_bytes(line_ends(module).encode("ascii"))
    golden = GOLDEN.read_bytes()
    assert golden.count(b"\r\n") == golden.count(b"\n") > 3000  # every line, no bare LF
    assert line_ends(module).encode("ascii") == golden


def _device_robot(viper):
    data = tomllib.loads((VIPER / "robot.toml").read_text())
    data["encoder"].update(interface="device", channel=0)
    return robot_from_dict(data, "device.toml")


def test_device_interface_is_refused_with_its_reason(viper, paper_plan):
    """DEVICE(0, unit, err, 1) is scale*(count-offset) clamped to SETDEVICE's limits (User's
    Guide p. 354) and SETDEVICE's syntax is unconfirmed: no program is generated for it."""
    with pytest.raises(WirecalError) as e:
        module_text(_device_robot(viper), paper_plan)
    text = str(e.value)
    assert 'device.toml: encoder.interface = "device"' in text
    assert "p. 354" in text
    assert "SETDEVICE" in text
    assert 'interface = "belt"' in text


@pytest.mark.parametrize("variant", ["paper", "printed", "patch", "options", "echo", "reference"])
def test_every_generated_module_follows_the_rules(viper, paper_plan, printed_plan, variant):
    robot, plan, opt = viper, paper_plan, GenOptions()
    if variant == "reference":
        data = tomllib.loads((VIPER / "robot.toml").read_text())
        data["encoder"].update(reference_length_mm=500.0, reference_repeats=2)
        robot = robot_from_dict(data, "reference.toml")
    if variant == "printed":
        plan = printed_plan
    elif variant == "echo":
        opt = GenOptions(echo_log=True)
    elif variant == "patch":
        opt = GenOptions(patch={n: 0.1 for n in plan.order})
    elif variant == "options":
        opt = GenOptions(
            run=RunParameters(speed_pct=5, accel_pct=10, settle_s=4.5, readings=50),
            zero_tol_mm=0.05,
            log_file="RUN2.CSV",
        )
    text = module_text(robot, plan, opt)
    assert len(parse_module(text, "WIRECAL.V2").programs) == text.count(".PROGRAM ") >= 27
    assert all(len(line) <= 80 for line in text.split("\n"))
    assert text.count(".PROGRAM ") == text.count("\n.END") + (text.startswith(".END"))
    if variant == "echo":
        write = text[text.index(".PROGRAM wc.write(") :]
        assert write.index("TYPE $line") < write.index("CALL wc.put(wc.lun, $line)")
    else:
        assert "TYPE $line" not in text
    if variant == "reference":  # the reference step before step 1, rows of step 0
        run = text[text.index(".PROGRAM wc.run()") :]
        assert run.index("CALL wc.ref()") < run.index("CALL wc.meas(1, 0)")
        assert "FOR k = 1 TO 2" in text[text.index(".PROGRAM wc.ref()") :]
        assert 'CALL wc.row("reference,", s, idx, cfirst, spread, tsam, tsam-t0)' in text
    else:
        assert "wc.ref" not in text
    if variant == "options":
        assert "SPEED 5 ALWAYS" in text
        assert "wc.nsamp = 50" in text
        assert "RUN2.CSV" in text


def test_deterministic(viper, paper_plan, module):
    assert module_text(viper, paper_plan) == module


def test_run_moves_exactly_through_the_plan(module, paper_plan):
    run = module[module.index(".PROGRAM wc.run()") :]
    run = run[: run.index(".END")]
    targets = [
        [float(v) for v in m.split(",")]
        for m in re.findall(r"SET #wc\.p = #PPOINT\(([^)]*)\)", run)
    ]
    expected = []
    for s in paper_plan.steps:
        expected.append(paper_plan.theta0_deg)
        expected += list(s.via_deg) + list(s.points_deg)
    expected.append(paper_plan.theta0_deg)
    np.testing.assert_array_equal(np.array(targets), np.array(expected))
    # each point is followed by BREAK and its measurement, with its plan position
    calls = re.findall(r"CALL wc\.meas\((\d+), (\d+)\)", run)
    _, step, index = paper_plan.all_points()
    # the zero of every step, then the closing zero (logged as step 11) after the last
    assert [int(s) for s, i in calls if i == "0"] == list(range(1, 12))
    assert [(int(a), int(b)) for a, b in calls if b != "0"] == list(zip(step, index, strict=True))
    assert run.count("BREAK") == 69 + 10 + 1


def _value(literal: str) -> float:
    m = re.fullmatch(r"(-?)\^D(\d+)(?:/wc\.p10\[(\d+)\])?", literal)
    if m:
        return (-1 if m.group(1) else 1) * int(m.group(2)) / 10 ** int(m.group(3) or 0)
    return float(literal)


def test_data_constants_read_back_exactly(module, viper, paper_plan):
    t = build_tables(viper, paper_plan)
    values = dict(re.findall(r"^\s+(wc\.\w+\[\d+\]) = (\S+)$", module, flags=re.M))
    for c in range(70):
        for k in range(6):
            idx = c * 8 + k + 1
            assert abs(_value(values[f"wc.ct[{idx}]"]) - t.ct[c, k]) <= 1e-15
            assert abs(_value(values[f"wc.st[{idx}]"]) - t.st[c, k]) <= 1e-15
    for i in range(1, 70):
        assert abs(_value(values[f"wc.dn[{i}]"]) - t.dn[i]) <= 1e-15 * t.dn[i]
        assert abs(_value(values[f"wc.dnf[{i}]"]) - t.dnf[i]) <= 1e-15
    assert _value(values["wc.tp[1]"]) == -60


@pytest.mark.parametrize(
    "x", [0.8660254037844387, -1e-3, 295.0, 547.71234567891, -0.025488, 1e-17, 3.0e8]
)
def test_double_literal(x):
    assert abs(_value(double_literal(x)) - x) <= 2e-16 * abs(x)


def test_log_header_and_columns_as_the_reader_expects(module, paper_plan):
    assert 'CALL wc.write("# wirecal-log 2")' in module
    fp = paper_plan.fingerprint()
    assert f'$wc.fpa = "{fp[:32]}"' in module
    assert f'$wc.fpb = "{fp[32:]}"' in module
    assert 'CALL wc.write("# mm_per_count: 0.025488")' in module
    assert '$cols = "kind,step,index,j1,j2,j3,j4,j5,j6,"' in module
    assert 'CALL wc.write($cols+"counts,samples,spread,t_s,settle_s")' in module
    assert "TIMER wc.tmr = 0" in module
    assert "FOPENW (wc.lun)" in module
    assert module.count("IOSTAT(") >= 6


def test_bad_options_refused(viper, paper_plan):
    with pytest.raises(WirecalError) as info:
        module_text(
            viper,
            paper_plan,
            GenOptions(run=RunParameters(speed_pct=150), log_file="TOOLONGNAME.CSV"),
        )
    assert info.value.problems == [
        "--speed 150: give a percentage in (0, 100]",
        "controller file name 'TOOLONGNAME.CSV': use 8.3 letters and digits",
    ]
    quoted = replace(viper, name='Viper "A"')
    with pytest.raises(WirecalError, match=r"in a V\+ string: printable ASCII without '\"'"):
        module_text(quoted, paper_plan)


def test_cli_gen(tmp_path):
    runner = CliRunner()
    robot, plan = str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")
    r = runner.invoke(main, ["gen", robot, plan, "-o", str(tmp_path / "ctl")])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "ctl" / "WIRECAL.V2").read_bytes() == GOLDEN.read_bytes()
    r = runner.invoke(main, ["gen", robot, plan, "-o", str(tmp_path / "lf"), "--lf"])
    assert r.exit_code == 0, r.output
    lf = (tmp_path / "lf" / "WIRECAL.V2").read_bytes()
    assert b"\r" not in lf
    assert lf.replace(b"\n", b"\r\n") == GOLDEN.read_bytes()
    again = runner.invoke(main, ["gen", robot, plan, "-o", str(tmp_path / "ctl")])
    assert again.exit_code == 2
    assert "exists; choose another name or pass --force" in again.output
    assert "Usage:" in runner.invoke(main, ["gen", "--help"]).output


@pytest.mark.parametrize(
    ("arm", "plan_name", "program", "solver"),
    [
        ("viper_s650", "paper_plan.toml", "WIRECAL.V2", ".PROGRAM wc.solve"),
        ("ur5e", "plan.toml", "wc_run.script", "def wc_solve"),
        ("abb_irb120", "plan.toml", "WIRECAL.mod", "PROC wc_solve"),
    ],
)
def test_gen_leaves_the_stepwise_solver_out_of_a_pool_plan(
    tmp_path, arm, plan_name, program, solver
):
    """A plan written from a pool (``joint_only = true``, as ``plan --pool -o`` writes it)
    isolates no parameter per step: ``gen`` writes the measurement programs without the
    controller's step-by-step solver (V+ has no --no-solver to ask for that), the program's
    comment and the command's note saying why, exit 0; the plan without the mark keeps it."""
    folder = VIPER.parent / arm
    plan = tmp_path / "pool_plan.toml"
    plan.write_text("joint_only = true\n" + (folder / plan_name).read_text(encoding="utf-8"))
    runner = CliRunner()
    r = runner.invoke(
        main, ["gen", str(folder / "robot.toml"), str(plan), "-o", str(tmp_path / "o")]
    )
    assert r.exit_code == 0, r.output
    assert f"note: {plan}: joint_only = true:" in r.output
    assert "step-by-step solver does not apply and is left out" in r.output
    text = (tmp_path / "o" / program).read_text(encoding="ascii")
    assert solver not in text
    assert "not generated: the plan was written from a pool" in text
    name = solver.split()[-1]  # wc.solve, wc_solve: named only where it says why it is absent
    assert [x for x in text.splitlines() if name in x and "not generated" not in x] == []
    r = runner.invoke(
        main,
        ["gen", str(folder / "robot.toml"), str(folder / plan_name), "-o", str(tmp_path / "s")],
    )
    assert r.exit_code == 0, r.output
    assert solver in (tmp_path / "s" / program).read_text(encoding="ascii")
    assert "joint_only" not in r.output
