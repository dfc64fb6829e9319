"""``plan --pool`` → a run → ``solve``: the fit the plan was made for, the replay's own.

A synthetic tracker table (a UR10 with DH errors, a compliance, 0.02 mm noise, in the
tracker's frame) is the pool; ``wirecal plan --pool -o plan.toml`` chooses θ0 and the
poses; the log is the run a wire from θ0's measured point would read (the replay's
readings: the distance rounded to the count, another zero); ``wirecal solve`` must give
the parameters the replay's fit gives on the same rows.
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from wirecal.cli.main import main
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulated_log_text
from wirecal.solver import params as P
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.kinematics import tool_position
from wirecal.solver.simulate import simulate_run
from wirecal.solver.tracker.data import TrackerTable
from wirecal.solver.tracker.replay import wire_fit
from wirecal.solver.wire_prior import fit_wire, posterior, prior_sigma

ROOT = Path(__file__).resolve().parents[1]
UR10 = ROOT / "tests" / "data" / "tracker" / "ur10_ipa" / "robot.toml"
TRUTH = {"th2": 0.05, "th3": -0.04, "a2": 0.4, "a3": -0.3, "d4": 0.2, "al3": 0.03, "c2": 6.0}
COUNTER_ZERO = 1000.0
"""The counts at θ0: any value (the replay's zero is another)."""


def _table(n: int, seed: int) -> TrackerTable:
    """A UR10's joints (4 decimals, as the log keeps them) and its measured tool points."""
    rng = np.random.default_rng(seed)
    lo = np.array([-90.0, -150.0, 30.0, -150.0, 30.0, -90.0])
    hi = np.array([90.0, -40.0, 140.0, -30.0, 150.0, 90.0])
    q = np.round(rng.uniform(lo, hi, (n, 6)), 4)
    truth = load_robot(UR10).model({**TRUTH, "tool_z": 0.8})
    rot = Rotation.from_rotvec([0.1, -0.2, 1.3]).as_matrix()
    x = tool_position(truth, np.radians(q)) @ rot.T + [1200.0, -2500.0, 300.0]
    x += rng.normal(0.0, 0.02, x.shape)
    return TrackerTable("pool.csv", "synthetic", np.arange(n) + 2, q, x)


def _row(table: TrackerTable, joints_deg: np.ndarray) -> int:
    """Return the table row at ``joints_deg`` (the plan's and the log's joints are the pool's)."""
    off = np.abs(table.q_deg - joints_deg).max(axis=1)
    assert off.min() < 1e-9
    return int(np.argmin(off))


def _run_log(robot_path: Path, plan_path: Path, table: TrackerTable) -> str:
    """Return the log of the plan's run read by a wire from θ0's measured point."""
    robot = load_robot(robot_path)
    plan = load_plan(plan_path, robot)
    anchor = table.xyz_mm[_row(table, plan.theta0_deg)]
    mpc = robot.encoder.mm_per_count
    run = simulate_run(robot, plan, {}, seed=0, noise_mm=0.0, counter_start=COUNTER_ZERO)

    def counts(kind: str, joints_deg: np.ndarray) -> float:
        if kind != "point":
            return COUNTER_ZERO
        far = np.linalg.norm(table.xyz_mm[_row(table, joints_deg)] - anchor)
        return COUNTER_ZERO + float(np.round(far / mpc))

    rows = tuple(
        dataclasses.replace(r, counts=counts(r.kind, r.joints_deg), spread=0.0)
        for r in run.readings
    )
    return simulated_log_text(dataclasses.replace(run, readings=rows))


@pytest.mark.slow
def test_solve_of_a_pool_plan_is_the_replays_fit(tmp_path):
    """Through the CLI: the patch's parameters are the replay's fit's to 1e-6 mm / deg,
    the anchor its anchor; and that fit is near the truth (the plan was made for it)."""
    table = _table(300, 3)
    pool = tmp_path / "pool.csv"
    pool.write_text(
        "j1,j2,j3,j4,j5,j6,x,y,z\n"
        + "".join(
            ",".join(f"{v:.4f}" for v in q) + "," + ",".join(f"{v:.6f}" for v in x) + "\n"
            for q, x in zip(table.q_deg, table.xyz_mm, strict=True)
        )
    )
    plan_path = tmp_path / "plan.toml"
    runner = CliRunner()
    args = ["plan", str(UR10), "--pool", str(pool), "--points", "40", "-o", str(plan_path)]
    r = runner.invoke(main, args)
    assert r.exit_code == 0, r.output
    log = tmp_path / "run.csv"
    log.write_text(_run_log(UR10, plan_path, table))
    patch = tmp_path / "patch.toml"
    r = runner.invoke(main, ["solve", str(UR10), str(plan_path), str(log), "-o", str(patch)])
    assert r.exit_code == 0, r.output
    r = runner.invoke(main, ["solve", str(UR10), str(plan_path), str(log), "--json"])
    doc = json.loads(r.output)
    solved = doc["methods"]["joint"]["parameters"]

    robot = load_robot(UR10)
    plan = load_plan(plan_path, robot)
    rows = np.array([_row(table, q) for q in plan.all_points()[0]])
    fit = wire_fit(robot, table, (_row(table, plan.theta0_deg), rows), robot.compliances)
    g = len(fit.layout.geometry)
    replayed = dict(
        zip(fit.layout.geometry, fit.x[:g] * fit.layout.boundary_per_internal[:g], strict=True)
    )
    assert list(solved) == list(replayed)  # the same parameters, in the same order
    assert np.allclose(list(solved.values()), list(replayed.values()), atol=1e-6)
    anchor = fit.layout.split(fit.x)[1]
    assert np.allclose(doc["pool_fit"]["anchor_mm"], anchor, atol=1e-6)
    # the arm's errors the readings carry; d4 only with d2, d3 (parallel axes 2–4: the
    # prior splits their sum evenly)
    tolerance = {"deg": 0.02, "mm": 0.05, "urad/Nm": 1.5}
    for name, value in TRUTH.items():
        if name != "d4":
            assert abs(solved[name] - value) < tolerance[P.unit_of(name)], (name, solved[name])
    assert abs(solved["d2"] + solved["d3"] + solved["d4"] - TRUTH["d4"]) < 0.05
    assert doc["plausibility"]["passed"]
    assert "prior" in doc["encoder"]["budget"]["joint"]["terms_mm"]
    text = patch.read_text()
    assert "[parameters.al3]" in text  # a DH error beyond the file's [calibration] list
    assert "[compliance.c2]" in text


def test_the_posterior_is_split_into_the_readings_and_the_prior():
    """noise + the prior's share = (JᵀJ/σ² + Λ)⁻¹, computed here by a plain inverse; the
    readings carry fewer parameters than are fitted, more than those without a prior, and
    σ is the residual's on the degrees of freedom they leave."""
    table = _table(80, 5)
    robot = load_robot(UR10)
    rows = np.arange(1, 61)
    length = np.linalg.norm(table.xyz_mm[rows] - table.xyz_mm[0], axis=1)
    fit, data = fit_wire(robot, robot.compliances, table.q_deg[rows], length, 0.5, 1e-6)
    base = point_model(robot)
    post = posterior(base, fit, data)
    J = post.jacobian
    lam = 1.0 / prior_sigma(base, fit.layout, fit.prior) ** 2
    P = np.linalg.inv(J.T @ J / post.sigma_mm**2 + np.diag(lam))
    sd = np.sqrt(np.diag(P))
    assert np.allclose(post.noise + post.prior_share, P, atol=1e-9 * np.outer(sd, sd).max())
    no_prior = int(np.sum(np.isinf(prior_sigma(base, fit.layout, fit.prior))))
    assert no_prior < post.effective < len(fit.x)
    rss = float(np.sum(post.residual_mm**2))
    assert post.sigma_mm == pytest.approx(np.sqrt(rss / (60 - post.effective)), rel=1e-12)
    assert post.sigma_mm > fit.sigma_mm  # the RMS of a fit of many parameters is short


@given(
    st.lists(
        st.floats(-359.9999, 359.9999, allow_nan=False).map(lambda v: round(v, 4)),
        min_size=6,
        max_size=6,
    )
)
def test_a_ppoint_line_keeps_the_limit_and_the_pose(q):
    """A pose recorded to 0.0001° (a pool's) broke V+'s 80-character line ("internal error
    … please report"): the literal now fits, within 0.005° of each angle, exact when it can."""
    from wirecal.gen.vplus.literals import MAX_LINE, PPOINT_PREFIX, ppoint

    text = ppoint(q)
    assert len(PPOINT_PREFIX + text) <= MAX_LINE
    values = [float(v) for v in re.fullmatch(r"#PPOINT\((.*)\)", text).group(1).split(",")]
    assert np.allclose(values, q, atol=0.005 + 1e-9)
    if len(PPOINT_PREFIX + "#PPOINT(" + ", ".join(f"{v:.4f}" for v in q) + ")") <= MAX_LINE:
        assert values == pytest.approx(q, abs=1e-9)


def _viper_pool(path: Path) -> None:
    """The Viper paper plan's θ0 and points, and twice more each moved, to 4 decimals."""
    viper = ROOT / "examples" / "viper_s650"
    robot = load_robot(viper / "robot.toml")
    plan = load_plan(viper / "paper_plan.toml", robot)
    q = plan.all_points()[0]
    rng = np.random.default_rng(0)
    pool = np.vstack([plan.theta0_deg[None], q, q + rng.normal(0, 4, q.shape)])
    pool = np.vstack([pool, q + rng.normal(0, 8, q.shape)])
    path.write_text(
        "j1,j2,j3,j4,j5,j6\n" + "".join(",".join(f"{v:.4f}" for v in r) + "\n" for r in pool)
    )


@pytest.mark.slow
def test_a_pool_plan_through_gen_solve_report_and_export(tmp_path):
    """A V+ arm: plan --pool → gen (its 4-decimal poses within the line limit) → a run →
    solve -o PATCH (the pool fit's parameters, the prior's share in the budget) →
    gen --patch refused (part of a fit) → export-urdf and report take the patch / the fit."""
    robot = ROOT / "examples" / "viper_s650" / "robot.toml"
    pool, plan, log, patch = (tmp_path / n for n in ("pool.csv", "plan.toml", "run.csv", "p.toml"))
    _viper_pool(pool)
    runner = CliRunner()

    def run(*args: str, code: int = 0) -> str:
        r = runner.invoke(main, list(args))
        assert r.exit_code == code, r.output
        assert "Traceback" not in r.output
        return r.output

    run("plan", str(robot), "--pool", str(pool), "--points", "40", "-o", str(plan))
    out = run("gen", str(robot), str(plan), "-o", str(tmp_path / "prog"))
    assert "runs the wire fit the plan was made for" in out
    out = run("observe", str(robot), str(plan))
    assert "'wirecal solve' runs the wire fit this plan was chosen for" in out
    run("simulate", str(robot), str(plan), "-o", str(log), "--seed", "2")
    out = run("solve", str(robot), str(plan), str(log), "-o", str(patch))
    assert re.search(r"^prior's share +\d", out, re.M), out
    assert re.search(r"^al4 +deg .* +\d\.\d\d$", out, re.M), out  # beyond the file's list
    out = run("solve", str(robot), str(plan), str(log), "--refine-scale", code=2)
    assert "--refine-scale refines the scale in the joint method" in out
    out = run(
        "gen", str(robot), str(plan), "-o", str(tmp_path / "p2"), "--patch", str(patch), code=2
    )
    assert "patch: holds tool_x, tool_y, tool_z" in out
    assert "entering part of a fit is not the fit" in out
    drift = ("--drift-mm-per-h", "3", "--samples", "500", "--noise-mm", "0.002", "--seed", "1")
    run("simulate", str(robot), str(plan), "-o", str(tmp_path / "drift.csv"), *drift)
    out = run("solve", str(robot), str(plan), str(tmp_path / "drift.csv"))
    assert "well measured, so it was removed from the lengths" in out  # judged on a clean σ
    run("export-urdf", str(robot), str(patch), "-o", str(tmp_path / "cal.urdf"))
    report = ("report", str(robot), str(plan), str(log), "-o", str(tmp_path / "r.html"))
    out = run(*report, "--controller", code=2)  # was a KeyError traceback: no wc.solve
    assert "report without --controller" in out
    run(*report)
    html = (tmp_path / "r.html").read_text()
    assert ">al4<" in html or "al4</td>" in html
    assert "the prior's share" in html  # the budget's row


def test_the_ur_companion_names_the_tool_point_it_cannot_carry(tmp_path):
    """A pool plan's patch holds the wire's attachment (tool_*): UR's companion refused the
    whole patch for it, so ``solve -o`` wrote nothing on a UR; now the deltas are written
    and the tool point named as not carried. The base frame is still refused."""
    import tomllib

    from wirecal.formats.patch_companion import read_companion
    from wirecal.lang.registry import language
    from wirecal.lang.urscript.calibration import calibration_text
    from wirecal.solver.errors import WirecalError

    ur5e = load_robot(ROOT / "examples" / "ur5e" / "robot.toml")
    text = calibration_text(ur5e, {"d4": 0.25, "tool_z": 0.8, "tool_x": -0.1})
    assert "# Not carried: the tool point's offsets" in text
    assert "#   tool_z +0.8000 mm, tool_x -0.1000 mm" in text
    assert tomllib.loads(text)["mounting"]["delta_d"] == pytest.approx(
        [0, 0, 0, 0.00025, 0, 0], abs=1e-15
    )
    path = tmp_path / "p.ur_calibration.conf"
    path.write_text(text)
    assert read_companion(path, language("urscript"))["delta_d"][3] == pytest.approx(0.00025)
    with pytest.raises(WirecalError, match="a0"):
        calibration_text(ur5e, {"a0": 0.1, "tool_z": 0.8})


def test_a_guide_pulley_is_refused_before_the_robot_moves(tmp_path):
    """The pool's wire fit models a straight wire from a point: over a guide pulley (an arc
    the budget leaves out) ``plan --pool`` refuses, naming the key, before any run."""
    text = (ROOT / "examples" / "ur5e" / "robot.toml").read_text()
    robot = tmp_path / "robot.toml"
    robot.write_text(
        text.replace('exit = "point"', 'exit = "pulley"\naxis = [0, 0, 1]\npulley_radius_mm = 15.0')
    )
    pool = tmp_path / "pool.csv"
    q = np.random.default_rng(1).uniform(-60.0, 60.0, (40, 6)) + np.array([0, -90, 90, -90, 90, 0])
    pool.write_text("j1,j2,j3,j4,j5,j6\n" + "".join(",".join(map(str, r)) + "\n" for r in q))
    r = CliRunner().invoke(main, ["plan", str(robot), "--pool", str(pool)])
    assert r.exit_code == 2, r.output
    assert 'exit = "pulley": the wire fit of a plan from a pool' in r.output
    assert "Traceback" not in r.output
