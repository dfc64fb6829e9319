"""The measurement log reader: one test per problem it must catch, each asserting the
message; partial logs readable; the counter wrap handled."""

from __future__ import annotations

import re

import numpy as np
import pytest

from wirecal.formats.log import format_row, parse_log
from wirecal.formats.simulated_log import simulate_log, simulated_log_text
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.log.readings import Reading
from wirecal.solver.log.rows import Tolerances
from wirecal.solver.simulate import Faults, simulate_run
from wirecal.solver.solve import solve

from .conftest import TABLE5 as TRUTH


@pytest.fixture(scope="module")
def log_text(viper, paper_plan):
    return simulate_log(viper, paper_plan, TRUTH, seed=5, counter_start=1000.0)


def measure(text, viper, plan, **kw):
    return check_log(parse_log(text, "run.csv"), plan, viper, **kw)


def problems(text, viper, plan, **kw):
    with pytest.raises(WirecalError) as info:
        measure(text, viper, plan, **kw)
    return info.value.problems


def lines(text):
    return text.splitlines()


def line_no(text, prefix):
    return next(i for i, line in enumerate(lines(text), 1) if line.startswith(prefix))


def replace_line(text, prefix, new):
    return "\n".join(new if line.startswith(prefix) else line for line in lines(text)) + "\n"


def test_a_row_is_written_at_the_logs_resolution():
    row = Reading("point", 2, 3, np.arange(1.0, 7.0), 1234.5, 10, 1.0, 0, 1.25, 0.5)
    assert format_row(row) == (
        "point,2,3,1.0000,2.0000,3.0000,4.0000,5.0000,6.0000,1234.5000,10,1,1.250,0.500"
    )


def test_a_row_without_times_is_refused():
    row = Reading("zero", 1, 0, np.zeros(6), 0.0, 10, 0.0, 0)  # as a version 1 log reads
    with pytest.raises(WirecalError, match="version 2 log row needs t_s and settle_s"):
        format_row(row)


def test_the_simulation_returns_readings_that_the_log_writes(viper, paper_plan, log_text):
    run = simulate_run(viper, paper_plan, TRUTH, seed=5, counter_start=1000.0)
    assert (run.robot, run.plan) == (viper.name, paper_plan.fingerprint())
    assert run.mm_per_count == viper.encoder.mm_per_count
    n_points = len(paper_plan.all_points()[0])
    n_zeros = len(paper_plan.steps) + 1  # each step's and the closing one
    assert len(run.readings) == n_points + n_zeros
    assert [r.kind for r in run.readings].count("zero") == n_zeros
    assert simulated_log_text(run) == log_text
    assert np.isfinite(measure(log_text, viper, paper_plan).distance_mm).all()


def test_a_stopped_run_returns_the_readings_before_the_stop(viper, paper_plan):
    whole = simulate_run(viper, paper_plan, TRUTH, seed=5, counter_start=1000.0)
    stopped = simulate_run(
        viper, paper_plan, TRUTH, seed=5, counter_start=1000.0, faults=Faults(stop_after=7)
    )
    assert len(stopped.readings) == 7
    assert [r.counts for r in stopped.readings] == [r.counts for r in whole.readings[:7]]


def test_clean_log(viper, paper_plan, log_text):
    m = measure(log_text, viper, paper_plan)
    assert m.missing == ()
    assert m.present.all()
    assert len(m.distance_mm) == 69
    assert m.missing_text() == "none"
    assert np.all(m.distance_mm > 20)
    assert np.all(m.distance_mm < 650)
    assert set(m.zero_drift_mm) == set(range(1, 12))  # 11: the closing zero


def test_counter_wrap_gives_the_same_lengths(viper, paper_plan):
    near_wrap = simulate_log(viper, paper_plan, TRUTH, seed=5, counter_start=2**23 - 5000)
    far = simulate_log(viper, paper_plan, TRUTH, seed=5, counter_start=1000.0)
    counts = [float(line.split(",")[9]) for line in lines(near_wrap) if line[:1] in "zp"]
    assert min(counts) < 0 < max(counts)  # the counter did wrap
    np.testing.assert_allclose(
        measure(near_wrap, viper, paper_plan).distance_mm,
        measure(far, viper, paper_plan).distance_mm,
        atol=1e-9,
    )


def test_wrong_version(viper, paper_plan, log_text):
    text = log_text.replace("# wirecal-log 2", "# wirecal-log 3", 1)
    with pytest.raises(
        WirecalError,
        match=r"run\.csv:1: log version '3'; this wirecal reads version 1 or 2",
    ):
        parse_log(text, "run.csv")


def as_version_1(text: str) -> str:
    """The log as wirecal 0.1 wrote it: version 1, without the t_s and settle_s columns."""
    out = []
    for line in lines(text):
        if line.startswith("# wirecal-log"):
            line = "# wirecal-log 1"
        elif not line.startswith("#"):
            line = ",".join(line.split(",")[:12])
        out.append(line)
    return "\n".join(out) + "\n"


def test_version_1_log_still_solves(viper, paper_plan, log_text):
    old = parse_log(as_version_1(log_text), "run.csv")
    assert old.version == 1
    assert all(r.t_s is None and r.settle_s is None for r in old.readings)
    new = measure(log_text, viper, paper_plan)
    m = check_log(old, paper_plan, viper)
    np.testing.assert_array_equal(m.distance_mm, new.distance_mm)
    for method in ("joint", "stepwise"):
        np.testing.assert_array_equal(
            solve(viper, paper_plan, m).estimates[method].values,
            solve(viper, paper_plan, new).estimates[method].values,
        )


def test_version_2_times_follow_the_run(viper, paper_plan, log_text):
    log = parse_log(log_text, "run.csv")
    t = np.array([r.t_s for r in log.readings])
    assert log.version == 2
    assert np.all(np.diff(t) > 0.5)  # a move's ramp at least between two readings
    settle = np.array([r.settle_s for r in log.readings])
    assert np.all((settle >= 0.08) & (settle < 0.5))  # the settle rule's window at least
    # first zero: the move to θ0 from θ0 (0.5 s ramp), nothing to settle: the window
    assert t[0] == pytest.approx(0.58, abs=1e-9)


@pytest.mark.parametrize(
    ("column", "value", "message"),
    [(12, "-0.5", "t_s -0.5 cannot be negative"), (13, "abc", "settle_s 'abc' is not a number")],
)
def test_bad_time_fields(log_text, column, value, message):
    n = line_no(log_text, "point,1,2,")
    cells = lines(log_text)[n - 1].split(",")
    cells[column] = value
    text = replace_line(log_text, "point,1,2,", ",".join(cells))
    with pytest.raises(WirecalError, match=rf"run\.csv:{n}: {message}"):
        parse_log(text, "run.csv")


def test_foreign_file(viper, paper_plan):
    with pytest.raises(
        WirecalError,
        match=r"run\.csv:1: not a wirecal log: the first line "
        "must be '# wirecal-log 2'",
    ):
        parse_log("time,value\n1,2\n", "run.csv")


def test_wrong_columns(log_text):
    text = log_text.replace("counts,samples,spread", "counts,spread", 1)
    with pytest.raises(WirecalError, match=r"run\.csv:6: columns are "):
        parse_log(text, "run.csv")


def test_fingerprint_mismatch_refused_unless_accepted(viper, paper_plan, printed_plan, log_text):
    got = problems(log_text, viper, printed_plan)
    assert len(got) == 1
    assert "the log was taken with another plan; use that plan, or --accept-foreign" in got[0]
    # --accept-foreign reads it anyway (against the printed plan the step-7 joints then differ)
    forced = problems(log_text, viper, printed_plan, accept_foreign=True)
    assert [p.split(": ", 1)[1] for p in forced] == [
        f"joint 2 is -{a}.0000 deg; the plan says -110 (tolerance 0.05): the robot was not "
        "where the plan puts it"
        for a in (115, 120, 125, 130, 135)
    ]


def test_missing_points_partial_log_readable(viper, paper_plan):
    text = simulate_log(viper, paper_plan, TRUTH, seed=5, faults=Faults(stop_after=40))
    m = measure(text, viper, paper_plan)
    assert m.present.sum() == 40 - 5  # 40 readings, 5 of them zeros
    assert m.missing_text() == "step 5 points 2–6; steps 6–10 (all points)"


def test_truncated_last_line_is_a_note(viper, paper_plan):
    text = simulate_log(
        viper, paper_plan, TRUTH, seed=5, faults=Faults(stop_after=20, truncate_last=True)
    )
    m = measure(text, viper, paper_plan)
    assert m.notes == (
        f"run.csv:{len(lines(text))}: incomplete last line ignored (the run "
        "stopped while writing it)",
    )
    assert (3, 5) in m.missing
    assert (3, 4) not in m.missing


def test_truncated_line_in_the_middle_is_an_error(viper, paper_plan, log_text):
    n = line_no(log_text, "point,2,3,")
    text = replace_line(log_text, "point,2,3,", "point,2,3,0.0000,-90.0000")
    with pytest.raises(WirecalError, match=rf"run\.csv:{n}: has 5 fields; expected 14"):
        parse_log(text, "run.csv")


def test_duplicate_point(viper, paper_plan, log_text):
    dup = next(line for line in lines(log_text) if line.startswith("point,3,2,"))
    text = log_text + dup + "\n"
    first = line_no(log_text, "point,3,2,")
    assert problems(text, viper, paper_plan) == [
        f"run.csv:{len(lines(text))}: duplicate point reading of step 3 point 2 (first on "
        f"line {first}); keep one run per log"
    ]


def test_extra_point(viper, paper_plan, log_text):
    row = next(line for line in lines(log_text) if line.startswith("point,1,6,"))
    text = log_text + row.replace("point,1,6,", "point,1,7,") + "\n"
    assert problems(text, viper, paper_plan) == [
        f"run.csv:{len(lines(text))}: step 1 has 6 points; point 7 is not in the plan"
    ]


def test_step_beyond_plan(viper, paper_plan, log_text):
    """Step 11 is the closing zero's; a zero of step 12 or a point of step 11 is not."""
    for row, step in (("zero,12,0", 12), ("point,11,1", 11)):
        text = log_text + row + ",0,-90,210,-90,0,-90,1000,10,0,400.000,3.000\n"
        assert problems(text, viper, paper_plan) == [
            f"run.csv:{len(lines(text))}: step {step} is not in the plan (it has 10 steps; "
            "the closing zero reading is logged as step 11)"
        ]


def test_closing_zero_required_unless_partial(viper, paper_plan, log_text):
    """Without the closing zero the last step is unchecked: solve refuses the log, naming
    the step to repeat, and --partial accepts it."""
    text = "".join(line + "\n" for line in lines(log_text) if not line.startswith("zero,11,"))
    m = measure(text, viper, paper_plan)
    assert not m.closed
    assert not m.complete
    assert not m.missing
    assert m.missing_text() == (
        "the closing zero reading at θ0 after step 10 (without it a wire slip during "
        "step 10 goes unseen: repeat step 10)"
    )
    with pytest.raises(WirecalError, match="the log is incomplete: missing the closing zero"):
        solve(viper, paper_plan, m, methods=("stepwise",))
    assert solve(viper, paper_plan, m, methods=("stepwise",), partial=True).estimates


def test_slip_in_the_last_step_is_caught_by_the_closing_zero(viper, paper_plan):
    """A 3 mm slip during step 10 used to move a1 by 1.6 mm with a normal residual; now
    the closing zero is 3 mm from the first and the log is refused, naming step 10."""
    text = simulate_log(viper, paper_plan, TRUTH, seed=5, faults=Faults(slip=(10, 3.0)))
    with pytest.raises(WirecalError) as e:
        measure(text, viper, paper_plan)
    (problem,) = e.value.problems
    drift = float(re.search(r"the closing zero reading is ([-+.\d]+) mm", problem).group(1))
    assert drift == pytest.approx(3.0, abs=0.05)  # the slip, up to the reading noise
    assert "remount at θ0 and repeat from step 10" in problem


def test_joints_differ_from_plan(viper, paper_plan, log_text):
    n = line_no(log_text, "point,4,2,")
    old = next(line for line in lines(log_text) if line.startswith("point,4,2,"))
    cells = old.split(",")
    cells[6] = "10.2000"  # j4: the plan says 10
    text = replace_line(log_text, "point,4,2,", ",".join(cells))
    assert problems(text, viper, paper_plan) == [
        f"run.csv:{n}: joint 4 is 10.2000 deg; the plan says 10 (tolerance 0.05): the robot "
        "was not where the plan puts it"
    ]
    assert measure(text, viper, paper_plan, tol=Tolerances(joint_deg=0.5)).present.all()


def test_non_numeric_counts(viper, paper_plan, log_text):
    n = line_no(log_text, "point,2,1,")
    old = next(line for line in lines(log_text) if line.startswith("point,2,1,"))
    cells = old.split(",")
    cells[9] = "ERR"
    with pytest.raises(WirecalError, match=rf"run\.csv:{n}: counts 'ERR' is not a number"):
        parse_log(replace_line(log_text, "point,2,1,", ",".join(cells)), "run.csv")


def test_distance_beyond_range(viper, paper_plan, log_text):
    n = line_no(log_text, "point,6,5,")
    old = next(line for line in lines(log_text) if line.startswith("point,6,5,"))
    cells = old.split(",")
    cells[9] = f"{float(cells[9]) + 30000:.4f}"  # +765 mm: beyond 1250 mm
    got = problems(replace_line(log_text, "point,6,5,", ",".join(cells)), viper, paper_plan)
    assert len(got) == 1
    assert got[0].startswith(f"run.csv:{n}: wire length ")
    assert got[0].endswith("mm is beyond the encoder's range 1250 mm")


def test_large_spread(viper, paper_plan, log_text):
    n = line_no(log_text, "point,8,3,")
    old = next(line for line in lines(log_text) if line.startswith("point,8,3,"))
    cells = old.split(",")
    cells[11] = "12"
    assert problems(replace_line(log_text, "point,8,3,", ",".join(cells)), viper, paper_plan) == [
        f"run.csv:{n}: spread of 10 samples is 12 counts (0.306 mm > 0.1 mm): the robot was "
        "still moving; lengthen the settle time and repeat step 8"
    ]


def test_wire_slip_names_the_step_to_repeat(viper, paper_plan):
    text = simulate_log(viper, paper_plan, TRUTH, seed=5, faults=Faults(slip=(4, 0.8)))
    got = problems(text, viper, paper_plan)
    n = line_no(text, "zero,5,")
    assert got[0].startswith(f"run.csv:{n}: zero reading at step 5 is +0.")
    assert got[0].endswith(
        "the wire slipped or the encoder moved after the zero of step 4; "
        "remount at θ0 and repeat from step 4"
    )


def test_negative_distance_points_at_the_sign(viper, paper_plan, log_text):
    text = log_text.replace("# mm_per_count: 0.025488", "# mm_per_count: -0.025488")
    got = problems(text, viper, paper_plan)
    assert len(got) == 1  # one problem for every negative length (issue 35 NU02)
    assert "points read negative wire lengths" in got[0]
    assert "the sign of mm_per_count is wrong, or the logged counts wrap sooner" in got[0]


def test_missing_header_and_zero(viper, paper_plan, log_text):
    text = "\n".join(line for line in lines(log_text) if not line.startswith("# plan:")) + "\n"
    with pytest.raises(WirecalError, match=r"run\.csv:\d+: header '# plan: …' is missing"):
        parse_log(text, "run.csv")
    no_zero = "\n".join(line for line in lines(log_text) if not line.startswith("zero,")) + "\n"
    got = problems(no_zero, viper, paper_plan)
    assert got == ["run.csv: no zero reading: the log must start with the zero reading at θ0"]
