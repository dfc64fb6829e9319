"""The sweeps' fast paths give their general paths' numbers bit for bit (issue 34).

One move's samples (solver/plan/moves.py) are those of the same move among others; the
segments' distance (solver/cell/clearance.py), its dot products summed in place, is the
clamped closest-point construction written out term by term; a capsule's gap to a box
(solver/cell/model.py), its sampling fractions kept, is its points' distance a segment at a
time; the pre-flight's cell check, the pairs far apart bounded, says what it says with every
gap exact.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.solver.cell import check
from wirecal.solver.cell.check import check_cell
from wirecal.solver.cell.clearance import segment_distance
from wirecal.solver.cell.model import BOX_STEP_MM, Box, _box_gaps
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.moves import move_samples


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([0.0, 0.01, 1.0, 30.0, 400.0]),
    others=st.integers(1, 4),
    step=st.sampled_from([0.5, 2.0, 3.0]),
)
def test_one_moves_samples_are_its_samples_among_others(seed, scale, others, step):
    rng = np.random.default_rng(seed)
    a = rng.uniform(-180.0, 180.0, (others + 1, 6))
    b = a + rng.normal(0.0, scale, a.shape)
    q, first = move_samples(a[:1], b[:1], step)
    q_all, first_all = move_samples(a, b, step)
    count = first_all[1]
    assert first.tolist() == [0]
    assert q.tobytes() == q_all[:count].tobytes()
    k = np.arange(1, count + 1)[:, None]
    assert q.tobytes() == (a[0] + k / count * (b[0] - a[0])).tobytes()


def _distance_written_out(p1, q1, p2, q2):
    """The clamped closest points, each dot product as x·x' + y·y' + z·z' (the definition)."""

    def dot(u, v):
        return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]

    def unit(x):
        return np.minimum(np.maximum(x, 0.0), 1.0)

    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a, e, f, c, b = dot(d1, d1), dot(d2, d2), dot(d2, r), dot(d1, r), dot(d1, d2)
    denom = a * e - b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(denom > 1e-12, unit((b * f - c * e) / denom), 0.0)
        t = np.where(e > 1e-12, (b * s + f) / e, 0.0)
        s = np.where(t < 0, unit(-c / np.where(a > 1e-12, a, 1)), s)
        s = np.where(t > 1, unit((b - c) / np.where(a > 1e-12, a, 1)), s)
    t = unit(t)
    gap = (p1 + s * d1) - (p2 + t * d2)
    return np.sqrt(dot(gap, gap))


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.sampled_from([(1, 1), (8, 1), (11, 3), (5, 40)]),
    degenerate=st.sampled_from(["none", "point", "parallel", "both"]),
)
def test_the_segments_distance_is_the_construction_written_out(seed, shape, degenerate):
    rng = np.random.default_rng(seed)
    p1, q1, p2, q2 = (rng.normal(0.0, 300.0, (3, *shape)) for _ in range(4))
    if degenerate in ("point", "both"):
        q2[:, 0] = p2[:, 0]  # the second segment a point
    if degenerate in ("parallel", "both"):
        q2[:, -1] = p2[:, -1] + 2.0 * (q1[:, -1] - p1[:, -1])
    want = _distance_written_out(p1, q1, p2, q2)
    assert segment_distance(p1, q1, p2, q2).tobytes() == want.tobytes()
    # broadcast as the housing's and the wire's checks ask: one segment against many
    got = segment_distance(p1[:, :1], q1[:, :1], p2, q2)
    assert got.tobytes() == _distance_written_out(p1[:, :1], q1[:, :1], p2, q2).tobytes()


def _box_gaps_written_out(box, a, b, near_mm):
    """A capsule axis's distance to a box: its bounding box's, else its sampled points'."""

    def to_box(lo, hi, p_lo, p_hi):
        shape = (3,) + (1,) * (p_lo.ndim - 1)
        out = np.maximum(np.maximum(lo.reshape(shape) - p_hi, p_lo - hi.reshape(shape)), 0.0)
        return np.sqrt(out[0] * out[0] + out[1] * out[1] + out[2] * out[2])

    lo, hi = np.array(box.min_mm, float), np.array(box.max_mm, float)
    best = to_box(lo, hi, np.minimum(a, b), np.maximum(a, b))
    for s, k in zip(*np.nonzero(best < near_mm[:, None]), strict=True):
        d = b[:, s, k] - a[:, s, k]
        count = int(np.ceil(np.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / BOX_STEP_MM)) + 1
        p = a[:, s, k, None] + np.linspace(0.0, 1.0, count) * d[:, None]
        best[s, k] = np.min(to_box(lo, hi, p, p))
    return best


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), s=st.integers(1, 12), n=st.integers(1, 20))
def test_the_box_gaps_are_the_sampled_points_distances_written_out(seed, s, n):
    rng = np.random.default_rng(seed)
    a = rng.normal(0.0, 400.0, (3, s, n))
    b = a + rng.normal(0.0, 300.0, (3, s, n))
    box = Box("b", tuple(rng.uniform(-300.0, 0.0, 3)), tuple(rng.uniform(0.0, 300.0, 3)))
    near = rng.uniform(0.0, 300.0, s)
    assert _box_gaps(box, a, b, near).tobytes() == _box_gaps_written_out(box, a, b, near).tobytes()


EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
CHECKED_PLANS = (
    ("viper_s650", "colliding_plan.toml"),
    ("ur5e", "colliding_plan.toml"),
    ("abb_irb120", "plan.toml"),
)


def _problems(robot, plan) -> list[str] | None:
    try:
        check_cell(robot, plan)
    except WirecalError as exc:
        return exc.problems
    return None


@settings(max_examples=12, deadline=None)
@given(
    which=st.sampled_from(CHECKED_PLANS),
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([0.0, 5.0, 30.0, 90.0]),
)
def test_the_cell_check_says_what_it_says_with_every_gap_exact(which, seed, scale):
    """The pairs beyond SURE_GAP_MM left as bounds: the same refusals, word for word."""
    arm, name = which
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    plan = load_plan(EXAMPLES / arm / name, robot)
    lo, hi = robot.limits_deg(body=False)
    rng = np.random.default_rng(seed)
    steps = tuple(
        replace(
            s, points_deg=np.clip(s.points_deg + rng.normal(0.0, scale, s.points_deg.shape), lo, hi)
        )
        for s in plan.steps
    )
    moved = replace(plan, steps=steps)
    got = _problems(robot, moved)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(check, "SURE_GAP_MM", np.inf)
        assert got == _problems(robot, moved)
