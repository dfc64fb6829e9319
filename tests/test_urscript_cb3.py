"""CB3 (software 3.x) URScript programs: only calls the 3.x pages document, the filtered count
unwrapped between readings that never move the wire half its range apart, a version 1 log,
and a twin that refuses what the declared software lacks."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pytest

from wirecal.formats.log import load_measurements
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors
from wirecal.gen.urscript.program import scripts
from wirecal.lang.registry import language
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.solve import solve
from wirecal.twin.urscript.controller import URController
from wirecal.twin.urscript.runs import run_ur_programs
from wirecal.twin.world import World

from .twin_runs import measure_ur_in_twin

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
HALF_RANGE_COUNTS = 2**15  # the filtered count wraps at 2^16 (SW5.20 page)


@pytest.fixture(scope="module")
def ur5():
    return load_robot(EXAMPLES / "ur5" / "robot.toml")


@pytest.fixture(scope="module")
def plan(ur5):
    return load_plan(EXAMPLES / "ur5" / "plan.toml", ur5)


@pytest.fixture(scope="module")
def texts(ur5, plan):
    return scripts(ur5, plan)


def test_the_example_is_a_cb3_ur5_with_ur_published_dh(ur5):
    assert ur5.controller.software == "3.15"
    # UR's DH page for the UR5: d1 89.159, a2 -425, a3 -392.25, d4 109.15, d5 94.65, d6 82.3 mm
    dh = np.asarray(ur5.nominal.dh)
    assert dh[0, 3] == pytest.approx(89.159)
    assert dh[2, 1] == pytest.approx(-425.0)
    assert dh[3, 1] == pytest.approx(-392.25)
    assert dh[3, 3] == pytest.approx(109.15)
    assert dh[4, 3] == pytest.approx(94.65)
    assert dh[5, 3] == pytest.approx(82.3)


def test_cb3_programs_use_only_calls_the_3x_pages_document(texts):
    lint = language("urscript").lint
    for name, text in texts.items():
        code = "\n".join(line.split("#")[0] for line in text.splitlines())
        assert "time(" not in code, name
        assert "opt=" not in code, name
        assert lint(text, name, "3.15") == [], name
        assert lint(text, name, "3.8") == [], name
        refused = lint(text, name, "3.7")  # before UR's conveyor guide's 3.8
        if "encoder_" in code:
            assert refused, name
            assert all("3.8 (CB3)" in p for p in refused), refused
    run = texts["wc_run.script"]
    assert '"# wirecal-log 1"' in run  # no clock: readings without time
    assert 'kind,step,index,j1,j2,j3,j4,j5,j6,counts,samples,spread"' in run


def _movej_targets_rad(text: str) -> list[np.ndarray]:
    """The joint targets of wc_run's movej calls, in program order."""
    found = re.findall(r"^  movej\((\[[^\]]*\])", text, flags=re.M)
    return [np.asarray(ast.literal_eval(t), float) for t in found]


def test_no_two_readings_are_half_the_filtered_range_apart(ur5, plan, texts):
    """Every movej of wc_run is followed by a reading (a leg's wc_read, or wc_meas); the
    nominal wire between two consecutive targets changes by a quarter of the range at
    most: far inside the half that the unwrapping tolerates (model errors of mm)."""
    q = np.array(_movej_targets_rad(texts["wc_run.script"]))
    assert len(q) > plan.n_points  # the legs are extra targets on the moves
    p0 = tool_position(ur5.nominal, np.radians(plan.theta0_deg)[None])[0]
    wire_mm = np.linalg.norm(tool_position(ur5.nominal, q) - p0, axis=1)  # a point exit
    steps_counts = np.abs(np.diff(np.r_[0.0, wire_mm])) / abs(ur5.encoder.mm_per_count)
    assert steps_counts.max() <= HALF_RANGE_COUNTS / 2 + 1
    assert wire_mm.max() / abs(ur5.encoder.mm_per_count) > HALF_RANGE_COUNTS  # legs needed


@pytest.mark.slow
def test_cb3_run_in_the_twin_identifies_the_truth(ur5, plan, texts, tmp_path):
    truth = random_errors(ur5, 1.0, np.random.default_rng([7, 1]))
    r = measure_ur_in_twin(ur5, plan, truth, tmp_path, texts=texts, seed=7)
    assert r.programs.run.status == "completed", r.programs.run.message
    assert r.received.complete
    assert r.log.read_text().startswith("# wirecal-log 1\n# robot: Universal Robots UR5 (CB3)\n")
    m = load_measurements(r.log, plan, ur5)
    assert m.complete
    est = solve(ur5, plan, m).estimates["joint"].as_dict()
    assert max(abs(v - truth.get(k, 0.0)) for k, v in est.items()) < 0.05  # deg, mm


def test_the_twin_refuses_a_call_the_declared_software_lacks(ur5, plan, tmp_path):
    e_series = scripts(
        load_robot(EXAMPLES / "ur5e" / "robot.toml"),
        load_plan(EXAMPLES / "ur5e" / "plan.toml", load_robot(EXAMPLES / "ur5e" / "robot.toml")),
    )
    world = World(ur5, {}, plan.theta0_deg, tmp_path)
    ctl = URController(world, software="3.15")
    with pytest.raises(WirecalError) as info:
        run_ur_programs(ctl, e_series["wc_mount.script"], e_series["wc_run.script"])
    text = str(info.value)
    assert "time() returning struct(sec, nanosec) is documented from software 5.19" in text
    assert "not confirmed on 3.15" in text
    assert world.moves == 0  # refused before anything ran
