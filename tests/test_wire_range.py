"""Range before motion (issue: a 500 mm encoder on the paper plan, which needs 603 mm):
the nominal wire at every target of wc.run and along every move to it."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.wire_range import check_wire_range, run_moves


def _short(viper, range_mm):
    return replace(viper, encoder=replace(viper.encoder, range_mm=range_mm))


def test_paper_plan_fits_the_viper_encoder(viper, paper_plan):
    check_wire_range(viper, paper_plan)


def test_run_moves_follow_wc_run(paper_plan):
    """θ0, via points, points, back to θ0, per step: 69 points + 10 returns + the vias."""
    moves = run_moves(paper_plan)
    vias = sum(len(s.via_deg) for s in paper_plan.steps)
    assert len(moves) == 69 + 10 + vias
    assert moves[0][0] == "step 1 (th6) point 1"
    np.testing.assert_array_equal(moves[0][1], paper_plan.theta0_deg)
    np.testing.assert_array_equal(moves[-1][2], paper_plan.theta0_deg)
    for (_, _, b, _), (_, a, _, _) in itertools.pairwise(moves):
        np.testing.assert_array_equal(a, b)  # each move starts where the last ended


def test_longest_point_and_the_move_beyond_it(viper, paper_plan):
    """The farthest point is 602.5 mm away (computed here from the forward kinematics);
    a move between points reaches farther than either end, and the check sees it."""
    model = viper.nominal
    q, _, _ = paper_plan.all_points()
    p0 = tool_position(model, np.radians(paper_plan.theta0_deg)[None])[0]
    longest = np.linalg.norm(tool_position(model, np.radians(q)) - p0, axis=1).max()
    assert longest == pytest.approx(602.5, abs=0.05)
    check_wire_range(_short(viper, longest + 20.0 + 45.0), paper_plan)  # moves reach 643.5
    with pytest.raises(WirecalError) as e:
        check_wire_range(_short(viper, longest + 20.0 + 0.1), paper_plan)
    assert all("on the move there" in p for p in e.value.problems)
    with pytest.raises(WirecalError) as e:
        check_wire_range(_short(viper, 700.0), paper_plan, margin_mm=60.0)
    assert "less the 60 mm margin" in e.value.problems[0]


def test_a_point_at_theta0_is_refused(viper, paper_plan):
    """A point equal to θ0 (the wire tip on the fixture) is named with its step."""
    s = paper_plan.steps[2]
    pts = np.vstack([s.points_deg, paper_plan.theta0_deg])
    plan = replace(
        paper_plan, steps=(*paper_plan.steps[:2], replace(s, points_deg=pts), *paper_plan.steps[3:])
    )
    with pytest.raises(WirecalError) as e:
        check_wire_range(viper, plan)
    (problem,) = e.value.problems
    assert problem.endswith(
        f"step 3 (th5) point {len(pts)}: the nominal wire is 0.0 mm long, within 5 mm of "
        "zero; move the point away from theta0"
    )
