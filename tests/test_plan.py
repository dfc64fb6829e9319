"""Plan files: validation messages, canonical fingerprint, round trip."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from wirecal.formats.plan_file import load_plan, plan_from_dict, plan_to_toml
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import fingerprint

from .conftest import VIPER

TEXT = (VIPER / "paper_plan.toml").read_text()


def test_paper_plan(paper_plan):
    assert paper_plan.n_points == 69
    assert len(paper_plan.steps) == 10
    assert paper_plan.order == ("th6", "d6", "th5", "th4", "a3", "d4", "a2", "th3", "th2", "a1")
    np.testing.assert_array_equal(paper_plan.theta0_deg, [0, -90, 210, -90, 0, -90])


def test_fingerprint_ignores_layout_but_not_content(viper, paper_plan):
    base = fingerprint(paper_plan)
    assert len(base) == 64
    reformatted = "# a comment\n" + TEXT.replace(
        "[0, -90, 210, -90, 0, -90]", "[0.0, -90.000, 210, -90, 0e0, -90]", 1
    )
    assert fingerprint(plan_from_dict(tomllib.loads(reformatted), viper)) == base
    with_omega = TEXT.replace('parameter = "th6"', 'parameter = "th6"\nomega = 2.0')
    assert fingerprint(plan_from_dict(tomllib.loads(with_omega), viper)) == base
    moved = TEXT.replace("[0, -90, 210, -90, -26, -180]", "[0, -90, 210, -90, -26, -179.999]")
    assert fingerprint(plan_from_dict(tomllib.loads(moved), viper)) != base


def test_round_trip(viper, paper_plan, printed_plan):
    for plan in (paper_plan, printed_plan):
        again = plan_from_dict(tomllib.loads(plan_to_toml(plan)), viper)
        assert fingerprint(again) == fingerprint(plan)
        assert again.description == plan.description


def _errors(viper, text):
    with pytest.raises(WirecalError) as info:
        plan_from_dict(tomllib.loads(text), viper, "p.toml")
    return info.value.problems


def test_point_beyond_limit_names_step_and_point(viper):
    text = TEXT.replace("[0, -90, 230, -65, -80, 0]", "[0, -90, 230, -65, -130, 0]")
    assert _errors(viper, text) == [
        "p.toml: step[5].points_deg[1]: joint 5 = -130 deg is beyond its limits [-120, 120]"
    ]


def test_order_and_step_mismatch(viper):
    problems = _errors(viper, TEXT.replace('parameter = "d6"', 'parameter = "th5"', 1))
    assert (
        "p.toml: step[2].parameter: is 'th5' but order[2] is 'd6'; steps must follow the "
        "order" in problems
    )


def test_parameter_not_in_robot_file(viper):
    problems = _errors(viper, TEXT.replace('"a1"]', '"a0"]'))
    assert any(
        "order: 'a0' is not in the robot file's [calibration] parameters" in p for p in problems
    )


def test_wrong_vector_length_and_unknown_key(viper):
    problems = _errors(
        viper,
        TEXT.replace("[0, -90, 210, -90, -26, -170]", "[0, -90, 210, -90, -26]").replace(
            "theta0_deg", "theta_0_deg", 1
        ),
    )
    assert (
        "p.toml: step[1].points_deg[2]: has 5 values; expected 6 (one per joint, deg)" in problems
    )
    assert "p.toml: theta_0_deg: unknown key (did you mean 'theta0_deg'?)" in problems
    assert "p.toml: theta0_deg: is missing" in problems


def test_robot_name_mismatch(viper):
    problems = _errors(viper, TEXT.replace('robot = "Adept Viper s650"', 'robot = "UR5"'))
    assert problems == [
        "p.toml: robot: plan is for 'UR5' but the robot file describes "
        "'Adept Viper s650'; use the matching robot file"
    ]


def test_missing_step(viper):
    cut = TEXT[: TEXT.rindex("[[step]]")]
    assert any("has 9 step(s) but order names 10" in p for p in _errors(viper, cut))


def test_unreadable(viper, tmp_path):
    with pytest.raises(WirecalError, match="cannot read plan file"):
        load_plan(tmp_path / "nope.toml", viper)
