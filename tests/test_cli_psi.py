"""``wirecal psi`` / ``wirecal observe`` through the command line."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from wirecal.cli.main import main

from .conftest import VIPER

ROBOT = str(VIPER / "robot.toml")
PLAN = str(VIPER / "paper_plan.toml")
PRINTED = str(VIPER / "paper_plan_as_printed.toml")


def run(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_psi_json_structure():
    r = run("psi", ROBOT, PLAN, "--json")
    assert r.exit_code == 0
    data = json.loads(r.output)
    assert data["order"] == ["th6", "d6", "th5", "th4", "a3", "d4", "a2", "th3", "th2", "a1"]
    assert len(data["rows"]) == 69
    first = data["rows"][0]
    assert first["step"] == 1
    assert first["index"] == 1
    assert first["parameter"] == "th6"
    assert first["joints_deg"] == [0, -90, 210, -90, -26, -180]
    assert round(first["psi"]["th6"], 2) == -1.07
    assert first["ok"] is True
    assert first["violations"] == []
    assert all(r["ok"] for r in data["rows"])
    assert data["identifiability"]["rank"] == 10


def test_psi_text_table_grouped_by_step():
    r = run("psi", ROBOT, PLAN)
    assert r.exit_code == 0
    assert "Step 1: th6  (6 points, 6 ok)" in r.output
    assert "Step 10: a1  (5 points, 5 ok)" in r.output
    assert "69 of 69 points ok." in r.output
    assert "rank 10 of 10" in r.output
    lines = r.output.splitlines()
    row = next(line for line in lines if line.startswith("  4    0.00  -90.00  239.93"))
    assert row.split("|")[1].split()[3] == "-3.04"
    assert row.endswith("| ok")


def test_printed_plan_violations_and_strict():
    r = run("psi", ROBOT, PRINTED, "--json")
    bad = [
        (x["step"], x["index"], x["violations"])
        for x in json.loads(r.output)["rows"]
        if not x["ok"]
    ]
    assert bad == [(7, i, ["th3"]) for i in range(2, 7)]
    assert run("psi", ROBOT, PRINTED).exit_code == 0
    strict = run("psi", ROBOT, PRINTED, "--strict")
    assert strict.exit_code == 1
    assert "64 of 69 points ok" in strict.output
    assert run("psi", ROBOT, PLAN, "--strict").exit_code == 0


def test_tolerance_option():
    data = json.loads(run("psi", ROBOT, PLAN, "--json", "--tol", "0.05").output)
    assert data["tolerance"] == 0.05
    leaking = {(x["step"], x["index"]) for x in data["rows"] if not x["ok"]}
    assert (4, 5) in leaking  # Ψ_a3 = 0.36 against Ψ_th4 = −2.62: 14 %


def test_observe_all():
    r = run("observe", ROBOT, PLAN, "--all", "--json")
    data = json.loads(r.output)
    assert set(data["unobservable"]) == {"al0", "a0", "th1", "d1"}
    assert {"th6", "tool_y"} in [set(c) for c in data["combinations"]]
    text = run("observe", ROBOT, PLAN).output
    assert "rank 10 of 10" in text
    assert "O3 =" in text


def test_bad_input_is_a_message_not_a_traceback(tmp_path):
    bad = tmp_path / "robot.toml"
    bad.write_text((VIPER / "robot.toml").read_text().replace('"th2", ', '"th9", '))
    r = CliRunner().invoke(main, ["psi", str(bad), PLAN])
    assert r.exit_code == 2
    assert "error: " + str(bad) + ": calibration.parameters: unknown parameter 'th9'" in r.output
    assert "Traceback" not in r.output


@pytest.mark.parametrize("command", [[], ["psi"], ["observe"]])
def test_help(command):
    r = run(*command, "--help")
    assert r.exit_code == 0
    assert "Usage:" in r.output
    assert len(r.output) > 200


def test_installed_console_script():
    # the script pip installed beside this interpreter (a venv's bin/ need not be on PATH)
    exe = shutil.which("wirecal", path=str(Path(sys.executable).parent))
    assert exe, "no wirecal console script beside this Python; install with pip install -e ."
    out = subprocess.run([exe, "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.startswith("wirecal, version ")
    out = subprocess.run([exe, "psi", ROBOT, PLAN, "--strict"], capture_output=True, text=True)
    assert out.returncode == 0
    assert "69 of 69 points ok" in out.stdout


def test_psi_strict_refuses_a_wire_beyond_the_encoders_range(tmp_path):
    """With a 500 mm encoder the paper plan's wire reaches 602.5 mm (step 6 point 5) and
    643.5 mm on the move to step 10's first point: a warning, an error with --strict."""
    robot = tmp_path / "short.toml"
    robot.write_text(
        (VIPER / "robot.toml").read_text().replace("range_mm = 1250.0", "range_mm = 500.0")
    )
    plain = CliRunner().invoke(main, ["psi", str(robot), PLAN])
    assert plain.exit_code == 0
    assert "warning: " in plain.output
    r = CliRunner().invoke(main, ["psi", str(robot), PLAN, "--strict"])
    assert r.exit_code == 1
    assert (
        "error: " + PLAN + ": step 6 (d4) point 5: the nominal wire is 602.5 mm long, "
        "beyond the encoder's range_mm 500 less the 20 mm margin" in r.output
    )
    assert "step 10 (a1) point 1: the nominal wire is 643.5 mm long on the move there" in (r.output)
    ok = CliRunner().invoke(main, ["psi", ROBOT, PLAN, "--strict"])
    assert ok.exit_code == 0
    assert "warning" not in ok.output
