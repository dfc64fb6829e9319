"""The payload step (issue 30): a known mass at the flange for some of the plan's points.

The torque of the mounted mass, the wire lengths with it (θ0 without it), the robot and
plan files' keys and refusals, the log's ``payload_kg`` marker, the V+ programs' prompts
(golden file), the twin's operator mounting the mass and ``solve`` using it.
"""

from __future__ import annotations

import copy
import functools
import os
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan, plan_from_dict, plan_to_toml
from wirecal.formats.robot_file import load_robot, robot_from_dict
from wirecal.formats.simulated_log import simulate_log
from wirecal.gen.rapid.backend import RapidGenerator
from wirecal.gen.rapid.program import RapidOptions
from wirecal.gen.rapid.program import module_text as rapid_module_text
from wirecal.gen.request import GenRequest
from wirecal.gen.urscript.program import UrOptions, scripts
from wirecal.gen.vplus.program import GenOptions, line_ends, module_text
from wirecal.lang.rapid import Rapid
from wirecal.lang.urscript import URScript
from wirecal.lang.urscript.parser import parse_program
from wirecal.solver.compliance import SIGMA_LIMIT_URAD_PER_NM
from wirecal.solver.distance import wire_lengths
from wirecal.solver.errors import WirecalError
from wirecal.solver.gravity import gravity_torques_nm, with_load
from wirecal.solver.kinematics import loaded, rigid_frames, tool_position
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plan.calibration_plan import PAYLOAD_STEP, Plan
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import sensitivity
from wirecal.solver.solve import solve
from wirecal.twin.rapid.adapter import ADAPTER as RAPID_ADAPTER
from wirecal.twin.urscript.controller import URController
from wirecal.twin.urscript.interp import Interpreter, URError
from wirecal.twin.world import World

from .conftest import VIPER
from .twin_runs import generated, measure_in_twin, measure_ur_in_twin

GOLDEN = Path(__file__).parent / "data" / "payload_viper_s650" / "WIRECAL.V2"
KG, COM = 3.5, (0.0, 0.0, 50.0)  # the Viper payload example: 1.5 kg left for the fixture
TRUE_C = {"c2": 4.0, "c3": 6.0}  # µrad/(N·m): within issue 30's 2–8


def _data(**calibration) -> dict:
    data = copy.deepcopy(tomllib.loads((VIPER / "robot.toml").read_text()))
    data["calibration"].update(calibration)
    return data


HERE = GOLDEN.parent


@functools.cache
def _designed(folder: Path) -> tuple[Robot, Plan]:
    """Return ``folder``'s robot file and the plan ``wirecal plan`` designed for it."""
    robot = load_robot(folder / "robot.toml")
    return robot, load_plan(folder / "plan.toml", robot)


@pytest.fixture(scope="module")
def robot():
    """The Viper asking c2, c3, with a 3.5 kg payload step (of its data sheet's 5 kg)."""
    return _designed(HERE)[0]


@pytest.fixture(scope="module")
def plan():
    """The plan ``wirecal plan`` designed for it: 10 points with the mass on."""
    return _designed(HERE)[1]


# ---- the model ------------------------------------------------------------------------


def test_the_mounted_mass_has_the_torque_of_a_payload_of_that_mass(robot):
    """A load of m kg at c on configuration i gives the torques of the file's own payload
    (``payload_mass_kg`` at ``payload_com_mm``), an independent code path, there only."""
    q = np.radians(np.random.default_rng(1).uniform(-90, 90, (7, 6)))
    f = rigid_frames(robot.nominal, q)
    kg = np.array([0, KG, 0, 2.0, 0, 0, KG])
    masses = robot.nominal.masses
    got = gravity_torques_nm(with_load(masses, kg, np.array(COM)), f.x, f.z, f.o)
    for i, m in enumerate(kg):
        alone = replace(masses, payload_mass_kg=m, payload_com_mm=np.array(COM))
        want = gravity_torques_nm(alone, f.x[i : i + 1], f.z[i : i + 1], f.o[i : i + 1])[0]
        np.testing.assert_allclose(got[i], want, rtol=1e-12, atol=1e-12)
    assert abs(got[1, 1] - got[0, 1]) > 1.0  # 3.5 kg changes joint 2's torque by N·m


def test_wire_lengths_with_the_mass_are_taken_from_theta0_without_it(robot, plan):
    """d_i = |p_loaded(q_i) − p(θ0)|, each point alone, on a compliant arm."""
    model = replace(robot.nominal, compliance=np.array([0, 4e-6, 6e-6, 0, 0, 0]))
    q = np.radians(plan.steps[-1].points_deg[:6])
    q0 = np.radians(plan.theta0_deg)
    kg = np.array([KG, 0, KG, 0, KG, 0])
    got = wire_lengths(loaded(model, kg, COM), q, q0)
    p0 = tool_position(model, q0[None])[0]
    for i in range(len(q)):
        p = tool_position(loaded(model, [kg[i]], COM), q[i : i + 1])[0]
        assert got[i] == pytest.approx(np.linalg.norm(p - p0), abs=1e-9)
    assert np.max(np.abs(got - wire_lengths(model, q, q0))) > 0.01  # the mass bends it


def test_the_compliance_derivative_with_the_mass_matches_finite_differences(robot, plan):
    """Ψ's c2, c3 columns with the mass on: central differences of the wire lengths."""
    q = plan.steps[-1].points_deg
    model = loaded(robot.nominal, np.full(len(q), KG), COM)
    psi = sensitivity(model, q, plan.theta0_deg, ["c2", "c3"]).psi  # mm per µrad/(N·m)
    h = 0.5e-6
    for col, j in enumerate((1, 2)):
        c = np.zeros(6)
        c[j] = h
        up = wire_lengths(replace(model, compliance=c), np.radians(q), np.radians(plan.theta0_deg))
        down = wire_lengths(
            replace(model, compliance=-c), np.radians(q), np.radians(plan.theta0_deg)
        )
        np.testing.assert_allclose(psi[:, col], (up - down) / (2 * h) * 1e-6, rtol=1e-3)


# ---- robot and plan files ---------------------------------------------------------------


@pytest.mark.parametrize(
    ("calibration", "message"),
    [
        ({"compliances": ["c2"], "payload_kg": 5.0}, "needs the arm's rated payload"),
        ({"compliances": ["c2"], "rated_payload_kg": 5, "payload_kg": 6}, "exceeds the rated"),
        ({"rated_payload_kg": 5.0, "payload_kg": 5.0}, "for [calibration] compliances"),
    ],
)
def test_a_payload_the_robot_file_cannot_take_is_refused(calibration, message):
    with pytest.raises(WirecalError) as e:
        robot_from_dict(_data(**calibration), "payload.toml")
    assert any("calibration.payload_kg" in p and message in p for p in e.value.problems)


def test_the_plan_file_keeps_the_step_and_its_mass_in_the_fingerprint(robot, plan):
    step = plan.payload_step
    assert step is not None
    assert (step.payload_kg, step.payload_com_mm) == (KG, COM)
    assert PAYLOAD_STEP not in plan.order  # no parameter of its own
    heavier = replace(plan, steps=(*plan.steps[:-1], replace(step, payload_kg=4.0)))
    bare = replace(plan, steps=plan.steps[:-1])
    assert len({plan.fingerprint(), heavier.fingerprint(), bare.fingerprint()}) == 3
    again = plan_from_dict(tomllib.loads(plan_to_toml(plan)), robot)
    assert again.fingerprint() == plan.fingerprint()


def _plan_problems(robot, text: str) -> list[str]:
    with pytest.raises(WirecalError) as e:
        plan_from_dict(tomllib.loads(text), robot, "p.toml")
    return e.value.problems


def test_a_payload_step_the_robot_cannot_take_is_refused(robot, plan, viper):
    text = plan_to_toml(plan)
    assert any(
        "only the payload step" in p
        for p in _plan_problems(
            robot, text.replace('parameter = "d6"\n', 'parameter = "d6"\npayload_kg = 1\n', 1)
        )
    )
    heavy = text.replace("payload_kg = 3.5\n", "payload_kg = 6\n")
    assert any("exceeds the arm's rated payload 5 kg" in p for p in _plan_problems(robot, heavy))
    unrated = replace(robot, rated_payload_kg=None)
    assert any("states no rated payload" in p for p in _plan_problems(unrated, text))
    assert any("is for compliances" in p for p in _plan_problems(viper, text))
    no_mass = text.replace("payload_kg = 3.5\n", "")
    assert any("needs its mass" in p for p in _plan_problems(robot, no_mass))


# ---- the log's marker, simulate, solve ----------------------------------------------------


@pytest.fixture(scope="module")
def log_text(robot, plan):
    return simulate_log(robot, plan, TRUE_C, seed=3, counter_start=1000.0)


def test_the_log_says_the_mass_and_the_reader_checks_it(robot, plan, log_text):
    assert "# payload_kg: 3.5\n" in log_text
    assert check_log(parse_log(log_text, "run.csv"), plan, robot).complete
    cases = {
        log_text.replace("# payload_kg: 3.5\n", ""): "has no '# payload_kg' line",
        log_text.replace("# payload_kg: 3.5\n", "# payload_kg: 4\n"): "is not the plan's",
    }
    for text, message in cases.items():
        with pytest.raises(WirecalError) as e:
            check_log(parse_log(text, "run.csv"), plan, robot, accept_foreign=True)
        assert any(message in p for p in e.value.problems)
    bare = replace(plan, steps=plan.steps[:-1])
    with pytest.raises(WirecalError) as e:
        check_log(parse_log(log_text, "run.csv"), bare, robot, accept_foreign=True)
    assert any("has no payload step" in p for p in e.value.problems)
    with pytest.raises(WirecalError) as e:
        parse_log(log_text.replace("# payload_kg: 3.5\n", "# payload_kg: heavy\n"), "run.csv")
    assert any("run.csv:5: payload_kg 'heavy'" in p for p in e.value.problems)


def test_solve_uses_each_points_mass(robot, plan, log_text):
    """c2, c3 come back within 3σ of the truth, σ below the identification limit (2.31
    µrad/(N·m); 3.5 kg gives 1.9 and 2.0 here, the former 5 kg 1.0 and 1.4)."""
    m = check_log(parse_log(log_text, "run.csv"), plan, robot)
    est = solve(robot, plan, m).estimates["joint"]
    got, std = est.as_dict(), est.std_by_name()
    for name, truth in TRUE_C.items():
        assert abs(got[name] - truth) < 3 * std[name]
        assert std[name] < SIGMA_LIMIT_URAD_PER_NM


# ---- the V+ programs and the twin ---------------------------------------------------------


@pytest.fixture(scope="module")
def payload_module(robot, plan) -> str:
    return generated(module_text, robot, plan, GenOptions())


def test_payload_golden_file(payload_module):
    """The V+ module of the payload plan is the reviewed one (WIRECAL_UPDATE_GOLDEN=1
    rewrites it after an intended change: review the diff)."""
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        GOLDEN.parent.mkdir(exist_ok=True)
        GOLDEN.write_bytes(line_ends(payload_module).encode("ascii"))
    assert line_ends(payload_module).encode("ascii") == GOLDEN.read_bytes()


def test_the_v_plus_run_prompts_at_theta0_around_the_payload_step(payload_module, plan):
    run = payload_module[payload_module.index(".PROGRAM wc.run()") :]
    n = len(plan.steps)
    zero = run.index(f"CALL wc.meas({n}, 0)")
    mount = run.index('PROMPT "# Type 1 when it is mounted')
    first = run.index(f"CALL wc.meas({n}, 1)")
    remove = run.index('PROMPT "# Type 1 when it is removed')
    closing = run.index(f"CALL wc.meas({n + 1}, 0)")
    assert zero < mount < first < remove < closing
    assert 'CALL wc.write("# payload_kg: 3.5")' in payload_module
    assert "(V+ Language Reference Guide v17.x, PAYLOAD program" in payload_module  # why not
    assert "FOR s = 1 TO wc.m\n" in payload_module  # the controller solver: parameters' steps


def test_the_v_plus_comment_says_what_the_payload_check_covered(payload_module):
    """The comment names the check made (the step's mass with the robot file's declared
    tool against the rating), with its numbers: the plan's 3.5 kg at [0, 0, 50] mm, the
    file's tool (none: 0 kg) and rating (5 kg), what that leaves for the tool mounted
    (5 − 3.5 kg); not a claim that everything on the flange is within the rating."""
    comment = " ".join(
        line.lstrip("; ") for line in payload_module.splitlines() if line.startswith(";")
    )
    assert "within its rated payload" not in comment
    assert (
        "wirecal checked only the step's mass, 3.5 kg at [0, 0, 50] mm in the flange frame, "
        "with the tool the robot file declares, 0 kg ([gravity] payload_mass_kg), against its "
        "[calibration] rated_payload_kg, 5 kg; not what is on the flange: the tool and "
        "fixture mounted must weigh no more than 1.5 kg."
    ) in comment


@pytest.mark.slow
def test_the_twin_operator_mounts_the_mass_and_solve_finds_the_compliances(
    robot, plan, payload_module, tmp_path
):
    run = measure_in_twin(robot, plan, TRUE_C, tmp_path, text=payload_module, seed=2)
    assert run.complete
    assert run.world.mounted_kg == 0.0  # removed before the closing zero
    console = "\n".join(run.world.console)
    assert console.index("when it is mounted") < console.index("when it is removed")
    _solves_the_compliances(robot, plan, run.log, KG)


def _solves_the_compliances(
    robot: Robot, plan: Plan, log_path: Path, kg: float, std_max: float = np.inf
) -> None:
    """The log says the mass; ``solve`` of it finds each true compliance within 4σ (and σ
    below ``std_max``, µrad/(N·m))."""
    log = parse_log(log_path.read_text(), str(log_path))
    assert log.payload_kg == kg
    est = solve(robot, plan, check_log(log, plan, robot)).estimates["joint"]
    got, std = est.as_dict(), est.std_by_name()
    for name, truth in TRUE_C.items():
        assert abs(got[name] - truth) < 4 * std[name]
        assert std[name] < std_max


UR = GOLDEN.parents[1] / "payload_ur5e"
UR_KG = 3.5  # the step's mass: 1.5 kg of the UR5e's rated 5 kg left for the tool


@pytest.fixture(scope="module")
def ur_robot():
    """The UR5e asking c2, c3, with a 3.5 kg payload step (of its rated 5 kg)."""
    return _designed(UR)[0]


@pytest.fixture(scope="module")
def ur_plan():
    """The plan ``wirecal plan`` designed for it at the shipped plan's θ0: 9 points with it."""
    return _designed(UR)[1]


@pytest.fixture(scope="module")
def ur_run_script(ur_robot, ur_plan) -> str:
    return generated(scripts, ur_robot, ur_plan, UrOptions())["wc_run.script"]


def test_payload_golden_script(ur_run_script):
    """The URScript wc_run of the payload plan is the reviewed one (WIRECAL_UPDATE_GOLDEN=1
    rewrites it after an intended change: review the diff)."""
    path = UR / "wc_run.script"
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        path.write_text(ur_run_script, encoding="ascii", newline="\n")
    assert ur_run_script == path.read_text(encoding="ascii")


def test_the_urscript_run_asks_by_popup_and_tells_the_controller(ur_run_script, ur_plan):
    """Zero, popup to mount, the active payload read and declared with the mass at their
    common centre, the points; back at θ0 the popup to remove, the payload read restored,
    the closing zero; no wc_solve."""
    n = len(ur_plan.steps)
    order = [
        f"z = wc_meas({n}, 0,",
        'popup("Payload step: mount the 3.5 kg mass',
        "wc_m0 = get_target_payload()",
        "wc_c0 = get_target_payload_cog()",
        "wc_mt = wc_m0 + 3.5",
        "set_payload(wc_mt, [(wc_m0 * wc_c0[0] + 0) / wc_mt, (wc_m0 * wc_c0[1] + 0) / wc_mt, "
        "(wc_m0 * wc_c0[2] + 0.175) / wc_mt])",
        f"wc_meas({n}, 1,",
        'popup("Remove the 3.5 kg mass',
        "set_payload(wc_m0, wc_c0)",
        f"wc_meas({n + 1}, 0,",
    ]
    at = [ur_run_script.index(x) for x in order]
    assert at == sorted(at)
    assert 'wc_send("# payload_kg: 3.5")' in ur_run_script
    assert "wc_solve(" not in ur_run_script


@pytest.mark.slow
def test_the_ur_twin_operator_mounts_the_mass_and_solve_finds_the_compliances(
    ur_robot, ur_plan, tmp_path
):
    run = measure_ur_in_twin(ur_robot, ur_plan, TRUE_C, tmp_path, seed=2)
    assert run.programs.complete
    assert run.programs.world.mounted_kg == 0.0
    assert run.programs.controller.payload[0] == 0.0  # the tool's alone again
    _solves_the_compliances(ur_robot, ur_plan, run.log, UR_KG, std_max=1.0)


def _with_tool(robot: Robot, kg: float, com_mm: tuple[float, float, float]) -> Robot:
    """Return ``robot`` with a tool of ``kg`` at ``com_mm`` ([gravity] payload_mass_kg)."""
    assert robot.masses is not None
    masses = replace(robot.masses, payload_mass_kg=kg, payload_com_mm=np.array(com_mm))
    return replace(robot, masses=masses)


def test_the_ur_twin_runs_a_payload_step_the_robot_file_gives_no_tool(ur_robot, ur_plan, tmp_path):
    """The shipped example with a real tool: the robot file gives no tool mass; the flange
    carries a 1.5 kg tool at 20 mm, the Installation's payload, and the step its 3.5 kg
    mass (5 kg in all: the UR5e's rating). The e-Series wc_run reads the tool and declares
    5 kg for the step, so the twin (which stops a move declaring less than the flange
    carries) runs it to the end, and the Installation's 1.5 kg at [0, 0, 0.02] m is
    restored exactly. The former example's 5 kg step refused any tool before moving."""
    true_arm = _with_tool(ur_robot, 1.5, (0.0, 0.0, 20.0))
    run = measure_ur_in_twin(true_arm, ur_plan, TRUE_C, tmp_path, seed=2)
    assert run.programs.complete, run.programs.stopped
    assert run.programs.world.mounted_kg == 0.0
    m, cog = run.programs.controller.payload
    assert m == 1.5
    assert cog == pytest.approx([0.0, 0.0, 0.02], abs=1e-7)  # a 32-bit float


def test_the_ur_run_refuses_a_tool_and_mass_beyond_the_rating_before_moving(
    ur_robot, ur_plan, tmp_path
):
    """The shipped step's 3.5 kg with the Installation's 1.6 kg tool: 5.1 kg would be
    carried, over the UR5e's rated 5 kg. wc_run checks before its first move and stops
    with an error popup naming the rating; the arm never moved (the receiver waits 2 s for
    a token in vain). The run's reason is the program's own popup, not the receiver's."""
    true_arm = _with_tool(ur_robot, 1.6, (0.0, 0.0, 20.0))
    run = measure_ur_in_twin(true_arm, ur_plan, TRUE_C, tmp_path, seed=2, timeout_s=2.0)
    assert not run.programs.complete
    assert "exceeds the rated 5 kg" in run.programs.world.console[-1]
    assert run.programs.world.mounted_kg == 0.0
    assert run.programs.world.moves == 0
    why = run.programs.stopped
    assert why.startswith("wc_run stopped at line 159: The Installation's payload plus the 3.5 kg")
    assert why.endswith(f"(wirecal receive: {run.received.stopped})")


def test_the_declared_load_is_the_installations_with_an_off_axis_mass(ur_robot, ur_plan, tmp_path):
    """wc_run's payload lines run in the twin with the Installation's 1 kg at [0, 0, 20] mm
    and a 2.345 kg mass at [0, -12.5, 47.3] mm: the controller is told 3.345 kg at
    (1·c_tool + 2.345·c_mass)/3.345, then exactly the Installation's again (32-bit floats:
    1e-6)."""
    step = replace(ur_plan.steps[-1], payload_kg=2.345, payload_com_mm=(0.0, -12.5, 47.3))
    plan = replace(ur_plan, steps=(*ur_plan.steps[:-1], step))
    run = generated(scripts, ur_robot, plan, UrOptions())["wc_run.script"].splitlines()
    first = run.index("  wc_m0 = get_target_payload()")
    declare = run[first : first + 4]
    arm = _with_tool(ur_robot, 1.0, (0.0, 0.0, 20.0))

    def told(*body: str) -> tuple[float, list]:
        cell = URController(World(arm, {}, np.asarray(plan.theta0_deg), tmp_path, noise_mm=0))
        text = "def t():\n" + "\n".join(body) + "\nend\n"
        Interpreter(parse_program(text, "t.script"), cell).execute()
        return cell.payload

    m, cog = told(*declare)
    assert m == pytest.approx(3.345, abs=1e-6)
    expected_m = (1.0 * np.array([0, 0, 0.02]) + 2.345 * np.array([0, -0.0125, 0.0473])) / 3.345
    assert cog == pytest.approx(expected_m.tolist(), abs=1e-6)
    m, cog = told(*declare, "  set_payload(wc_m0, wc_c0)")
    assert (m, cog) == (1.0, pytest.approx([0.0, 0.0, 0.02], abs=1e-7))


def test_the_ur_twin_stops_a_move_declaring_less_than_the_flange_carries(
    ur_robot, ur_plan, tmp_path
):
    """The twin's Installation payload is the true arm's tool (1 kg at 20 mm), read back by
    get_target_payload(_cog); after set_payload(0.5, …) a movej stops, naming both masses."""
    arm = _with_tool(ur_robot, 1.0, (0.0, 0.0, 20.0))
    cell = URController(World(arm, {}, np.asarray(ur_plan.theta0_deg), tmp_path, noise_mm=0.0))
    assert cell.get_target_payload() == 1.0
    assert cell.get_target_payload_cog() == pytest.approx([0.0, 0.0, 0.02], abs=1e-7)
    here = [float(np.radians(x)) for x in ur_plan.theta0_deg]
    cell.movej(here)  # the Installation's payload declares the tool: the move runs
    cell.set_payload(0.5, [0.0, 0.0, 0.0])
    with pytest.raises(URError, match=r"1 kg at the flange and 0\.5 kg declared"):
        cell.movej(here)


def test_a_cb3_payload_step_declares_the_robot_files_tool_with_the_mass(ur_robot, ur_plan):
    """CB3 (3.15): a 1 kg tool at 20 mm with the 3.5 kg mass at 50 mm: set_payload(4.5 kg
    at (1·20 + 3.5·50)/4.5 = 43.333 mm), then the tool's alone; no call read on e-Series
    pages only, and the checker refuses get_target_payload for 3.15, by name."""
    cb3 = _with_tool(ur_robot, 1.0, (0.0, 0.0, 20.0))
    cb3 = replace(cb3, controller=replace(cb3.controller, software="3.15"))
    run = generated(scripts, cb3, ur_plan, UrOptions())["wc_run.script"]
    declared = ("set_payload(4.5, [0, 0, 0.043333])", "set_payload(1, [0, 0, 0.02])")
    at = [run.index(x) for x in declared]
    assert at == sorted(at)
    assert "get_target_payload" not in run
    problems = URScript().lint("def t():\n  m = get_target_payload()\nend\n", "t.script", "3.15")
    assert any("get_target_payload() is documented from software 5.20" in p for p in problems)


IRB = GOLDEN.parents[1] / "payload_abb_irb120"


@pytest.fixture(scope="module")
def irb_robot():
    """The IRB 120 asking c2, c3, with a 2.9 kg payload step (with its 0.1 kg tool, within
    its rated payload)."""
    return _designed(IRB)[0]


@pytest.fixture(scope="module")
def irb_plan():
    """The plan ``wirecal plan`` designed for it: 10 points with the mass on."""
    return _designed(IRB)[1]


@pytest.fixture(scope="module")
def rapid_module(irb_robot, irb_plan) -> str:
    return generated(rapid_module_text, irb_robot, irb_plan, RapidOptions())


def test_payload_golden_rapid_module(rapid_module):
    """The RAPID module of the payload plan is the reviewed one (WIRECAL_UPDATE_GOLDEN=1
    rewrites it after an intended change: review the diff)."""
    path = IRB / "WIRECAL.mod"
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        path.write_text(rapid_module, encoding="ascii", newline="\n")
    assert rapid_module == path.read_text(encoding="ascii")


def test_the_rapid_run_asks_and_tells_gripload_at_theta0(rapid_module, irb_plan):
    """Zero, TPReadNum to mount, GripLoad of the mass, the points; back at θ0 TPReadNum to
    remove, GripLoad load0, the closing zero; the log's marker; no wc_solve."""
    run = rapid_module[rapid_module.index("PROC wc_run()") :]
    n = len(irb_plan.steps)
    order = [
        f"wc_meas {n}, 0, 0;",
        'TPReadNum answer, "1 when it is mounted',
        "GripLoad wc_load;",
        f"wc_meas {n}, 1, 0;",
        "MoveAbsJ wc_theta0, ",
        'TPReadNum answer, "1 when it is removed',
        "GripLoad load0;",
        f"wc_meas {n + 1}, 0, 0;",
    ]
    at, pos = [], 0
    for x in order:  # each after the one before
        pos = run.index(x, pos)
        at.append(pos)
    assert at == sorted(at)
    assert "PERS loaddata wc_load := [2.9, [0, 0, 50], [1, 0, 0, 0], 0, 0, 0];" in rapid_module
    assert 'wc_out "# payload_kg: 2.9";' in run
    assert "PROC wc_solve" not in rapid_module
    assert "yumpu.com/en/document/view/5679047, p. 183" in rapid_module  # the page read


def test_an_off_axis_fractional_mass_passes_the_checker(irb_robot, irb_plan):
    """The loaddata of another mass and centre: written as the plan says, the checker clean,
    the FlexPendant's lines within a RAPID string's 80 characters for the longest numbers."""
    com = (-123.4567, 98.7654, -321.0987)
    step = replace(irb_plan.steps[-1], payload_kg=0.123456, payload_com_mm=com)
    plan = replace(irb_plan, steps=(*irb_plan.steps[:-1], step))
    text = rapid_module_text(irb_robot, plan)
    load = "[0.123456, [-123.4567, 98.7654, -321.0987], [1, 0, 0, 0], 0, 0, 0]"
    assert f"wc_load := {load};" in text
    assert '"# its centre at [-123.4567, 98.7654, -321.0987] mm in the flange frame;"' in text
    lines = [x for x in text.splitlines() if x.lstrip().startswith('TPWrite "')]
    assert max(len(x.split('"')[1]) for x in lines) <= 80
    assert Rapid().lint(text, "WIRECAL.mod", irb_robot.controller.software) == []
    far = replace(step, payload_kg=1e-05, payload_com_mm=(-9999.9999, 1e-05, 9999.9999))
    text = rapid_module_text(irb_robot, replace(plan, steps=(*plan.steps[:-1], far)))
    assert "wc_load := [0.00001, [-9999.9999, 0, 9999.9999], [1, 0, 0, 0], 0, 0, 0];" in text
    assert Rapid().lint(text, "WIRECAL.mod", irb_robot.controller.software) == []


def test_gripload_declares_the_mass_and_wc_tool_the_tool(irb_robot, irb_plan):
    """A tool of 1 kg at 20 mm ([gravity] payload_mass_kg) with a 2 kg mass at 50 mm: every
    move's wc_tool declares the tool's 1 kg (its tload), GripLoad the 2 kg mass alone, 3 kg
    in all — never less than the flange carries (the RAPID Reference Manual's tooldata page:
    tload the tool's own load, the payload connected with GripLoad); load0 after."""
    masses = replace(irb_robot.masses, payload_mass_kg=1.0, payload_com_mm=np.array([0, 0, 20.0]))
    step = replace(irb_plan.steps[-1], payload_kg=2.0, payload_com_mm=(0.0, 0.0, 50.0))
    plan = replace(irb_plan, steps=(*irb_plan.steps[:-1], step))
    text = rapid_module_text(replace(irb_robot, masses=masses), plan)
    assert "wc_load := [2, [0, 0, 50], [1, 0, 0, 0], 0, 0, 0];" in text
    assert (
        "wc_tool := [TRUE, [[0, 0, 0], [1, 0, 0, 0]], [1, [0, 0, 20], [1, 0, 0, 0], 0, 0, 0]];"
        in text
    )
    assert "GripLoad load0;" in text


def test_the_checker_refuses_a_gripload_of_another_type():
    """Right both ways: GripLoad takes a loaddata, not a number or a tooldata."""
    for arg in ("3", "tool0"):
        text = "MODULE T\n  PROC main()\n    GripLoad " + arg + ";\n  ENDPROC\nENDMODULE\n"
        problems = Rapid().lint(text, "t.mod")
        assert any("GripLoad" in p and "loaddata" in p for p in problems), problems


def test_gen_writes_the_rapid_payload_module(tmp_path):
    """`wirecal gen` on the IRB 120's payload plan: exit 0, the module with GripLoad."""
    args = ["gen", str(IRB / "robot.toml"), str(IRB / "plan.toml"), "-o", str(tmp_path)]
    out = CliRunner().invoke(main, args)
    assert out.exit_code == 0, out.output
    text = (tmp_path / "WIRECAL.mod").read_bytes().decode("ascii")
    assert "GripLoad wc_load;\r\n" in text
    assert "GripLoad load0;\r\n" in text


def _without_tool(folder: Path, cb3: bool, mass: float | None) -> str:
    """Return ``folder``'s robot file with the tool's mass left out (None) or ``mass``;
    ``cb3``: the UR5e's declared as a CB3 (3.15) with room for a tool in its rating."""
    text = (folder / "robot.toml").read_text(encoding="utf-8")
    text = text.replace("payload_mass_kg = 0.1\n", "")  # the IRB 120's
    if cb3:
        text = text.replace('software = "5.20"', 'software = "3.15"')
        text = text.replace("rated_payload_kg = 5.0", "rated_payload_kg = 6.0")
    if mass is not None:
        text = text.replace("[gravity]\n", f"[gravity]\npayload_mass_kg = {mass}\n", 1)
    return text


@pytest.mark.parametrize("mass", [None, 0.0, 1e-7])
@pytest.mark.parametrize(
    ("folder", "cb3", "declares"),
    [
        ("payload_abb_irb120", False, "the RAPID module declares the load at the flange"),
        ("payload_ur5e", True, "a CB3 program's payload step declares it"),
    ],
)
def test_a_robot_file_without_the_tools_mass_is_refused(tmp_path, folder, cb3, declares, mass):
    """No [gravity] payload_mass_kg (or 0, or a mass written as 0): the flange carries at
    least the wire's fixture, so the program would declare too little: the RAPID module in
    every move, a CB3 payload step (CB3 pages document no way to read the Installation's
    payload; the e-Series programs read it and need none). `wirecal gen` refuses, naming
    the key, exit 2, nothing written."""
    robot = tmp_path / "robot.toml"
    robot.write_text(_without_tool(GOLDEN.parents[1] / folder, cb3, mass), encoding="utf-8")
    plan = GOLDEN.parents[1] / folder / "plan.toml"
    out = CliRunner().invoke(main, ["gen", str(robot), str(plan), "-o", str(tmp_path / "o")])
    assert out.exit_code == 2, out.output
    assert f"[gravity] payload_mass_kg: no tool mass; {declares}" in out.output
    assert "Traceback" not in out.output
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())


def test_the_rapid_twin_stops_a_move_with_the_mass_undeclared(
    irb_robot, irb_plan, rapid_module, tmp_path
):
    """A module that forgets GripLoad: the twin's IRC5 stops at the first move with the
    mass on, by name (the rest of the run is not made)."""
    forgot = rapid_module.replace("    GripLoad wc_load;\n", "", 1)
    run = RAPID_ADAPTER.measure(irb_robot, irb_plan, {}, tmp_path, {"WIRECAL.mod": forgot})
    assert not run.complete
    assert "3 kg at the flange and 0.1 kg declared (the tool's tload 0.1 kg, GripLoad 0 kg)" in (
        run.stopped
    )
    assert run.world.mounted_kg == 2.9


def test_the_rapid_twin_stops_a_move_without_the_tools_load(
    irb_robot, irb_plan, rapid_module, tmp_path
):
    """A module whose moves name tool0 (no tool load) while the flange carries the robot
    file's 0.1 kg tool: the twin's IRC5 stops its first move (wc_mount's), by name."""
    bare = rapid_module.replace(", fine, wc_tool;", ", fine, tool0;")
    run = RAPID_ADAPTER.measure(irb_robot, irb_plan, {}, tmp_path, {"WIRECAL.mod": bare})
    assert not run.complete
    assert "0.1 kg at the flange and 0 kg declared (the tool's tload 0 kg" in run.stopped
    assert not run.log.exists() or "# end" not in run.log.read_text()


def test_a_language_that_does_not_prompt_refuses_a_payload_plan(irb_robot, irb_plan):
    """The generators' base refuses a payload plan for a language whose programs would not
    ask for the mass (every shipped language asks; a new one must say so)."""

    class Silent(RapidGenerator):
        payload_step = False

    with pytest.raises(WirecalError, match="do not prompt for it: plan without"):
        Silent().programs(irb_robot, irb_plan, GenRequest())


@pytest.mark.slow
def test_the_rapid_twin_operator_mounts_the_mass_and_solve_finds_the_compliances(
    irb_robot, irb_plan, rapid_module, tmp_path
):
    run = RAPID_ADAPTER.measure(
        irb_robot, irb_plan, TRUE_C, tmp_path, {"WIRECAL.mod": rapid_module}, seed=2
    )
    assert run.complete, run.stopped
    assert run.world.mounted_kg == 0.0  # removed before the closing zero
    assert run.controller.load == (0.0, (0.0, 0.0, 0.0))  # load0 again
    pendant = "\n".join(run.controller.flexpendant)
    assert pendant.index("when it is mounted") < pendant.index("when it is removed")
    pasted = parse_log(pendant, "pasted")  # the FlexPendant's lines, the prompts among them
    assert pasted.payload_kg == 2.9
    assert len(pasted.readings) == len(parse_log(run.log.read_text(), "file").readings)
    _solves_the_compliances(irb_robot, irb_plan, run.log, 2.9, std_max=3.0)


@settings(max_examples=60, deadline=None)
@given(
    kg=st.floats(min_value=0.01, max_value=5.0, allow_nan=False),
    com=st.tuples(*[st.floats(min_value=-500.0, max_value=500.0, allow_nan=False)] * 3),
)
def test_the_payload_step_reads_back_as_written(kg, com):
    """Any mass within the rating and centre within range: the file reads back the same
    step and fingerprint; the mass is in the fingerprint. A centre whose every value is
    under 1 mm (not all zero) is refused as metres (AU11), not read back."""
    assume(not 0 < max(abs(c) for c in com) < 1)
    robot, plan = _designed(HERE)
    step = replace(plan.steps[-1], payload_kg=kg, payload_com_mm=com)
    mine = replace(plan, steps=(*plan.steps[:-1], step))
    back = plan_from_dict(tomllib.loads(plan_to_toml(mine)), robot)
    assert back.payload_step is not None
    assert (back.payload_step.payload_kg, back.payload_step.payload_com_mm) == (kg, com)
    assert back.fingerprint() == mine.fingerprint()
    assert (back.fingerprint() == plan.fingerprint()) == (
        round(kg, 6) == KG
        and all(round(c, 6) == round(p, 6) for c, p in zip(com, COM, strict=True))
    )
