"""The patch as the controller gets it: ``gen --patch`` writes wc.patch, which runs in the twin
and types the same table as the SPEC file ``solve -o`` writes beside the patch; entered in the
twin's controller, that table makes its model the true robot's (sign and value)."""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.truth import truth_text
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.accuracy import error_vs_truth_mm, workspace
from wirecal.solver.kinematics import tool_position
from wirecal.solver.params import ErrorSet
from wirecal.twin.vplus.controller import VplusController
from wirecal.twin.vplus.interp import Interpreter
from wirecal.twin.world import World

from .conftest import TABLE5, VIPER

ROBOT, PLAN = str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")
NUMBER = r"[-+]?\d+\.\d+"


def _spec_rows(text: str) -> dict[str, tuple[float, float]]:
    """Return the SPEC file's rows: parameter -> (new value, offset)."""
    pattern = rf"^(\w+)\s+\d+\s+.+?\s+(?:deg|mm)\s+{NUMBER}\s+({NUMBER})\s+({NUMBER})"
    return {
        m[1]: (float(m[2]), float(m[3]))
        for m in (re.match(pattern, line) for line in text.splitlines())
        if m
    }


def _typed_rows(console: list[str]) -> dict[str, tuple[float, float]]:
    """Return the rows wc.spec typed: parameter -> (new value, offset)."""
    pattern = rf"^(\w+)\s+(?:deg|mm)\s+({NUMBER})\s+({NUMBER})$"
    return {
        m[1]: (float(m[3]), float(m[2]))
        for m in (re.match(pattern, line.strip()) for line in console)
        if m
    }


@pytest.fixture(scope="module")
def patched(tmp_path_factory, viper, paper_plan):
    """Simulate the Table 5 robot, solve to a patch, run wc.patch of ``gen --patch`` in the twin."""
    tmp = tmp_path_factory.mktemp("patch")
    (tmp / "truth.toml").write_text(truth_text(viper, TABLE5, None))
    log, patch = tmp / "run.csv", tmp / "patch.toml"
    runner = CliRunner()
    truth = str(tmp / "truth.toml")
    for args in (
        ["simulate", ROBOT, PLAN, "-o", str(log), "--ideal-encoder", "--errors", truth],
        ["solve", ROBOT, PLAN, str(log), "-o", str(patch)],
        ["gen", ROBOT, PLAN, "--patch", str(patch), "-o", str(tmp / "ctl")],
    ):
        r = runner.invoke(main, args)
        assert r.exit_code == 0, r.output
    (module,) = (tmp / "ctl").glob("*.V2")
    cell = VplusController(World(viper, TABLE5, paper_plan.theta0_deg, tmp / "disk"))
    interp = Interpreter(parse_module(module.read_text(encoding="ascii"), module.name), cell)
    outcome = interp.execute("wc.patch")
    assert outcome.status == "completed", outcome.message
    return {
        "interp": interp,
        "typed": _typed_rows(outcome.console),
        "spec": _spec_rows((tmp / "patch.spec.txt").read_text()),
        "patch": tomllib.loads(patch.read_text())["parameters"],
    }


def test_wc_patch_types_the_spec_table(patched, paper_plan):
    """Every parameter: wc.spec's new value and offset are the SPEC file's, to the digits
    each prints (the SPEC file 4 decimals, wc.spec 4 for the value and 6 for the offset)."""
    typed, spec = patched["typed"], patched["spec"]
    assert set(typed) == set(spec) == set(paper_plan.order)
    for name, (value, offset) in spec.items():
        assert typed[name][0] == pytest.approx(value, abs=1.01e-4), name
        assert typed[name][1] == pytest.approx(offset, abs=0.51e-4), name


def test_wc_patch_keeps_the_patch_offsets_in_internal_units(patched, viper, paper_plan):
    """wc.e[j] holds the patch's offset j in rad or mm (the plan's order), to the double's
    literal precision."""
    internal = ErrorSet(paper_plan.order, viper.n_joints).to_internal(
        [patched["patch"][n]["offset"] for n in paper_plan.order]
    )
    for j, x in enumerate(internal, 1):
        assert float(patched["interp"].get_global("wc.e", j)) == pytest.approx(x, rel=1e-12)


def test_spec_values_entered_make_the_twin_the_true_robot(patched, viper):
    """The sign, against an independent truth: the twin's controller believing the SPEC
    table's values (new − nominal) has its tool point within 0.05 mm of the true robot's
    (mean over 1000 configurations), from over 1 mm with the nominal model; the opposite
    sign would make it worse than nominal."""
    believed = {n: v - viper.nominal_value(n) for n, (v, _) in patched["spec"].items()}
    twin = patched["interp"].cell.world
    q = workspace(viper)
    for controller, low, high in (
        ({}, 1.0, np.inf),
        (believed, 0.0, 0.05),
        ({n: -x for n, x in believed.items()}, 1.5, np.inf),
    ):
        cell = VplusController(World(viper, TABLE5, twin.mount_deg, twin.disk), controller)
        true = tool_position(cell.world.model, q)
        gap = np.linalg.norm(tool_position(cell.believed, q) - true, axis=1)
        assert low < gap.mean() < high, controller
    assert error_vs_truth_mm(viper, TABLE5, believed, q) < 0.05
