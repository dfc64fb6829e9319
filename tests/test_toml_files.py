"""The TOML field validator, and the readers built on it: truth files, patches (read back
beside the writer, ``wirecal gen --patch``), validation setups; one ``bool`` rule in all."""

from __future__ import annotations

import tomllib
from datetime import UTC, datetime

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.patch import PatchMeta, PatchValue, patch_text, read_patch
from wirecal.formats.patch_digest import seal
from wirecal.formats.plan_file import plan_from_dict
from wirecal.formats.robot_file import robot_from_dict
from wirecal.formats.toml_fields import Table, document
from wirecal.formats.truth import load_errors
from wirecal.formats.validation_files import load_setup
from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.identify import Estimate

from .conftest import VIPER


def _table(data, keys=None):
    return Table(data, Problems("f.toml"), "t", keys)


def _problems(t: Table) -> list[str]:
    return t.problems.items


# -- the validator ---------------------------------------------------------------------------
def test_bool_is_never_a_number():
    t = _table({"x": True, "n": False, "v": [1, True], "m": [[1.0, False]]})
    assert t.number("x") is None
    assert t.integer("n") is None
    assert t.vector("v") is None
    assert t.matrix("m", cols=2) is None
    assert _problems(t) == [
        "f.toml: t.x: is true; give a finite number",
        "f.toml: t.n: is false; give a whole number",
        "f.toml: t.v: value 2 is true; give a finite number",
        "f.toml: t.m[1]: value 2 is false; give a finite number",
    ]


@pytest.mark.parametrize(
    ("value", "kwargs", "expected", "message"),
    [
        (3, {}, 3.0, None),
        (float("nan"), {}, None, "is nan; give a finite number"),
        (float("inf"), {"lo": 0}, None, "is inf; give a number ≥ 0"),
        (
            1e300,
            {"lo": -10, "hi": 10, "unit": "mm"},
            None,
            "is 1e+300; give a number within ±10 mm",
        ),
        (0, {"above": 0}, None, "is 0; give a number > 0"),
        (5, {"lo": 1, "hi": 3}, None, "is 5; give a number between 1 and 3"),
        ("5", {}, None, 'is "5"; give a finite number'),
        ([5], {}, None, "is [5]; give a finite number"),
    ],
)
def test_number(value, kwargs, expected, message):
    t = _table({"x": value})
    assert t.number("x", **kwargs) == expected
    assert _problems(t) == ([f"f.toml: t.x: {message}"] if message else [])


def test_integer_is_a_toml_integer():
    t = _table({"a": 24, "b": 24.0, "c": 24.5, "d": 7})
    assert t.integer("a", lo=8, hi=64) == 24
    assert t.integer("b", lo=8, hi=64) is None
    assert t.integer("c", lo=8, hi=64) is None
    assert t.integer("d", lo=8) is None
    assert _problems(t) == [
        "f.toml: t.b: is 24.0; give a whole number between 8 and 64 (no decimal point)",
        "f.toml: t.c: is 24.5; give a whole number between 8 and 64",
        "f.toml: t.d: is 7; give a whole number ≥ 8",
    ]


def test_required_optional_and_unknown_keys():
    t = _table({"rnage_mm": 1, "zzz": 2}, keys=("range_mm", "mode"))
    assert t.number("range_mm") is None
    assert t.integer("mode", 3) == 3
    assert _problems(t) == [
        "f.toml: t.rnage_mm: unknown key (did you mean 'range_mm'?)",
        "f.toml: t.zzz: unknown key",
        "f.toml: t.range_mm: is missing",
    ]


def test_vectors_and_matrices():
    t = _table({"p": [1, 2], "q": "x", "m": [[1, 2], [3]], "e": []})
    assert t.vector("p", length=3, labels="(x, y, z)") is None
    assert t.vector("q") is None
    assert t.matrix("m", cols=2) is None
    assert t.matrix("e", cols=2) is None
    np.testing.assert_array_equal(t.matrix("absent", [], cols=2, nonempty=False), np.zeros((0, 2)))
    assert _problems(t) == [
        "f.toml: t.p: has 2 values; expected 3 (x, y, z)",
        'f.toml: t.q: is "x"; give a list of numbers',
        "f.toml: t.m[2]: has 1 values; expected 2",
        "f.toml: t.e: is []; give a non-empty list of rows of 2 numbers",
    ]


def test_nested_tables_reported_once():
    t = _table({"enc": 5, "steps": [{"a": 1}, 3]})
    enc = t.table("enc", ("a",))
    assert enc.number("a") is None  # the table's problem hides its keys'
    missing = t.table("kin", ("dh",))
    assert missing.matrix("dh", cols=4) is None
    steps = t.tables("steps", ("a",))
    assert steps[0].number("a") == 1
    assert not steps[1].present
    assert _problems(t) == [
        "f.toml: t.enc: is 5; give a table [t.enc]",
        "f.toml: t.kin: is missing; add the table [t.kin]",
        "f.toml: t.steps[2]: is 3; give a table",
    ]


def test_strings_and_choices():
    t = _table({"s": " ", "c": "standard", "l": ["a", 1]})
    assert t.string("s") is None
    assert t.string("c", choices={"craig": "modified DH"}) is None
    assert t.strings("l", what="parameter names") is None
    assert t.string("absent", "x") == "x"
    assert _problems(t) == [
        'f.toml: t.s: is " "; give a non-empty string',
        'f.toml: t.c: is "standard"; give "craig" (modified DH)',
        'f.toml: t.l: is ["a", 1]; give a list of parameter names',
    ]


def test_document_names_the_other_kind():
    with pytest.raises(WirecalError) as info:
        document({"errors": {}, "robot": "x"}, "t.toml", "patch file", ())
    assert info.value.problems == [
        "t.toml: is a truth file (true offsets of a simulated robot), not a patch written by "
        "wirecal solve"
    ]
    assert document({"errors": {}}, "t.toml", "truth file", ("errors",)).present


# -- one bool rule in every reader --------------------------------------------------------
ROBOT = tomllib.loads((VIPER / "robot.toml").read_text())
PLAN = tomllib.loads((VIPER / "paper_plan.toml").read_text())


def test_bool_rule_in_every_reader(viper, paper_plan, tmp_path):
    robot = {**ROBOT, "encoder": {**ROBOT["encoder"], "range_mm": True}}
    plan = {**PLAN, "theta0_deg": [0, -90, 210, -90, True, -90]}
    truth = tmp_path / "t.toml"
    truth.write_text("[errors]\nth2 = true\n")
    setup = tmp_path / "v.toml"
    setup.write_text((VIPER / "validation.toml").read_text().replace("poses = 50", "poses = true"))
    patch = tmp_path / "p.toml"
    patch.write_text(_patch(viper, paper_plan).replace("offset = 0.5", "offset = true"))
    cases = [
        (lambda: robot_from_dict(robot, "r.toml"), "encoder.range_mm: is true; give"),
        (lambda: plan_from_dict(plan, viper, "p.toml"), "theta0_deg: value 5 is true; give"),
        (lambda: load_errors(truth, viper), "errors.th2: is true; give"),
        (lambda: load_setup(setup), "configuration.poses: is true; give"),
        (lambda: read_patch(patch), "parameters.th2.offset: is true; give"),
    ]
    for read, message in cases:
        with pytest.raises(WirecalError) as info:
            read()
        assert any(message in p for p in info.value.problems), info.value.problems


# -- truth files --------------------------------------------------------------------------
def test_truth_file(viper, tmp_path):
    path = tmp_path / "t.toml"
    path.write_text('robot = "Adept Viper s650"\nseed = 3\n[errors]\nth2 = 0.5\na2 = -1\n')
    assert load_errors(path, viper) == {"th2": 0.5, "a2": -1.0}
    path.write_text('robot = "UR5"\nsed = 3\n[errors]\nth9 = 1\na2 = 1e300\nth3 = 400\n')
    with pytest.raises(WirecalError) as info:
        load_errors(path, viper)
    assert info.value.problems[0] == f"{path}: sed: unknown key (did you mean 'seed'?)"
    assert info.value.problems[1] == (
        f"{path}: robot: the truth is for 'UR5' but the robot file describes "
        "'Adept Viper s650'; use the matching robot file"
    )
    assert info.value.problems[2].startswith(f"{path}: errors.th9: unknown parameter 'th9'")
    assert info.value.problems[3:] == [
        f"{path}: errors.a2: is 1e+300; give a number within ±10000 mm",
        f"{path}: errors.th3: is 400; give a number within ±360 deg",
    ]


def test_patch_given_as_truth(viper, paper_plan, tmp_path):
    path = tmp_path / "patch.toml"
    path.write_text(_patch(viper, paper_plan))
    with pytest.raises(WirecalError) as info:
        load_errors(path, viper)
    assert info.value.problems == [
        f"{path}: is a patch written by wirecal solve, not a truth file (true offsets of a "
        "simulated robot)"
    ]


# -- patches ------------------------------------------------------------------------------
def _patch(viper, plan, std=True) -> str:
    estimate = Estimate(
        "joint",
        ("th2", "a2"),
        np.array([0.5, -0.125]),
        0.011,
        std=np.array([0.01, 0.02]) if std else None,
    )
    return patch_text(
        viper,
        estimate,
        plan_fingerprint=plan.fingerprint(),
        log_path="run.csv",
        log_sha256="ab" * 32,
        version="9.9",
        date=datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC),
    )


def test_patch_round_trip(viper, paper_plan, tmp_path):
    path = tmp_path / "patch.toml"
    path.write_text(_patch(viper, paper_plan))
    patch = read_patch(path)
    assert patch.meta == PatchMeta(
        robot="Adept Viper s650",
        plan=paper_plan.fingerprint(),
        log="run.csv",
        log_sha256="ab" * 32,
        method="joint",
        date="2026-01-02T03:04:05Z",
        wirecal="9.9",
        residual_rms_mm=0.011,
    )
    assert patch.parameters == {
        "th2": PatchValue("deg", 0.0, 0.5, 0.5, 0.01),
        "a2": PatchValue("mm", 270.0, -0.125, 269.875, 0.02),
    }
    assert patch.offsets_for(viper, paper_plan) == {"th2": 0.5, "a2": -0.125}
    path.write_text(_patch(viper, paper_plan, std=False))
    assert read_patch(path).parameters["a2"].std is None


def test_patch_unidentified_std_and_verdict(viper, paper_plan, tmp_path):
    """A patch accepted despite the plausibility gate says so, and σ = inf marks a parameter
    the points do not identify: both read back."""
    path = tmp_path / "patch.toml"
    text = _patch(viper, paper_plan).replace("std = 0.02", "std = inf")
    path.write_text(  # as solve writes it: sealed with the mark
        seal(text.replace("[parameters.th2]", 'plausibility = "overridden: x"\n\n[parameters.th2]'))
    )
    patch = read_patch(path)
    assert patch.meta.plausibility == "overridden: x"
    assert patch.parameters["a2"].std == float("inf")
    path.write_text(seal(text.replace("std = inf", "std = -inf")))
    with pytest.raises(WirecalError, match=r"parameters\.a2\.std: is -inf; give a number ≥ 0 mm"):
        read_patch(path)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (
            lambda t: t.replace("value = 269.875", "value = 269.0"),
            "parameters.a2.value: is 269.0 "
            "but nominal + offset is 269.875: the patch was edited; write it again with wirecal "
            "solve",
        ),
        (
            lambda t: t.replace('unit = "mm"', 'unit = "m"'),
            'parameters.a2.unit: is "m"; give "deg" (th, al) or "mm" (a, d, tool)',
        ),
        (lambda t: t.replace('log_sha256 = "abab', 'log_sha256 = "xyab'), "log_sha256: is 'xyab"),
        (lambda t: t.replace("method =", "methd ="), "methd: unknown key (did you mean 'method'?)"),
        (
            lambda t: t.replace("std = 0.02", "std = -0.02"),
            "parameters.a2.std: is -0.02; give a number ≥ 0 mm",
        ),
    ],
)
def test_patch_refused(viper, paper_plan, tmp_path, edit, message):
    path = tmp_path / "patch.toml"
    path.write_text(edit(_patch(viper, paper_plan)))
    with pytest.raises(WirecalError) as info:
        read_patch(path)
    assert any(f"{path}: {message}" in p for p in info.value.problems), info.value.problems


def test_patch_of_another_robot_or_plan(viper, paper_plan, printed_plan, tmp_path):
    path = tmp_path / "patch.toml"
    path.write_text(seal(_patch(viper, printed_plan).replace("Adept Viper s650", "UR5")))
    with pytest.raises(WirecalError) as info:
        read_patch(path).offsets_for(viper, paper_plan)
    assert info.value.problems == [
        f"{path}: robot: the patch is for 'UR5' but the robot file describes 'Adept Viper "
        "s650'; use the matching robot file",
        f"{path}: plan: the patch was solved from another plan; generate with the plan it "
        "came from",
    ]


GEN = ["gen", str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")]


def test_gen_patch(viper, paper_plan, tmp_path):
    full = Estimate("joint", paper_plan.order, np.full(10, 0.25), 0.011)
    patch = tmp_path / "patch.toml"
    patch.write_text(
        patch_text(
            viper,
            full,
            plan_fingerprint=paper_plan.fingerprint(),
            log_path="run.csv",
            log_sha256="ab" * 32,
            version="9.9",
        )
    )
    runner = CliRunner()
    r = runner.invoke(main, [*GEN, "-o", str(tmp_path / "ok"), "--patch", str(patch)])
    assert r.exit_code == 0, r.output
    plain = runner.invoke(main, [*GEN, "-o", str(tmp_path / "plain")])
    assert plain.exit_code == 0, plain.output
    patched = (tmp_path / "ok" / "WIRECAL.V2").read_text()
    assert patched != (tmp_path / "plain" / "WIRECAL.V2").read_text()
    partial = tmp_path / "partial.toml"
    partial.write_text(_patch(viper, paper_plan))
    r = runner.invoke(main, [*GEN, "-o", str(tmp_path / "p"), "--patch", str(partial)])
    assert r.exit_code == 2, r.output
    assert "patch: no value for th6, d6, th5, th4, a3, d4, th3, a1" in r.output


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (
            '# wirecal truth\nrobot = "Adept Viper s650"\nseed = 3\n[errors]\nth2 = 0.5\n',
            "is a truth file (true offsets of a simulated robot), not a patch written by "
            "wirecal solve",
        ),
        (
            (VIPER / "paper_plan.toml").read_text(),
            "is a plan file (θ0 and point sets), not a patch",
        ),
        ("plan = [", "not valid TOML"),
    ],
)
def test_gen_patch_not_a_patch(tmp_path, content, message):
    path = tmp_path / "x.truth.toml"
    path.write_text(content)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, [*GEN, "-o", str(out), "--patch", str(path)])
    assert r.exit_code == 2
    assert r.output.startswith(f"error: {path}: {message}")
    assert "Traceback" not in r.output
    assert not out.exists()


# -- validation setup ---------------------------------------------------------------------
def test_setup_rules(tmp_path):
    path = tmp_path / "v.toml"
    text = (VIPER / "validation.toml").read_text()
    assert load_setup(VIPER / "validation.toml").grid == (19, 11)
    path.write_text(
        text.replace("grid = [19, 11]", "grid = [19.5, 11]")
        .replace("yaw_deg = 0.0", "yaw = 0.0")
        .replace("[850.0, 0.0, -150.0]", "[850.0, 0.0, 1e300]")
    )
    with pytest.raises(WirecalError) as info:
        load_setup(path)
    assert info.value.problems == [
        f"{path}: plate.yaw: unknown key (did you mean 'yaw_deg'?)",
        f"{path}: configuration.encoder_mm: value 3 is 1e+300; give a number within ±10000 mm",
        f"{path}: plate.grid: value 1 is 19.5; give a whole number between 1 and 1000",
    ]
