"""The plausibility gate: the faults that used to end in a confident wrong patch (a stuck
encoder, a robot file in metres, points that identify nothing, gross outliers) end with
exit status 3, a message saying what to check, and no file; sound logs pass."""

from __future__ import annotations

import dataclasses
import json
import re
import tomllib
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.identifiability import covariance
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plausibility import assess
from wirecal.solver.solve import solve
from wirecal.solver.verdict import chi2_quantile

from .conftest import VIPER


@pytest.mark.parametrize(
    ("alpha", "dof", "table"),
    [
        (0.05, 1, 3.841459),  # the printed tables' χ²_ν(1 − α) to 6 decimals
        (0.01, 10, 23.209251),
        (0.05, 30, 43.772972),
        (0.001, 4, 18.466827),
    ],
)
def test_chi2_quantile_matches_the_tables(alpha, dof, table):
    assert chi2_quantile(alpha, dof) == pytest.approx(table, abs=1e-6)


@pytest.mark.parametrize("alpha", [1e-6, 1e-3, 0.5])
def test_chi2_quantile_two_dof_is_closed_form(alpha):
    """For ν = 2 the χ² law is exponential: χ²_2(1 − α) = −2·ln α exactly."""
    assert chi2_quantile(alpha, 2) == pytest.approx(-2.0 * np.log(alpha), rel=1e-12)


ROBOT = str(VIPER / "robot.toml")
PLAN = str(VIPER / "paper_plan.toml")


def run(*args, input=None):
    return CliRunner().invoke(main, [str(a) for a in args], input=input, catch_exceptions=False)


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    truth = random_errors(viper, 1.0, np.random.default_rng(3))
    return simulate_log(viper, paper_plan, truth, seed=3)


def counts_set(text: str, value) -> str:
    """The log with every reading's counts replaced by ``value(old)``."""
    out = []
    for line in text.splitlines():
        if line.startswith(("zero,", "point,")):
            cells = line.split(",")
            cells[9] = value(cells[9])
            line = ",".join(cells)
        out.append(line)
    return "\n".join(out) + "\n"


def refused(result, patch):
    assert result.exit_code == 3, result.output
    assert "Traceback" not in result.output
    assert "nothing was written: this identification is not plausible" in result.output
    assert not patch.exists()
    assert not patch.with_name(patch.stem + ".spec.txt").exists()


def test_stuck_encoder_is_refused(tmp_path, log_text):
    log = tmp_path / "stuck.csv"
    log.write_text(counts_set(log_text, lambda c: "1234.0000"))
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "-o", patch)
    refused(r, patch)
    assert "every count is the same: the encoder did not count" in r.output
    assert "wrong channel, interface, belt_mode or pulse_inputs" in r.output
    assert "check it with wc.check before measuring again" in r.output
    assert re.search(r"span 0\.000 mm where the robot file's geometry gives \d{3}\.\d mm", r.output)


def test_counts_logged_in_mm_are_named(tmp_path, log_text):
    """A controller program that logged the wire's length, not the count: refused with 'the
    encoder counted far less than the wire moved', never named. Its span is mm_per_count
    (0.025488) times the model's: the counts column holds millimetres."""
    log = tmp_path / "in_mm.csv"
    log.write_text(counts_set(log_text, lambda c: f"{float(c) * 0.025488:.4f}"))
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "-o", patch)
    refused(r, patch)
    assert re.search(
        r"span 1\d\.\d{3} mm where the robot file's geometry gives \d{3}\.\d mm at the same "
        r"points, 0\.02[45]\d* times as much: the log's counts column looks like millimetres "
        r"\(its span is mm_per_count 0\.025488 × the expected one\)",
        r.output,
    )
    assert "log the raw count" in r.output
    assert "counted far less" not in r.output


def test_an_encoder_counting_a_fifth_is_not_taken_for_mm(tmp_path, log_text):
    """The neighbour: counts a fifth of the true ones (a span ratio of 0.2, far from
    mm_per_count) still read as an encoder that counted less than the wire moved."""
    log = tmp_path / "fifth.csv"
    log.write_text(counts_set(log_text, lambda c: f"{float(c) * 0.2:.4f}"))
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "-o", patch)
    refused(r, patch)
    assert "the encoder counted far less than the wire moved" in r.output
    assert "millimetres" not in r.output


def test_robot_file_in_metres_is_refused(tmp_path, viper, paper_plan, log_text):
    text = (VIPER / "robot.toml").read_text()
    for mm, m in (
        ("[ -90.0,   75.0,  0.0,   0.0]", "[ -90.0, 0.075, 0.0, 0.0]"),
        ("[   0.0,  270.0,  0.0,   0.0]", "[   0.0, 0.270, 0.0, 0.0]"),
        ("[  90.0,  -90.0,  0.0, 295.0]", "[  90.0, -0.090, 0.0, 0.295]"),
        ("[  90.0,    0.0,  0.0,  80.0]", "[  90.0, 0.0, 0.0, 0.080]"),
        ("point_mm = [-60.0, 0.0, 50.0]", "point_mm = [-0.060, 0.0, 0.050]"),
    ):
        assert mm in text
        text = text.replace(mm, m)
    robot = tmp_path / "robot_m.toml"
    robot.write_text(text)
    log = tmp_path / "run.csv"
    log.write_text(log_text)
    patch = tmp_path / "patch.toml"
    r = run("solve", robot, PLAN, log, "-o", patch)
    # The robot file reader refuses it first; the gate behind it names the units, should a
    # robot in metres get through (built in memory here, past the reader).
    assert r.exit_code == 2
    assert "the lengths look like metres; give a and d in mm" in r.output
    assert not patch.exists()
    dh_m = viper.dh.copy()
    dh_m[:, [1, 3]] /= 1000
    metres = dataclasses.replace(viper, dh=dh_m, tool_point=viper.tool_point / 1000)
    m = check_log(parse_log(log_text, "run.csv"), paper_plan, metres)
    verdict = assess(solve(metres, paper_plan, m), "joint")
    checks = {f.check: f.message for f in verdict.findings}
    assert "are the robot file's lengths in mm (not m)?" in checks["lengths"]
    assert "(1e+03 times as much)" in checks["lengths"]
    assert checks["residual"].startswith("the residual is far above the noise")


@pytest.fixture(scope="module")
def j1_plan(tmp_path_factory):
    """Every point of every step turns joint 1 only: one distance per point, one direction."""
    order = ["th6", "d6", "th5", "th4", "a3", "d4", "a2", "th3", "th2", "a1"]
    lines = [
        'robot = "Adept Viper s650"',
        "theta0_deg = [0, -90, 210, -90, 0, -90]",
        "order = [" + ", ".join(f'"{n}"' for n in order) + "]",
    ]
    for k, name in enumerate(order):
        rows = ", ".join(f"[{j1 + k}, -90, 210, -90, 0, -90]" for j1 in (10, 20, 30, 40, 50, 60))
        lines += ["[[step]]", f'parameter = "{name}"', f"points_deg = [{rows}]"]
    path = tmp_path_factory.mktemp("plan") / "j1_plan.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.slow
def test_points_that_identify_nothing_are_refused(tmp_path, j1_plan):
    log = tmp_path / "j1.csv"
    assert run("simulate", ROBOT, j1_plan, "-o", log, "--seed", 2).exit_code == 0
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, j1_plan, log, "-o", patch)
    refused(r, patch)
    assert "the distance Jacobian has rank 1 of 10" in r.output
    assert "th4 is unobservable: no wire length of these points depends on it" in r.output
    assert "wirecal observe ROBOT PLAN" in r.output
    # Overridden, every σ says so instead of 0, and no tool error is promised.
    shown = run("solve", ROBOT, j1_plan, log, "--accept-implausible")
    assert shown.exit_code == 0
    assert shown.output.count("unidentifiable") == 10
    assert "0.0000        0.0000" not in shown.output
    assert "tool error (mm)   unbounded   unbounded" in shown.output
    data = json.loads(run("solve", ROBOT, j1_plan, log, "--accept-implausible", "--json").stdout)
    assert set(data["methods"]["joint"]["std"].values()) == {None}
    assert data["methods"]["joint"]["predicted_tool_error_mm"] == {"mean": None, "max": None}
    assert data["plausibility"]["passed"] is False
    assert data["plausibility"]["rank"] == 1


def test_override_is_recorded_in_the_patch_and_spec_table(tmp_path, log_text):
    log = tmp_path / "stuck.csv"
    log.write_text(counts_set(log_text, lambda c: "1234.0000"))
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "-o", patch, "--accept-implausible")
    assert r.exit_code == 0
    assert "warning: implausible result accepted: implausible wire lengths" in r.output
    field = tomllib.loads(patch.read_text())["plausibility"]
    assert field == (
        "overridden: failed: implausible wire lengths; residual far above the noise model; "
        "estimates on their bound or beyond a plausible size"
    )
    spec = patch.with_name("patch.spec.txt").read_text()
    assert spec.startswith("WARNING: wirecal's plausibility gate refused this result")


def test_sound_log_passes_and_the_patch_says_so(tmp_path, log_text):
    log = tmp_path / "run.csv"
    log.write_text(log_text)
    patch = tmp_path / "patch.toml"
    r = run("solve", ROBOT, PLAN, log, "-o", patch)
    assert r.exit_code == 0, r.output
    assert "plausibility (joint): passed (residual σ 0.01" in r.output
    assert tomllib.loads(patch.read_text())["plausibility"].startswith("passed (residual σ")


def test_report_is_gated_too(tmp_path, log_text):
    log = tmp_path / "stuck.csv"
    log.write_text(counts_set(log_text, lambda c: "1234.0000"))
    out = tmp_path / "report.html"
    r = run("report", ROBOT, PLAN, log, "-o", out)
    assert r.exit_code == 3
    assert "the encoder did not count" in r.output
    assert not out.exists()


def test_gross_outliers_are_refused_unless_robust(tmp_path):
    log = tmp_path / "outliers.csv"
    args = ("--seed", 2, "--outliers", 3, "--outlier-mm", 1.5, "--random", 0.5)
    assert run("simulate", ROBOT, PLAN, "-o", log, *args).exit_code == 0
    plain = run("solve", ROBOT, PLAN, log)
    assert plain.exit_code == 3
    assert "gross outliers: --robust" in plain.output
    assert run("solve", ROBOT, PLAN, log, "--robust").exit_code == 0


@pytest.mark.slow
@pytest.mark.parametrize("noise_mm", [0.01, 0.02])
def test_no_false_alarm_over_20_seeds(viper, paper_plan, noise_mm):
    """Sound simulated logs, noise up to the gate's default: none refused, by any check."""
    for seed in range(20):
        truth = random_errors(viper, 1.0, np.random.default_rng([seed, 1]))
        text = simulate_log(viper, paper_plan, truth, seed=seed, noise_mm=noise_mm)
        result = solve(viper, paper_plan, check_log(parse_log(text, "s.csv"), paper_plan, viper))
        for method in result.estimates:
            verdict = assess(result, method)
            assert verdict.passed, (seed, method, verdict.findings)
            assert verdict.residual_sigma_mm < 0.8 * verdict.residual_limit_mm


def test_residual_limit_is_the_documented_chi_square_bound(viper, paper_plan, log_text):
    result = solve(viper, paper_plan, check_log(parse_log(log_text, "s.csv"), paper_plan, viper))
    verdict = assess(result, "joint")
    # χ²(59 dof) upper 1e-6 quantile = 125.665 (tables); σ_model² = 0.02² + 0.025488²/12.
    expected = np.sqrt(0.02**2 + 0.025488**2 / 12) * np.sqrt(125.665 / 59)
    assert verdict.residual_limit_mm == pytest.approx(expected, rel=1e-4)
    assert verdict.noise_model_mm == pytest.approx(0.021310, abs=1e-6)


def test_covariance_is_rank_aware():
    cov, ok = covariance(np.array([[1.0, 0.0], [0.0, 2.0], [0.0, 0.0]]), 1.0)
    np.testing.assert_allclose(cov, np.diag([1.0, 0.25]), atol=1e-12)
    assert ok.tolist() == [True, True]
    _, ok = covariance(np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0], [0.0, 2.0, 2.0]]), 1.0)
    assert ok.tolist() == [True, False, False]  # a2 + a3 seen, a2 − a3 not
    _, ok = covariance(np.array([[1.0, 2.0, 0.5]]), 1.0)  # fewer rows than parameters
    assert ok.tolist() == [False, False, False]


def test_override_is_carried_into_gen_and_export_urdf(tmp_path, log_text):
    """A patch written with --accept-implausible says so wherever it goes: gen's output and
    wc.patch (a comment, and TYPEd when it runs), export-urdf's output and the URDF."""
    log = tmp_path / "stuck.csv"
    log.write_text(counts_set(log_text, lambda c: "1234.0000"))
    patch = tmp_path / "patch.toml"
    assert run("solve", ROBOT, PLAN, log, "-o", patch, "--accept-implausible").exit_code == 0
    warning = "plausibility gate refused this result and the refusal was overridden"

    r = run("gen", ROBOT, PLAN, "-o", tmp_path / "gen", "--patch", patch)
    assert r.exit_code == 0, r.output
    assert f"warning: {patch}: wirecal's {warning} (--accept-implausible): failed:" in r.output
    module = (tmp_path / "gen" / "WIRECAL.V2").read_text()
    wc_patch = module[module.index(".PROGRAM wc.patch()") :]
    wc_patch = wc_patch[: wc_patch.index(".END")]
    assert '    TYPE "*** WARNING:"' in wc_patch
    assert "    ; WARNING:" in wc_patch
    assert wc_patch.count("implausible wire") == 2  # in the comment and in a TYPE line

    urdf = tmp_path / "calibrated.urdf"
    r = run("export-urdf", ROBOT, patch, "-o", urdf)
    assert r.exit_code == 0, r.output
    assert f"warning: {patch}: wirecal's {warning}" in r.output
    text = urdf.read_text()
    assert text.splitlines()[1].startswith(f"<!-- WARNING: wirecal's {warning}")
    ET.fromstring(text.split("\n", 1)[1])  # still well-formed XML after the comment
