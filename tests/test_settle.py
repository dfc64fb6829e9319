"""The settle rule's unsettled path and the wire-limited speeds, on the twin.

The still twin's settle times and the clock against run_timeline are in test_twin.py (its
run of the paper plan).

Expectations are computed independently of the code under test: wire speeds from the wire
lengths by finite differences along each move, the settle window from the rule's constants
as the template states them.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from wirecal.formats.log import load_measurements, read_log
from wirecal.gen.vplus.program import GenOptions, module_text
from wirecal.solver.distance import wire_lengths
from wirecal.solver.plan.planner import design
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    PAPER_RUN,
    optimal_readings,
    run_timeline,
)
from wirecal.twin.run_moves import move_of_step, run_targets
from wirecal.twin.world import Faults

from .twin_runs import measure_in_twin

TRUTH = {"th2": 0.05, "th3": -0.04, "a2": 0.1, "d4": -0.08}


def test_a_vibrating_twin_logs_unsettled_and_measures_the_point_again(viper, paper_plan, tmp_path):
    """Still vibrating at step 3 point 2: after the 2 s maximum the reading is logged as
    'unsettled' and the run pauses; the operator steadies the arm and continues; the point
    is measured again. The reader accepts the log and uses the second reading."""
    move = move_of_step(paper_plan, 3, 2)
    r = measure_in_twin(
        viper,
        paper_plan,
        TRUTH,
        tmp_path,
        seed=4,
        faults=Faults(vibration_at_move=move),
        proceed_on_pause=True,
    )
    assert r.run.status == "completed"
    assert any(line.startswith("# *** Still vibrating") for line in r.run.console)
    log = read_log(r.log)
    unsettled = [x for x in log.readings if x.kind == "unsettled"]
    assert [(x.step, x.index) for x in unsettled] == [(3, 2)]
    assert DEFAULT_RUN.settle_max_s <= unsettled[0].settle_s < DEFAULT_RUN.settle_max_s + 0.03
    again = next(x for x in log.readings if (x.kind, x.step, x.index) == ("point", 3, 2))
    assert again.line > unsettled[0].line
    assert again.settle_s < 0.2  # the operator steadied it: no wait beyond the window
    m = load_measurements(r.log, paper_plan, viper)
    assert m.complete
    assert m.unsettled == ((3, 2),)


@pytest.mark.slow
def test_samples_that_spread_too_wide_are_logged_unsettled_and_taken_again(
    viper, paper_plan, tmp_path
):
    """A spread tolerance of 1 count (0.03 mm) against the ±1-count jitter: many samplings
    fail it; each is logged as 'unsettled' and the point sampled again at once (a pause
    only when the 2 s maximum passes); every used reading keeps within 1 count."""
    r = measure_in_twin(
        viper,
        paper_plan,
        TRUTH,
        tmp_path,
        options=GenOptions(spread_tol_mm=0.03),
        seed=5,
        proceed_on_pause=True,
    )
    assert r.run.status == "completed"
    log = read_log(r.log)
    used = [x for x in log.readings if x.kind != "unsettled"]
    unsettled = [x for x in log.readings if x.kind == "unsettled"]
    assert len(used) == 80
    assert len(unsettled) > 20
    assert max(x.spread for x in used) <= 1
    # refused for their spread, or sampled after the 2 s maximum had passed (then paused)
    assert all(x.spread > 1 or x.settle_s >= 2 for x in unsettled)
    retried = {(x.step, x.index) for x in unsettled}
    waits = [x.settle_s for x in used if (x.step, x.index) in retried]
    assert max(waits) > 0.3  # the retries' time is in the settle time of the used reading
    m = load_measurements(r.log, paper_plan, viper)
    assert m.complete
    assert len(m.unsettled) == len(unsettled)


def test_a_vibrating_twin_stopped_at_the_pause_leaves_a_readable_log(viper, paper_plan, tmp_path):
    r = measure_in_twin(
        viper,
        paper_plan,
        TRUTH,
        tmp_path,
        seed=4,
        faults=Faults(vibration_at_move=move_of_step(paper_plan, 3, 2)),
    )
    assert r.run.status == "paused"
    m = load_measurements(r.log, paper_plan, viper)
    assert m.unsettled == ((3, 2),)
    assert m.missing_text() == "step 3 points 2–10; steps 4–10 (all points)"


def _program_moves(text: str) -> list[tuple[float, str]]:
    """Each MOVE of wc.run: its SPEED and its #PPOINT target, as the module states them."""
    run = text[text.index(".PROGRAM wc.run()") :]
    run = run[: run.index(".END")]
    pairs = re.findall(r"SET #wc\.p = (#PPOINT\([^)]*\))\n    SPEED ([\d.]+) ALWAYS\n    MOVE", run)
    return [(float(speed), target) for target, speed in pairs]


def _peak_wire_speed_mm_s(robot, plan, a_deg, b_deg, speed_pct) -> float:
    """Peak wire speed of a joint move at cruise, by finite differences of the wire length."""
    s = np.linspace(0, 1, 401)
    q = a_deg + s[:, None] * (b_deg - a_deg)
    length = wire_lengths(robot.nominal, np.radians(q), np.radians(plan.theta0_deg))
    slowest = np.max(np.abs(b_deg - a_deg) / robot.joint_speed_deg_s)
    if slowest == 0:
        return 0.0
    s_dot = speed_pct / 100 / slowest
    return float(np.max(np.abs(np.diff(length)) / np.diff(s)) * s_dot)


def _check_wire_speeds(robot, plan, text) -> np.ndarray:
    moves = _program_moves(text)
    assert len(moves) == len(run_targets(plan))
    targets = [plan.theta0_deg]
    for step in plan.steps:
        targets += [plan.theta0_deg, *step.via_deg, *step.points_deg]
    targets.append(plan.theta0_deg)
    peaks = np.array(
        [
            _peak_wire_speed_mm_s(robot, plan, np.asarray(a), np.asarray(b), speed)
            for (speed, _), a, b in zip(moves, targets[:-1], targets[1:], strict=True)
        ]
    )
    assert np.all(peaks <= robot.encoder.max_wire_speed_mm_s)
    return peaks


def test_generated_speeds_keep_the_paper_plans_wire_within_its_limit(
    viper, paper_plan, viper_module
):
    peaks = _check_wire_speeds(viper, paper_plan, viper_module)
    assert peaks.max() > 0.5 * viper.encoder.max_wire_speed_mm_s  # the limit is used


@pytest.mark.slow
def test_generated_speeds_keep_the_designed_plans_wire_within_its_limit(viper):
    plan = design(viper, np.array([0, -90, 210, -90, 0, -90], float)).plan
    _check_wire_speeds(viper, plan, module_text(viper, plan))


@pytest.mark.slow
def test_the_twin_refuses_a_hand_edited_speed_beyond_the_wire_limit(
    viper, paper_plan, viper_module, tmp_path
):
    text = viper_module
    moves = _program_moves(text)
    k = int(np.argmin([speed for speed, _ in moves]))  # the move the wire slows most
    speed, target = moves[k]
    old = f"SET #wc.p = {target}\n    SPEED {speed:g} ALWAYS"
    assert text.count(old) == 1
    edited = text.replace(old, f"SET #wc.p = {target}\n    SPEED 100 ALWAYS")
    r = measure_in_twin(viper, paper_plan, TRUTH, tmp_path, text=edited)
    assert r.run.status == "error"
    assert r.run.message.startswith(f"*Wire overspeed* move {k + 1} to (")
    assert "beyond the encoder's max_wire" in r.run.message
    assert r.world.moves == k  # stopped before it moved


@pytest.mark.slow
def test_the_paper_run_waits_its_fixed_settle_first(viper, paper_plan, tmp_path):
    """--settle-s 3 (the paper's wait) then the rule: every reading waited 3 s plus the
    window, and the run takes the paper's time."""
    r = measure_in_twin(viper, paper_plan, TRUTH, tmp_path, options=GenOptions(run=PAPER_RUN))
    settle = {x.settle_s for x in read_log(r.log).readings}
    assert settle == {3.08}
    assert r.world.clock == pytest.approx(run_timeline(viper, paper_plan, PAPER_RUN).total_s, 0.01)


def test_readings_per_point_from_the_noise_model():
    """σ_p² = 0.01² + 0.025488²/12 (does not average), σ_j² = 0.4 × 0.025488² (the ±1-count
    jitter, averages): error² × time per point is least at N = √(σ_j² T / (σ_p² δ)),
    √(2.5986e-4 × 1.2 / (1.5414e-4 × 0.02)) = 10.06 for a 1.2 s move and settle."""
    assert optimal_readings(0.025488) == 10 == DEFAULT_RUN.readings
    assert optimal_readings(0.025488, stop_s=0.3) == 5  # √25.3
    assert optimal_readings(0.001) == 1  # a fine encoder: jitter 0.0006 mm, nothing to average
