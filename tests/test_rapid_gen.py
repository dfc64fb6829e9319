"""The RAPID module generator: golden bytes, what the module holds, what it refuses."""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot, robot_from_dict
from wirecal.gen.rapid import GENERATOR
from wirecal.gen.rapid.program import RapidOptions, line_ends, module_text
from wirecal.gen.request import GenRequest
from wirecal.lang.rapid import Rapid
from wirecal.lang.rapid.module import num_literal
from wirecal.solver.errors import WirecalError

ROOT = Path(__file__).resolve().parent.parent
IRB = ROOT / "examples" / "abb_irb120"
GOLDEN = Path(__file__).parent / "golden" / "abb_irb120" / "WIRECAL.mod"


@pytest.fixture(scope="module")
def irb():
    robot = load_robot(IRB / "robot.toml")
    return robot, load_plan(IRB / "plan.toml", robot)


@pytest.fixture(scope="module")
def text(irb):
    return module_text(*irb)


def test_golden_file(text, irb):
    """Byte for byte the reviewed module and deterministic; WIRECAL_UPDATE_GOLDEN=1
    rewrites it after an intended change (review the diff)."""
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        GOLDEN.write_bytes(line_ends(text).encode("ascii"))
    golden = GOLDEN.read_bytes()
    assert golden.count(b"\r\n") == golden.count(b"\n") > 1000  # CRLF, every line
    assert line_ends(text).encode("ascii") == golden
    assert module_text(*irb) == text


def test_module_shape(text, irb):
    """One module; the three routines; every plan target a MoveAbsJ (θ0 once per step
    plus the closing one through wc_theta0); one reading per zero and point."""
    _, plan = irb
    assert text.startswith("MODULE WIRECAL\n")
    assert text.endswith("ENDMODULE\n")
    for proc in ("wc_mount", "wc_check", "wc_run", "wc_meas", "wc_solve"):
        assert len(re.findall(rf"^  PROC {proc}\(", text, re.M)) == 1
    vias = sum(len(s.via_deg) for s in plan.steps)
    assert text.count("MoveAbsJ wc_theta0,") == len(plan.steps) + 2  # + wc_mount
    assert len(re.findall(r"MoveAbsJ \[\[", text)) == plan.n_points + vias
    assert len(re.findall(r"^    wc_meas ", text, re.M)) == plan.n_points + len(plan.steps) + 1
    # the first point of step 1, as the plan has it (deg)
    q = ", ".join(f"{x:g}" for x in plan.steps[0].points_deg[0])
    assert f"MoveAbsJ [[{q}], [9E+09" in text


def test_strings_fit_rapid(text):
    """Every string literal holds at most 80 characters (a RAPID string's length)."""
    pieces = [p for line in text.splitlines() for p in line.split('"')[1::2]]
    assert pieces
    assert max(map(len, pieces)) <= 80


def test_log_header_and_reads(text, irb):
    _robot, plan = irb
    assert f'wc_out "# plan: {plan.fingerprint()}";' in text
    assert 'wc_out "# mm_per_count: 0.025488";' in text
    assert 'Open "HOME:" \\File:="WIRECAL.LOG", wc_log \\Write;' in text
    assert text.count("GInputDnum(wc_gi)") == 4  # check (2), wc_meas (2)
    assert text.count('AliasIO "wc_giCount0", wc_gi;') == 1  # bound at run time (wc_bind)
    assert text.count("    wc_bind;") == 2  # by wc_check and wc_run
    assert "d := d - 4294967296;" in text
    assert "d := d + 4294967296;" in text


def test_no_solver(irb, text):
    bare = module_text(*irb, RapidOptions(solver=False))
    assert "wc_solve" not in bare
    assert "wc_rc{slot}" not in bare
    assert text.count("wc_solve;") == 1
    assert text.index("wc_meas 10, 0, 0;") < text.index("wc_solve;") < text.index('"# end"')


def test_refuses_other_encoder(irb):
    data = tomllib.loads((IRB / "robot.toml").read_text())
    data["encoder"]["counter_bits"] = 24
    robot = robot_from_dict(data, "bits.toml")
    with pytest.raises(WirecalError, match="counter_bits = 32"):
        module_text(robot, irb[1])


def test_every_move_declares_the_tools_load(irb, text):
    """Every MoveAbsJ names wc_tool, a PERS tooldata held by the robot, its TCP the flange,
    its tload the robot file's [gravity] payload_mass_kg at payload_com_mm (0.1 kg at
    [-25, 0, 20] mm, written here by hand): tool0 declares no load (RAPID Reference Manual,
    tooldata), which would tell the controller less than the flange carries."""
    tool = "[TRUE, [[0, 0, 0], [1, 0, 0, 0]], [0.1, [-25, 0, 20], [1, 0, 0, 0], 0, 0, 0]]"
    assert f"  PERS tooldata wc_tool := {tool};\n" in text
    moves = re.findall(r"^\s*MoveAbsJ .*$", text, re.M)
    plan = irb[1]  # the points and vias, θ0 per step, wc_mount's and the closing θ0
    assert (
        len(moves) == plan.n_points + sum(len(s.via_deg) for s in plan.steps) + len(plan.steps) + 2
    )
    assert all(m.endswith(", fine, wc_tool;") for m in moves)
    assert "tool0;" not in text
    assert "pp. 225-227" in text  # the page read


def test_moves_the_wire_limits_slow_get_their_own_speeddata(irb):
    """With a wire that may accelerate at only 10 m/s², some moves get a slower speeddata
    (v_ori below wc_v's); the others keep wc_v; the module stays clean."""
    robot, plan = irb
    tight = replace(robot, encoder=replace(robot.encoder, max_wire_accel_mm_s2=10_000.0))
    text = module_text(tight, plan)
    v_ori = {
        m.group(1): float(m.group(2))
        for m in re.finditer(r"CONST speeddata (wc_v\d*) := \[[^,]+, ([^,]+),", text)
    }
    assert len(v_ori) > 1
    assert all(v < v_ori["wc_v"] for name, v in v_ori.items() if name != "wc_v")
    used = re.findall(r"MoveAbsJ [^;]*, (wc_v\d*), fine", text)
    assert set(used) == set(v_ori)
    assert Rapid().lint(text, "WIRECAL.mod", robot.controller.software) == []
    assert "wc_v1" not in module_text(*irb)  # the shipped encoder: the run's one speed


def test_generator_programs_and_write(irb, tmp_path):
    out = GENERATOR.programs(*irb, GenRequest(solver=False))
    assert list(out) == ["WIRECAL.mod"]
    assert "wc_solve" not in out["WIRECAL.mod"]
    (path,) = GENERATOR.write(tmp_path, out, GenRequest(crlf=False))
    assert path.read_bytes() == out["WIRECAL.mod"].encode("ascii")  # --lf: LF only
    assert "PP to Routine" in GENERATOR.next_steps(*irb, GenRequest(), "r.toml", "p.toml")


@pytest.mark.parametrize(
    ("given", "option"), [({"host": "10.0.0.1"}, "--host"), ({"log_file": "X.LOG"}, "--log-name")]
)
def test_generator_refuses_by_option(irb, given, option):
    with pytest.raises(WirecalError, match=f"{option}: not taken by the ABB RAPID"):
        GENERATOR.programs(*irb, GenRequest(**given))


@pytest.mark.parametrize("x", [1.0, -0.0, 0.1, 6.123233995736766e-17, 302.0])
def test_num_literal_is_the_nearest_float32(x):
    assert np.float32(float(num_literal(x))) == np.float32(x)


def test_patch_companion(irb):
    """Joint zero offsets for the controller (axis, rad, the reading to jog to); the
    rest named as what only a URDF or rewritten targets carry; TOML that reads back."""
    from wirecal.lang.rapid.patch import patch_section

    robot, _ = irb
    text = patch_section(robot, {"th5": -0.02, "a2": 0.3, "th2": 0.1, "d6": 0.1})
    data = tomllib.loads(text)
    joints = data["joint_offsets"]
    assert joints["axis"] == [2, 5]
    assert joints["offset_rad"] == pytest.approx([0.1 * 3.141592653589793 / 180, -0.000349066])
    assert joints["jog_to_deg"] == [-0.1, 0.02]
    assert data["not_carried"]["parameters"] == ["a2", "d6"]
    assert "URDF" in data["not_carried"]["why"]
    assert tomllib.loads(patch_section(robot, {}))["joint_offsets"]["axis"] == []


def test_module_lints_clean(irb, text):
    """The RAPID checker (lang/rapid) finds nothing in the module, with or without the
    solver, for the example's declared RobotWare."""
    from wirecal.lang.rapid import Rapid

    robot, plan = irb
    software = robot.controller.software
    assert Rapid().lint(text, "WIRECAL.mod", software) == []
    bare = module_text(robot, plan, RapidOptions(solver=False))
    assert Rapid().lint(bare, "WIRECAL.mod", software) == []


# ---------- as careful as the V+ module (issue 32) ----------
def test_data_before_routines(text):
    """Every module-level declaration comes before the first routine, as every public
    module does (the module syntax lists data before routines)."""
    lines = text.splitlines()
    first_routine = next(n for n, line in enumerate(lines) if line.startswith("  PROC "))
    data = [n for n, line in enumerate(lines) if re.match(r"  (CONST|VAR|PERS) ", line)]
    assert data
    assert max(data) < first_routine


def test_no_line_over_what_controllers_load(text):
    """200 characters: below the longest lines seen in controller-loaded modules (248, 231)."""
    assert max(len(line) for line in text.splitlines()) <= 200


def test_the_spread_message_states_the_tests_real_size(text):
    """0.1 mm at 0.025488 mm/count is a 3-count test: 3 × 0.025488 = 0.076 mm."""
    assert "IF hi - lo > 3 THEN" in text
    assert "samples spread over 3 counts (0.076 mm)" in text
    assert "0.1 mm: the robot" not in text


def test_start_after_a_refused_reading_samples_again(text):
    """Both Stops of wc_meas (a wide spread, a jumped zero) lie inside the sampling loop,
    and the refused reading is logged as unsettled (not used)."""
    from wirecal.lang.rapid import nodes as N
    from wirecal.lang.rapid.parser import parse_module

    meas = next(r for r in parse_module(text).routines if r.name == "wc_meas")
    loops = [s for s in meas.body if isinstance(s, N.While)]
    assert len(loops) == 1

    def stops(stmts):
        for s in stmts:
            if isinstance(s, N.Call) and s.name == "Stop":
                yield s
            for body in [b for _, b in getattr(s, "branches", [])] + [getattr(s, "orelse", [])]:
                yield from stops(body)

    assert len(list(stops(loops[0].body))) == 2
    assert not list(stops([s for s in meas.body if s is not loops[0]]))
    assert 'head := "unsettled,";' in text


def test_error_handlers_for_the_log_and_the_arithmetic(text):
    """wc_run names a refused log, wc_solve a zero divisor, wc_bind a missing signal."""
    from wirecal.lang.rapid.parser import parse_module

    handlers = {r.name: r.handler for r in parse_module(text).routines}
    assert all(handlers[name] for name in ("wc_run", "wc_solve", "wc_bind"))
    assert "IF ERRNO = ERR_FILEOPEN OR ERRNO = ERR_FILEACC THEN" in text
    assert "IF ERRNO = ERR_DIVZERO THEN" in text
    assert "    Close wc_log;\n    Open " in text  # a log left open by an aborted run
