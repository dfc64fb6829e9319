"""A declared ``repeatability_mm``: the gate's noise model and the zero readings' slip check.

An arm that repeats to 0.05 mm (declared in the robot file, so the twin's and simulate's
arm lands so) must pass the plausibility gate and the generated programs' slip check when
the log is sound, and a bad log or a slipped wire must still be caught.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import integrate, stats

from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.simulated_log import simulate_log
from wirecal.solver.kinematics import tool_position
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plausibility import assess
from wirecal.solver.simulate import Unmodelled
from wirecal.solver.solve import solve
from wirecal.solver.verdict import FALSE_ALARM
from wirecal.solver.zero_reading import SLIP_FACTOR

from .test_zero_reading import EXAMPLES, _robot

PLANS = {"ur5e": "plan.toml", "viper_s650": "paper_plan.toml", "abb_irb120": "plan.toml"}


def _robot_file(tmp_path: Path, arm: str, repeatability_mm: float | None) -> str:
    text = (EXAMPLES / arm / "robot.toml").read_text()
    if repeatability_mm is not None:
        line = f"[calibration]\nrepeatability_mm = {repeatability_mm}\n"
        text = text.replace("[calibration]\n", line)
    path = tmp_path / f"{arm}_{repeatability_mm}.toml"
    path.write_text(text)
    return str(path)


def _landing_sigma_monte_carlo(robot, plan, draws: int = 4000) -> float:
    """RMS over the plan's points of the wire length's σ when the arm lands as the twin's.

    The twin's joint errors (Unmodelled), the wire from the tool point at θ0 (the UR5e's
    point exit: ‖p − p0‖), ``draws`` landings per point; independent of the gate's code.
    """
    q, _, _ = plan.all_points()
    p0 = tool_position(robot.nominal, np.radians(plan.theta0_deg)[None])[0]
    rng = np.random.default_rng(11)
    many = np.repeat(q, draws, axis=0)
    landed = many + Unmodelled(robot.repeatability_mm, 0.0).joint_errors_deg(
        robot.nominal, many, rng
    )
    d = np.linalg.norm(tool_position(robot.nominal, np.radians(landed)) - p0, axis=1)
    return float(np.sqrt(np.mean(d.reshape(len(q), draws).var(axis=1))))


def test_the_gates_noise_model_adds_the_declared_repeatability_only():
    plain, declared = _robot("ur5e"), _robot("ur5e", repeatability_mm=0.05)
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", plain)
    text = simulate_log(declared, plan, {}, seed=3, unmodelled=Unmodelled(0.05, 0.0))
    verdicts, dofs = {}, set()
    for robot in (plain, declared):
        m = check_log(parse_log(text, "run"), plan, robot)
        result = solve(robot, plan, m)
        verdicts[robot.repeatability_mm] = assess(result, "joint")
        dofs.add(int(m.present.sum()) - len(result.estimates["joint"].names))
    q = abs(plain.encoder.mm_per_count)
    reading = np.hypot(0.02, q / np.sqrt(12))  # the default reading noise and quantisation
    (dof,) = dofs
    chi = np.sqrt(stats.chi2.isf(FALSE_ALARM, dof) / dof)
    # Without the key: the reading noise and quantisation only, as before.
    assert verdicts[None].noise_model_mm == pytest.approx(reading, rel=1e-12)
    assert verdicts[None].residual_limit_mm == pytest.approx(reading * chi, rel=1e-9)
    # With it: plus the landing's scatter, 0.026 mm here (Monte Carlo of 4000 landings per
    # point: its relative standard error ~1 %).
    landing = _landing_sigma_monte_carlo(declared, plan)
    assert 0.02 < landing < 0.03
    expected = np.hypot(reading, landing)
    assert verdicts[0.05].noise_model_mm == pytest.approx(expected, rel=0.02)
    assert verdicts[0.05].residual_limit_mm == pytest.approx(expected * chi, rel=0.02)


def _simulate(tmp_path: Path, robot: str, arm: str, seed: int, *extra: str) -> tuple[str, str]:
    log = str(tmp_path / f"run{seed}{len(extra)}.log")
    args = ["simulate", robot, str(EXAMPLES / arm / PLANS[arm]), "-o", log, "--seed", str(seed)]
    res = CliRunner().invoke(main, [*args, "--force", *extra])
    return log, res.output if res.exit_code == 0 else f"exit {res.exit_code}: {res.output}"


def _solve(robot: str, arm: str, log: str):
    res = CliRunner().invoke(
        main, ["solve", robot, str(EXAMPLES / arm / PLANS[arm]), log, "--json"]
    )
    return res.exit_code, res.output


def test_cli_simulate_of_an_arm_repeating_to_0_05_mm_passes_the_gate(tmp_path):
    """Seed 2 was refused (residual σ 0.0352 mm, the limit 0.0333 without the arm)."""
    robot = _robot_file(tmp_path, "ur5e", 0.05)
    for seed in (0, 1, 2):
        log, out = _simulate(tmp_path, robot, "ur5e", seed)
        assert out.startswith("wrote"), out
        code, out = _solve(robot, "ur5e", log)
        assert code == 0, out
        gate = json.loads(out)["plausibility"]
        assert gate["passed"]
        assert 0.045 < gate["residual_limit_mm"] < 0.06


@pytest.mark.parametrize("declared", [None, 0.05])
def test_a_bad_log_is_refused_with_or_without_the_key(tmp_path, declared):
    """Four readings 0.3 mm off: residual σ about 0.1 mm, twice the widened limit."""
    robot = _robot_file(tmp_path, "ur5e", declared)
    log, out = _simulate(tmp_path, robot, "ur5e", 2, "--outliers", "4", "--outlier-mm", "0.3")
    assert out.startswith("wrote"), out
    code, out = _solve(robot, "ur5e", log)
    assert code == 3, out
    assert "the residual is far above the noise" in out
    assert ("the arm's repeatability" in out) == (declared is not None)


def test_slip_factor_is_the_false_alarm_quantile_of_the_widest_shape():
    """δ along one line: ‖δa‖ − ‖δb‖ = σ(|za| − |zb|), E‖δ‖ = σ√(2/π) (quadrature)."""

    def beyond(x: float) -> float:  # P(| |za| − |zb| | > x), za, zb ~ N(0, 1)
        inner = lambda y: 2 * stats.norm.pdf(y) * 2 * stats.norm.sf(x + y)  # noqa: E731
        return 2 * integrate.quad(inner, 0, np.inf, epsabs=1e-15)[0]

    mean = np.sqrt(2 / np.pi)
    assert beyond(SLIP_FACTOR * mean) <= FALSE_ALARM
    assert beyond((SLIP_FACTOR - 0.05) * mean) > FALSE_ALARM  # no looser than it needs
    # An isotropic δ (‖δ‖ = σ·χ₃) is far inside it: a Monte Carlo of 10⁶ pairs.
    rng = np.random.default_rng(0)
    a, b = (np.linalg.norm(rng.standard_normal((1_000_000, 3)), axis=1) for _ in range(2))
    assert np.quantile(np.abs(a - b), 1 - 1e-4) / stats.chi.mean(3) < 0.6 * SLIP_FACTOR


@pytest.mark.parametrize(
    ("arm", "check"),
    [
        ("viper_s650", "wc.ztol = {}\n"),
        ("ur5e", "jumped by more than {} mm"),
        ("abb_irb120", "jumped by more than {} mm"),
    ],
)
def test_generated_slip_check_takes_the_declared_repeatability(tmp_path, arm, check):
    """5.84·E‖δ‖ at θ0, rounded up to 0.01 mm: E‖δ‖ at 0.05 mm is 2.5 times the 11.4 µm
    (Viper, IRB 120) and 18.7 µm (UR5e) the docs give at 0.02 mm (test_zero_reading checks
    them against a Monte Carlo): 0.166 → 0.17, 0.273 → 0.28 mm; 0.1 mm without the key."""
    texts = {}
    for declared in (None, 0.05):
        out = tmp_path / f"{arm}_{declared}"
        robot = _robot_file(tmp_path, arm, declared)
        args = ["gen", robot, str(EXAMPLES / arm / PLANS[arm]), "-o", str(out)]
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 0, res.output
        texts[declared] = "".join(p.read_text() for p in sorted(out.iterdir()))
    wide = "0.28" if arm == "ur5e" else "0.17"
    assert check.format("0.1") in texts[None]
    assert check.format(wide) not in texts[None]
    assert check.format(wide) in texts[0.05]
    assert check.format("0.1") not in texts[0.05]


def test_twin_run_of_an_arm_repeating_to_0_05_mm_completes_and_a_slip_is_caught(tmp_path):
    """Seed 2: the UR5e's programs stopped at step 6 (a zero 0.1 mm from the last)."""
    robot = _robot_file(tmp_path, "ur5e", 0.05)
    log, out = _simulate(tmp_path, robot, "ur5e", 2, "--controller")
    assert out.startswith("wrote"), out
    code, out = _solve(robot, "ur5e", log)
    assert code == 0, out
    _, out = _simulate(tmp_path, robot, "ur5e", 2, "--controller", "--slip", "3:0.5")
    assert out.startswith("exit 1"), out
    assert "jumped by more than 0.28 mm" in out
    assert "during step 3" in out


def test_a_slipped_wire_is_still_refused_by_the_log_reader(tmp_path):
    robot = _robot_file(tmp_path, "ur5e", 0.05)
    log, out = _simulate(tmp_path, robot, "ur5e", 2, "--slip", "3:0.5")
    assert out.startswith("wrote"), out
    code, out = _solve(robot, "ur5e", log)
    assert code == 2, out
    assert "the wire slipped" in out
    assert "tolerance 0.28 mm" in out


def test_fit_gate_takes_the_declared_repeatability_by_solves_rule():
    """``wirecal fit`` on a table from a Viper that repeats to 0.05 mm (joints logged to
    1e-4°, lengths to 1 µm: the landing dominates the floor): with the key declared the
    gate passes it, its noise model grown by σ_a (``landing_sigma_mm``, solve's rule; the
    held-out floor too);
    without the key the same table is refused; a table 0.3 mm noisier is still refused."""
    from dataclasses import replace

    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.errors import Implausible
    from wirecal.solver.fit.gate import gate_fit
    from wirecal.solver.fit.result import FitOptions, fit_table
    from wirecal.solver.fit.synth import synthetic_table

    robot = load_robot(EXAMPLES / "viper_s650" / "robot.toml")
    declared = replace(robot, repeatability_mm=0.05)
    syn = synthetic_table(
        declared,
        300,
        seed=1,
        sessions=1,
        snags=0,
        typos=0,
        joint_resolution_deg=1e-4,
        length_resolution_mm=0.001,
        repeatability_mm=0.05,
    )
    options = FitOptions(repeats=2)
    gate = gate_fit(fit_table(declared, syn.table, options))
    verdict = gate.chosen.verdict
    assert verdict.passed, verdict.findings
    # the noise model explains the residual (the reading noise 0.02 mm alone would not)
    assert verdict.residual_sigma_mm > 0.025
    assert abs(verdict.residual_sigma_mm / verdict.noise_model_mm - 1) < 0.15
    with pytest.raises(Implausible, match="the residual σ"):
        gate_fit(fit_table(robot, syn.table, options))
    rng = np.random.default_rng(7)
    noisy = replace(syn.table, length_mm=syn.table.length_mm + rng.normal(0, 0.3, 300))
    with pytest.raises(Implausible, match="the residual σ"):
        gate_fit(fit_table(declared, noisy, options))
