"""``--partial`` is honest: every step solved without the zero reading after it (the check
that its wire did not slip) is named in the patch, the SPEC table, ``--json``, the report
and on the terminal; a version 1 log (no closing zero reading) is read with that warning."""

from __future__ import annotations

import json
import tomllib

import pytest
from click.testing import CliRunner

from wirecal.app.report import render_report
from wirecal.cli.main import main
from wirecal.formats.log import parse_log
from wirecal.formats.patch import read_patch
from wirecal.formats.simulated_log import simulate_log
from wirecal.solver.log.measurements import check_log
from wirecal.solver.solve import solve

from .conftest import TABLE5, VIPER
from .test_logfile import as_version_1

ROBOT = str(VIPER / "robot.toml")
PLAN = str(VIPER / "paper_plan.toml")
MM_PER_COUNT = 0.025488
STEP10 = (
    "step 10 (a1) unchecked: the closing zero reading at θ0 is missing, so a wire slip "
    "during step 10 is invisible"
)


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    return simulate_log(viper, paper_plan, TABLE5, seed=3, counter_start=1000.0)


def slipped_in_step_10(text: str, slip_mm: float = 0.5) -> str:
    """The wire slips at the first move of step 10 (every point of it reads long) and
    the run stops before the closing zero reading that would have shown it."""
    out = []
    for line in text.splitlines():
        cells = line.split(",")
        if line.startswith("zero,11,"):
            continue
        if line.startswith("point,10,"):
            cells[9] = f"{float(cells[9]) + slip_mm / MM_PER_COUNT:.4f}"
        out.append(",".join(cells))
    return "\n".join(out) + "\n"


def run(args, stdin=None):
    return CliRunner().invoke(main, ["solve", ROBOT, PLAN, *args], input=stdin)


def test_a_slip_in_the_last_step_is_named_everywhere(tmp_path, log_text):
    """The issue's case: --partial solves it (exit 0) with the slip unseen, and now every
    output says that step 10 was not checked."""
    log = tmp_path / "run.csv"
    log.write_text(slipped_in_step_10(log_text))
    refused = run([str(log)])
    assert refused.exit_code == 2
    assert "missing the closing zero reading at θ0 after step 10" in refused.output

    patch = tmp_path / "patch.toml"
    r = run([str(log), "--partial", "-o", str(patch)])
    assert r.exit_code == 0, r.output
    assert f"warning: {STEP10}" in r.stderr
    assert tomllib.loads(patch.read_text())["unchecked"] == [STEP10]
    assert read_patch(patch).meta.unchecked == (STEP10,)
    spec = (tmp_path / "patch.spec.txt").read_text().splitlines()
    assert spec[:2] == [
        f"WARNING: {STEP10}.",
        "Measure the step(s) again before entering these values.",
    ]
    data = json.loads(run([str(log), "--partial", "--json"]).stdout)
    assert data["unchecked"] == [{"step": 10, "parameter": "a1", "warning": STEP10}]
    # what the mark is for: the 0.5 mm slip moves a1, the step's parameter, by 0.27 mm
    clean = json.loads(run(["-", "--json"], stdin=log_text).stdout)
    a1 = [d["methods"]["joint"]["parameters"]["a1"] for d in (data, clean)]
    assert abs(a1[0] - TABLE5["a1"]) > 0.2
    assert abs(a1[1] - TABLE5["a1"]) < 0.05


def test_a_run_stopped_mid_step_names_that_step(viper, paper_plan, log_text):
    """Stopped in step 5: its points are there but no zero of step 6 checks them."""
    cut = log_text[: log_text.index("point,5,4,")]
    result = solve(
        viper, paper_plan, check_log(parse_log(cut, "cut.csv"), paper_plan, viper), partial=True
    )
    assert result.unchecked == (
        "step 5 (a3) unchecked: the zero reading of step 6 at θ0 is missing, so a wire slip "
        "during step 5 is invisible",
    )
    assert "a3" in result.names
    html = render_report(result)
    assert "Warning: step 5 (a3) unchecked: the zero reading of step 6" in html


def test_a_complete_log_has_no_mark(tmp_path, log_text):
    log = tmp_path / "run.csv"
    log.write_text(log_text)
    patch = tmp_path / "patch.toml"
    r = run([str(log), "-o", str(patch)])
    assert r.exit_code == 0, r.output
    assert "unchecked" not in patch.read_text()
    assert "WARNING" not in (tmp_path / "patch.spec.txt").read_text()
    assert "unchecked" not in r.stderr


def test_a_version_1_log_without_closing_zero_is_read_with_the_warning(tmp_path, log_text):
    """wirecal 0.1 took no closing zero reading: such a log solves without --partial,
    the last step named as unchecked; its values equal the version 2 solve's."""
    v1 = "\n".join(
        line for line in as_version_1(log_text).splitlines() if not line.startswith("zero,11,")
    )
    log = tmp_path / "old.csv"
    log.write_text(v1 + "\n")
    r = run([str(log), "--json"])
    assert r.exit_code == 0, r.output
    warning = STEP10.replace("is missing,", "is missing (a version 1 log has none),")
    assert f"warning: {warning}" in r.stderr
    old = json.loads(r.stdout)
    assert old["unchecked"][0]["warning"] == warning
    assert old["missing"] == []
    new = json.loads(run(["-", "--json"], stdin=log_text).stdout)
    for method in ("stepwise", "joint"):
        got, want = old["methods"][method]["parameters"], new["methods"][method]["parameters"]
        assert got == pytest.approx(want, abs=1e-4)  # the same lengths; no drift fit in v1
