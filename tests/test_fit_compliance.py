"""``wirecal fit`` with ``[calibration] compliances``: c_j estimated beside the geometry.

The compliant tables are simulated by the robot model's own frames bent under gravity
(:func:`~wirecal.solver.fit.synth.synthetic_table` with a compliant truth: the kinematics'
``frames``, not the fit's length model), joints logged to 0.01° (at a pendant's 0.1° the
rounding floor, 0.23 mm, hides the sag: σ(c3) ≈ 11 µrad/(N·m) at 1000 rows).
"""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest
from click.testing import CliRunner

from tests.conftest import ROOT
from wirecal.cli.main import main
from wirecal.formats.patch import read_patch
from wirecal.formats.robot_file import load_robot
from wirecal.solver.fit.result import FitOptions, fit_table
from wirecal.solver.fit.synth import synthetic_table, table_text

VIPER = ROOT / "examples" / "viper_s650" / "robot.toml"
TRUTH_URAD_PER_NM = np.array([0.0, 6.0, 8.0, 0.0, 0.0, 0.0])  # issue 30's range, joints 2, 3


@pytest.fixture(scope="module")
def viper():
    return replace(load_robot(VIPER), compliances=("c2", "c3"))


def _compliances(result) -> dict[str, tuple[float, float]]:
    core = result.main.core
    per = core.layout.boundary_per_internal
    return {
        n: (float(v), float(s))
        for n, v, s in zip(core.layout.names, core.x * per, core.std * per, strict=True)
        if n.startswith("c")
    }


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow)])
def test_a_compliant_table_gives_c2_and_c3_within_three_sigma(viper, seed):
    # measured (seeds 0-2): c2 5.45-5.80 ± 0.52-0.58, c3 5.91-8.87 ± 1.7-1.8 µrad/(N·m)
    syn = synthetic_table(
        viper, 1000, seed=seed, compliance_urad_per_nm=TRUTH_URAD_PER_NM, joint_resolution_deg=0.01
    )
    got = _compliances(fit_table(viper, syn.table, FitOptions(holdout="none")))
    assert set(got) == {"c2", "c3"}
    for name, truth in (("c2", 6.0), ("c3", 8.0)):
        value, std = got[name]
        assert abs(value - truth) <= 3 * std, (name, value, std)
    assert got["c2"][1] < 1.0  # c2 known to 1 µrad/(N·m)


def test_a_rigid_table_keeps_no_compliance_or_one_within_three_sigma_of_zero(viper):
    syn = synthetic_table(viper, 1000, seed=0, joint_resolution_deg=0.01)
    result = fit_table(viper, syn.table, FitOptions(holdout="none"))
    for value, std in _compliances(result).values():
        assert abs(value) <= 3 * std
    dropped = dict(result.main.core.dropped)
    assert "not worth a parameter (BIC)" in dropped["c2"]  # |z| 0.22 on this table


def test_at_a_pendants_rounding_the_compliances_are_named_poorly_identified(viper):
    syn = synthetic_table(viper, 300, seed=0, compliance_urad_per_nm=TRUTH_URAD_PER_NM)
    dropped = dict(fit_table(viper, syn.table, FitOptions(holdout="none")).main.core.dropped)
    assert "poorly identified: with it c3's σ" in dropped["c3"]


@pytest.mark.slow
def test_cli_writes_the_compliances_to_the_patchs_compliance_table(tmp_path, viper):
    text = VIPER.read_text(encoding="utf-8").replace(
        "[calibration]\n", '[calibration]\ncompliances = ["c2", "c3"]\n', 1
    )
    robot_file = tmp_path / "robot.toml"
    robot_file.write_text(text, encoding="utf-8")
    syn = synthetic_table(
        viper, 1000, seed=0, compliance_urad_per_nm=TRUTH_URAD_PER_NM, joint_resolution_deg=0.01
    )
    table = tmp_path / "t.csv"
    table.write_text(table_text(syn.table), encoding="utf-8")
    patch = tmp_path / "patch.toml"
    args = ["fit", str(robot_file), str(table), "--holdout", "none", "--json", "-o", str(patch)]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    out, _ = json.JSONDecoder().raw_decode(r.output[r.output.index("{") :])
    assert out["plausibility"]["passed"]
    params = out["parameters"]
    assert params["c2"]["unit"] == "urad/Nm"
    assert abs(params["c2"]["value"] - 6.0) <= 3 * params["c2"]["std"]
    written = read_patch(patch)
    assert set(written.compliance) == {"c2", "c3"}
    assert written.compliance["c2"].value == pytest.approx(params["c2"]["value"], abs=1e-3)
