"""The error budget's 95 % bound against the truth: its coverage over simulated calibrations.

The Viper s650 and the corrected paper plan; each calibration a realistic run
(:mod:`wirecal.app.coverage`: offsets within ±1 deg/mm, the encoder's scale drawn within
its 500 ppm tolerance, 0.5 K of warming, reading noise σ 0.01 mm) solved as ``wirecal
solve`` does; with the twin's unmodelled errors (repeatability 0.02 mm, gravity sag
0.01 deg/m) unless ``--no-unmodelled``. Without a gauge (the robot file as shipped) and with
one (nests 500 mm apart, certified to 0.002 mm, seated 3 times). With ``--no-unmodelled`` the
robot file declares no gravity sag (``gravity_sag_deg_per_m = 0``), so the budget's other
terms are checked alone. Per case: how many true errors the bound covers, with the Wilson 95 %
interval; how many exceed the budget's mean; the largest ratio of error to bound.

``--compliance ARM`` (issue 30) checks the bounds from identified compliances instead: the
arm's robot file with ``[calibration] compliances = ["c2", "c3", "c4", "c5"]`` and
``repeatability_mm = 0.02`` (the twin's arm repeats to it, the solver reads the zero
readings by it) and its shipped plan (the Viper: the corrected paper plan), gauge off/on ×
compliance off (a rigid true arm) / on (c2..c5 drawn within 2–8 µrad/(N·m), the range the
budget's prior states, :data:`~wirecal.solver.compliance.COMPLIANCE_RANGE_URAD_PER_NM`); no assumed
sag. Per case: the coverage of bound95_mm over the patch's error (geometry only, the sag
left in it) and of bound95_compensated_mm over the compensated error, the median of
bound/error, and its floor: the errors' 95 % point over their median, the least median
ratio any bound that is the same for every run could have while covering 95 % of them (a
bound that covers must reach the 95 % point; where one term with a fixed distribution
dominates, as the scale within its tolerance without a gauge, no honest bound gets below
it). On the rigid rows, ``shared``: the compliant arm's 95 % point over the rigid arm's
median (compensated errors), the least median ratio on the rigid arm of a bound that
covers both when the readings cannot tell the two arms apart. ``c err/σ``: the identified
compliances' median |ĉ − c|/σ, σ the joint estimate's (the patch's ``[compliance]`` std; about
0.67, the half-normal's median, when it is honest), ``c cover``: how many of them ĉ ± 1.96 σ
covers. ``post σ``: the unidentified
compliance the readings narrowed most, its posterior σ over its prior's (1: they said
nothing). The header counts the runs whose true scale lies beyond 95 % of its tolerance:
without a gauge, where the scale dominates, a bound at the scale's 95 % point misses about
those (7 of the first 100 seeds, where 5 are expected). Several arms in one run:
``--compliance ur5e viper_s650 abb_irb120``.

The encoder's scenarios (issue 30's outside check; with ``--compliance`` only): ``--drift
MM_PER_H`` drifts the zero readings by that much (the realistic encoder's is none),
``--paper-run`` runs the plan at the paper's settings (20 % speed, 3 s settle: a run two
to three times longer, so the zero readings tell the drift about four times better),
``--scale-ppm PPM`` sets the encoder's true scale error instead of drawing it within the
tolerance (``--scale-ppm 500``: at the tolerance's edge).

Any robot file and plan: give ``--compliance`` the robot file's path instead of an arm's
name; the plan is the one beside it (the demo's rule, :func:`plan_beside`: ``plan.toml``
first), and the file is taken as above (``compliances`` set to c2..c5 whatever it lists,
``repeatability_mm`` 0.02; its other keys, a payload step's mass among them, as they are).
The payload plans (issue 30's payload step, designed for c2, c3 with a mass 50 mm out from
the flange: 3.5 kg on the UR5e and the Viper, 1.5 kg of their 5 kg left for the tool; 2.9 kg
on the IRB 120, with its 0.1 kg tool its rated 3 kg):
``--compliance tests/data/payload_ur5e/robot.toml tests/data/payload_viper_s650/robot.toml
tests/data/payload_abb_irb120/robot.toml``.

``--cost`` (issue 34: the quick test loop's solves) prints instead the CPU of ``solve`` of
the Viper's paper plan (a simulated log) and of the same log again (the tests solve the same
logs many times over: the budgets' bounds and factorisations are kept by their inputs), and
of a UR5e with identified compliances; by the code now and, with ``--before CHECKOUT``, by
the code there, interleaved run by run, with the ratio and whether the budgets are the same
bit for bit (:func:`bench_fit.compare_trees`); and the CPU of drawing each arm's bounds
again, ten times each (the 95 % quantile alone, not kept: :func:`wirecal.solver.bound._bound_mm`;
the UR5e's with the compliances' box-restricted draws), and whether they are the same bit
for bit.

    python bench/bench_bound.py [--trials 300] [--no-unmodelled]
    python bench/bench_bound.py --compliance ur5e viper_s650 abb_irb120 [--trials 40]
    python bench/bench_bound.py --compliance tests/data/payload_*/robot.toml [--trials 40]
    python bench/bench_bound.py --compliance viper_s650 --drift 1 [--paper-run] [--scale-ppm 500]
    python bench/bench_bound.py --cost [--before CHECKOUT] [--runs 3]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import time  # noqa: E402
import tomllib  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from bench_fit import compare_trees  # noqa: E402 - a sibling script's runner

from wirecal.app.coverage import (  # noqa: E402
    Scenario,
    compliance_trial,
    trial,
    wilson,
    with_gauge,
)
from wirecal.app.demo import PLANS, example_files, plan_beside  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot, robot_from_dict  # noqa: E402
from wirecal.solver.bound import BOUND_PROBABILITY  # noqa: E402
from wirecal.solver.compliance import COMPLIANCE_RANGE_URAD_PER_NM  # noqa: E402
from wirecal.solver.plan.calibration_plan import Plan  # noqa: E402
from wirecal.solver.run_parameters import PAPER_RUN  # noqa: E402
from wirecal.solver.simulate import Unmodelled, realistic_encoder  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=300)
    ap.add_argument("--no-unmodelled", action="store_true")
    ap.add_argument(
        "--compliance",
        nargs="+",
        metavar="ARM_OR_ROBOT_FILE",
        help=f"the compliance cases' arms ({', '.join(ARMS)}) or robot files",
    )
    ap.add_argument("--drift", type=float, default=0.0, help="zero drift, mm/h")
    ap.add_argument("--paper-run", action="store_true", help="20 % speed, 3 s settle")
    ap.add_argument("--scale-ppm", type=float, help="the true scale's error (ppm)")
    ap.add_argument("--cost", action="store_true", help="the CPU of solving (docstring)")
    ap.add_argument("--before", type=Path, help="a checkout of the code before (--cost)")
    ap.add_argument("--runs", type=int, default=3, help="runs per tree (--cost)")
    args = ap.parse_args()
    if args.cost:
        print(f"CPU of solving (medians of {args.runs} runs, one thread)")
        compare_trees(COST_CHILD, ["examples"], args.before, args.runs)
        return
    if args.compliance:
        run = PAPER_RUN if args.paper_run else Scenario().run
        scenario = Scenario(args.drift, run, args.scale_ppm)
        for arm in args.compliance:
            compliance_cases(arm, args.trials, scenario)
        return
    files = example_files()
    without = load_robot(files["robot"])
    gauge = with_gauge(without)
    plan = load_plan(files["plan"], without)
    unmodelled = None if args.no_unmodelled else Unmodelled()
    if unmodelled is None:  # the robot file then says so: the budget assumes no sag either
        without, gauge = (replace(r, gravity_sag_deg_per_m=0.0) for r in (without, gauge))
    print(
        f"{args.trials} calibrations per case; unmodelled errors "
        f"{'off' if unmodelled is None else 'on'}; true error: mean over 1000 configurations"
    )
    print(
        f"{'gauge':<7}{'covered':>9}{'coverage':>10}{'95 % interval':>17}{'> mean':>8}"
        f"{'error mm':>10}{'mean mm':>9}{'bound mm':>10}{'error/bound max':>17}{'s':>5}"
    )
    for name, robot in (("no", without), ("yes", gauge)):
        t0 = time.perf_counter()
        runs = [trial(robot, plan, seed, unmodelled) for seed in range(1, args.trials + 1)]
        err = np.array([r.error_mm for r in runs])
        mean = np.array([r.mean_mm for r in runs])
        bound = np.array([r.bound_mm for r in runs])
        k, n = int(np.sum(err <= bound)), len(runs)
        lo, hi = wilson(k, n)
        print(
            f"{name:<7}{k:>5}/{n:<3}{k / n:10.1%}{f'{lo:.1%}–{hi:.1%}':>17}"
            f"{np.mean(err > mean):8.0%}{err.mean():10.4f}{mean.mean():9.4f}{bound.mean():10.4f}"
            f"{np.max(err / bound):17.2f}{time.perf_counter() - t0:5.0f}"
        )


REPEATABILITY_MM = 0.02
"""The compliance cases' arm repeatability: declared in the robot file, so the twin's arm
repeats to it and the solver reads the zero readings by it (:mod:`~wirecal.solver.zero_reading`)."""

ARMS = ("viper_s650", "ur5e", "abb_irb120")
"""The arms with a shipped plan (the demo's beside each robot file, :func:`plan_beside`)."""


COST_CHILD = """
import hashlib, json, os, sys, time
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"
from dataclasses import replace
from pathlib import Path
import numpy as np
from wirecal.formats.log import parse_log
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import random_errors
from wirecal.solver.log.measurements import check_log
from wirecal.solver import bound
from wirecal.solver.solve import solve
examples = Path(sys.argv[1])
figures, outputs = {}, {}
asked, drawn = {}, bound._bound_mm
def kept_inputs(*args):
    asked.setdefault(arm, []).append(args)
    return drawn(*args)
bound._bound_mm = kept_inputs
def timed(name, robot, plan, m):
    cpu = time.process_time()
    result = solve(robot, plan, m)
    figures[name] = time.process_time() - cpu
    outputs[name] = hashlib.sha256(repr(sorted(
        (k, b.as_json()) for k, b in result.budgets.items())).encode()).hexdigest()
for arm, plan_file in (("viper_s650", "paper_plan.toml"), ("ur5e", "plan.toml")):
    robot = load_robot(examples / arm / "robot.toml")
    if arm == "ur5e":
        robot = replace(robot, compliances=("c2", "c3"), repeatability_mm=0.02)
    plan = load_plan(examples / arm / plan_file, robot)
    truth = random_errors(robot, 1.0, np.random.default_rng(5))
    m = check_log(parse_log(simulate_log(robot, plan, truth, seed=5), "s.csv"), plan, robot)
    timed(f"solve, {arm}", robot, plan, m)
    timed(f"solve, {arm}, the same log again", robot, plan, m)
for arm, each in asked.items():
    cpu = time.process_time()
    again = [drawn(*args) for _ in range(10) for args in each]
    name = f"{arm}: its solve's {len(each)} bounds drawn 10 times"
    figures[name] = time.process_time() - cpu
    outputs[name] = hashlib.sha256(repr(again).encode()).hexdigest()
print(json.dumps({"figures": figures, "outputs": outputs}))
"""


def robot_path(arm: str) -> Path:
    """Return the robot file of ``arm``: a shipped arm's (:data:`ARMS`) or the path given."""
    if arm in ARMS:
        return Path(__file__).resolve().parents[1] / "examples" / arm / "robot.toml"
    return Path(arm)


def compliance_cases(arm: str, trials: int, scenario: Scenario) -> None:
    """Print coverage and median bound/error, gauge × compliance (module docstring)."""
    path = robot_path(arm)
    if not path.is_file():
        raise SystemExit(f"{arm}: neither one of {', '.join(ARMS)} nor a robot file")
    data = tomllib.loads(path.read_text())
    calibration = data.setdefault("calibration", {})
    calibration["compliances"] = ["c2", "c3", "c4", "c5"]
    calibration["repeatability_mm"] = REPEATABILITY_MM  # the twin's arm's, declared
    without = robot_from_dict(data, str(path))
    plan_path = plan_beside(path)
    if plan_path is None:
        raise SystemExit(f"{path}: no plan beside it (one of {', '.join(PLANS)})")
    plan = load_plan(plan_path, without)
    tol = without.encoder.scale_tolerance_ppm
    beyond = sum(
        abs(realistic_encoder(without.encoder, np.random.default_rng([s, 4])).scale_ppm)
        > BOUND_PROBABILITY * tol
        for s in range(1, trials + 1)
    )
    print(
        f"{arm}, {plan_path.name}{_payload(plan)}: {trials} calibrations per case; "
        f"repeatability 0.02 mm; "
        f"true scale beyond {BOUND_PROBABILITY:.0%} of its ±{tol:g} ppm in {beyond} runs"
        + _scenario(scenario)
    )
    print(
        f"{'gauge':<6}{'compl.':<7}{'ident.':<8}{'patch: cover':>13}{'bound/err':>10}{'floor':>6}"
        f"{'comp.: cover':>13}{'bound/err':>10}{'floor':>6}{'shared':>7}{'err mm':>8}"
        f"{'c err/σ':>8}{'c cover':>8}{'post σ':>9}{'s':>5}"
    )
    for gauge_name, robot in (("no", without), ("yes", with_gauge(without))):
        cases = {}
        for compliant in (True, False):
            t0 = time.perf_counter()
            runs = [
                compliance_trial(robot, plan, seed, Unmodelled(None, 0.0), compliant, scenario)
                for seed in range(1, trials + 1)
            ]
            cases[compliant] = (runs, time.perf_counter() - t0)
        bent = np.array([r.error_compensated_mm for r in cases[True][0]])
        for compliant in (False, True):
            runs, seconds = cases[compliant]
            head = f"{gauge_name:<6}{'on' if compliant else 'off':<7}"
            print(head + _row(robot, runs, None if compliant else bent) + f"{seconds:5.0f}")


def _scenario(scenario: Scenario) -> str:
    """Return the header's note of the encoder's scenario (none for the default)."""
    out = f"; zero drift {scenario.drift_mm_per_h:g} mm/h" if scenario.drift_mm_per_h else ""
    out += "; the paper's run (20 % speed, 3 s settle)" if scenario.run == PAPER_RUN else ""
    if scenario.scale_ppm is not None:
        out += f"; true scale {scenario.scale_ppm:+g} ppm (the 'beyond' count is of drawn ones)"
    return out


def _payload(plan: Plan) -> str:
    """Return the header's note of the plan's payload step (mass, points), or nothing."""
    step = plan.payload_step
    return (
        ""
        if step is None
        else f" (payload step {step.payload_kg:g} kg, {len(step.points_deg)} points)"
    )


def _row(robot, runs: list, bent: np.ndarray | None) -> str:
    """Return one case's figures (module docstring); ``bent``: the compliant arm's errors."""
    ep = np.array([r.error_patch_mm for r in runs])
    ec = np.array([r.error_compensated_mm for r in runs])
    bp = np.array([r.bound_mm for r in runs])
    bc = np.array([r.bound_compensated_mm for r in runs])
    ident = sorted({n for r in runs for n in r.std if n in robot.compliances})
    z = [
        abs(r.estimate[n] - r.truth[n]) / r.std[n]
        for r in runs
        for n in ident
        if np.isfinite(r.std[n]) and r.std[n] > 0
    ]
    post = {n: np.median([r.posterior[n][1] for r in runs]) for n in runs[0].posterior}
    post = {n: sd / PRIOR_SIGMA for n, sd in post.items()}
    told = min(post, key=post.__getitem__) if post else "-"
    shared = np.quantile(bent, 0.95) / np.median(ec) if bent is not None else np.nan
    return (
        f"{','.join(ident) or '-':<8}"
        f"{np.mean(ep <= bp):13.0%}{np.median(bp / ep):10.2f}{floor(ep):6.2f}"
        f"{np.mean(ec <= bc):13.0%}{np.median(bc / ec):10.2f}{floor(ec):6.2f}{shared:7.2f}"
        f"{np.median(ec):8.4f}{np.median(z) if z else np.nan:8.2f}"
        f"{np.mean(np.array(z) <= 1.96) if z else np.nan:8.0%}"
        f"{told:>4}{post.get(told, np.nan):5.2f}"
    )


PRIOR_SIGMA = (COMPLIANCE_RANGE_URAD_PER_NM[1] - COMPLIANCE_RANGE_URAD_PER_NM[0]) / 12**0.5
"""σ of an unidentified compliance's prior, uniform over its stated range."""


def floor(error_mm: np.ndarray) -> float:
    """Return the least median bound/error of a bound the same for every run that covers 95 %.

    Such a bound is at least the errors' 95 % point; its median ratio is that over their
    median (module docstring): the ratio the runs' own spread allows.
    """
    return float(np.quantile(error_mm, 0.95) / np.median(error_mm))


if __name__ == "__main__":
    main()
