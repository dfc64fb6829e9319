"""wc_solve, the URScript controller solver at the end of wc_run, run in the twin.

The generated text is executed by the URScript interpreter with the controller's 32-bit
ints and floats; the expectations come from the Python reference solver (double
precision) on the same log, never from the code under test.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.app.compare import controller_runs
from wirecal.cli.main import main
from wirecal.formats.controller_result import parse_result, result_in_log
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.gen.urscript.program import OPS_PER_SYNC, UrOptions, float_literal, scripts
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve
from wirecal.twin.urscript.solver_run import READING_INTS, ur_readings

ROOT = Path(__file__).resolve().parent.parent
UR5 = ROOT / "examples" / "ur5e"
GOLDEN = Path(__file__).parent / "golden" / "ur5e" / "wc_run.script"
AGREEMENT = 1e-5  # deg/mm: the pinned bound (measured: 2e-6 over 12 truths)


@pytest.fixture(scope="module")
def ur5():
    robot = load_robot(UR5 / "robot.toml")
    return robot, load_plan(UR5 / "plan.toml", robot)


@pytest.fixture(scope="module")
def run_text(ur5):
    return scripts(*ur5)["wc_run.script"]


def _solver_part(text: str) -> str:
    start = text.index("  def wc_solve(rd):")
    return text[start : text.index("\n  end\n", start) + 7]


def test_golden_solver_part(ur5, run_text):
    """The solver part of the golden wc_run.script, byte for byte, and deterministic."""
    golden = GOLDEN.read_text(encoding="ascii")
    assert _solver_part(run_text) == _solver_part(golden)
    assert scripts(*ur5)["wc_run.script"] == run_text


def test_no_solver_option(ur5, run_text):
    bare = scripts(*ur5, UrOptions(solver=False))["wc_run.script"]
    for word in ("wc_solve", "wc_keep", "sync()"):
        assert word not in bare
    assert run_text.count("wc_solve(wc_rd)") == 1
    # the call is after the closing zero and before the end marker
    assert run_text.index("wc_meas(11, 0, z, t0)") < run_text.index("wc_solve(wc_rd)")
    assert run_text.index("wc_solve(wc_rd)") < run_text.index('wc_send("# end")')


def test_gen_no_solver_cli(tmp_path):
    r = CliRunner().invoke(
        main,
        [
            "gen",
            str(UR5 / "robot.toml"),
            str(UR5 / "plan.toml"),
            "-o",
            str(tmp_path / "o"),
            "--no-solver",
        ],
    )
    assert r.exit_code == 0, r.output
    assert "wc_solve" not in (tmp_path / "o" / "wc_run.script").read_text()


@pytest.mark.parametrize("x", [1.0, -0.0, 0.1, -392.25, 6.123233995736766e-17, 0.9999999])
def test_float_literal_is_the_nearest_float32(x):
    text = float_literal(x)
    assert "." in text
    assert np.float32(float(text)) == np.float32(x)


def _case(robot, plan, text, seed, tmp_path):
    rng = np.random.default_rng([seed, 77])
    truth = dict(zip(robot.parameters, rng.uniform(-4.5, 4.5, 10), strict=True))
    start = 2**31 - 15_000 if seed % 3 == 0 else None  # the raw int32 count wraps
    log = simulate_log(robot, plan, truth, seed=seed, counter_start=start)
    m = check_log(parse_log(log, f"seed{seed}.csv"), plan, robot)
    ref = solve(robot, plan, m).estimates["stepwise"].as_dict()
    run = controller_runs(robot, plan, m, tmp_path, programs={"wc_run.script": text})["stepwise"]
    return run, {n: abs(run.offsets[n] - v) for n, v in ref.items()}


@pytest.fixture(scope="module")
def case(ur5, run_text, tmp_path_factory):
    """:func:`_case` of a seed, run once a module (two tests read seed 1's run)."""
    runs: dict[int, tuple] = {}

    def run(seed: int) -> tuple:
        if seed not in runs:
            runs[seed] = _case(*ur5, run_text, seed, tmp_path_factory.mktemp(f"seed{seed}"))
        return runs[seed]

    return run


@pytest.mark.parametrize("seed", [0, 1])
def test_agrees_with_the_reference(case, seed):
    _, diff = case(seed)
    assert max(diff.values()) <= AGREEMENT


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(2, 12))
def test_agrees_with_the_reference_more_truths(ur5, run_text, tmp_path, seed):
    _, diff = _case(*ur5, run_text, seed, tmp_path)
    assert max(diff.values()) <= AGREEMENT


def test_operations_and_pacing(ur5, case):
    """One sqrt per point and iteration (50 points x 5); only + - * / and sqrt; sync()
    after every joint of every forward kinematics keeps < 400 operations between two."""
    _, plan = ur5
    run, _ = case(1)
    ops = run.operations
    assert set(ops) == {"add", "mul", "div", "sqrt"}
    assert ops["sqrt"] == plan.n_points * 5
    assert 3e5 < run.total_operations < 6e5
    fks = len(plan.steps) * 5 + plan.n_points * 5  # theta0 + each point, per iteration
    assert run.syncs == fks * 6 + (plan.n_points + 1) + plan.n_points + 10
    assert run.most_between_syncs < OPS_PER_SYNC
    assert run.console[-1].startswith("# Controller solver done")
    assert any(line.startswith("# a3  mm  ") for line in run.console)  # the table of values


def test_readings_from_a_log_by_hand(ur5):
    robot, plan = ur5
    q, _, _ = plan.all_points()
    rows = [
        "# wirecal-log 2",
        f"# robot: {robot.name}",
        f"# plan: {plan.fingerprint()}",
        f"# mm_per_count: {robot.encoder.mm_per_count}",
        "kind,step,index,j1,j2,j3,j4,j5,j6,counts,samples,spread,t_s,settle_s",
    ]
    k = 0
    for s, step in enumerate(plan.steps, 1):
        rows.append(
            f"zero,{s},0,{','.join(f'{x:.4f}' for x in plan.theta0_deg)},"
            f"-2147483000.2500,10,1,0.000,3.000"
        )
        for i in range(len(step.points_deg)):
            rows.append(
                f"point,{s},{i + 1},{','.join(f'{x:.4f}' for x in q[k])},"
                f"{100 + k}.0700,10,1,0.000,3.000"
            )
            k += 1
    rows.append(
        f"zero,{len(plan.steps) + 1},0,{','.join(f'{x:.4f}' for x in plan.theta0_deg)},"
        "5.0000,10,1,0.000,3.000"
    )
    log = parse_log("\n".join(rows) + "\n", "hand.csv")
    rd = ur_readings(log.readings, plan)
    assert len(rd) == READING_INTS * (len(plan.steps) + plan.n_points)
    assert rd[:2] == [-2147483001, 7500]  # floor of the count, offset x 10^4
    slot = len(plan.steps) + 2  # point 3 in plan order
    assert rd[slot * 8 : slot * 8 + 2] == [102, 700]
    assert rd[slot * 8 + 2 : slot * 8 + 8] == [round(x * 10000) for x in q[2]]


def test_result_in_log_reads_only_the_prefixed_lines():
    text = (
        "# wirecal-log 2\nzero,1,0\n# solver: step 1 of 1: th2 identified\n"
        "# controller: # wirecal-controller-result 1\n# controller: # method: stepwise\n"
        "# controller: parameter,unit,offset\n# controller: th2,deg,-0.001234\n# end\n"
    )
    assert parse_result(result_in_log(text), "log") == {"th2": -0.001234}
    assert result_in_log("# wirecal-log 2\n# end\n") is None
    with pytest.raises(WirecalError, match="not a number"):
        parse_result(result_in_log(text.replace("-0.001234", "x")), "log")


@pytest.mark.slow
def test_cli_simulate_controller_then_solve_method_controller(tmp_path):
    """simulate --controller runs wc_run (wc_solve at its end) in the twin; the log carries
    its result; solve --method controller reruns wc_solve on the log and compares."""
    import json

    robot, plan, log = str(UR5 / "robot.toml"), str(UR5 / "plan.toml"), tmp_path / "run.csv"
    r = CliRunner().invoke(main, ["simulate", robot, plan, "-o", str(log), "--controller"])
    assert r.exit_code == 0, r.output
    in_log = parse_result(result_in_log(log.read_text(encoding="ascii")), "log")
    r = CliRunner().invoke(main, ["solve", robot, plan, str(log), "--method", "controller"])
    assert r.exit_code == 0, r.output
    assert "URScript wc_solve run in the digital twin" in r.output
    r = CliRunner().invoke(
        main, ["solve", robot, plan, str(log), "--method", "controller", "--json"]
    )
    ctl = json.loads(r.stdout)["methods"]["controller"]
    assert ctl["parameters_max_difference"] <= AGREEMENT
    assert ctl["parameters"] == pytest.approx(in_log, abs=5e-6)
    assert ctl["most_operations_between_syncs"] < OPS_PER_SYNC
    assert "polished" not in ctl
