"""Identified gravity compliances against the truth: Monte Carlo over random true arms.

Per arm (robot file with ``[calibration] compliances = ["c2", "c3", "c4", "c5"]`` and a
reference gauge, :func:`~wirecal.app.coverage.with_gauge`) and per plan (its shipped plan,
and the plan ``wirecal plan`` designs for that file at the shipped plan's θ0, with the
points for the compliances, :mod:`~wirecal.solver.plan.compliance`): ``--truths`` true
arms (offsets within ±1 deg/mm, compliances uniform in 2–8 µrad/(N·m): issue 30's range,
:data:`~wirecal.formats.truth.TRUE_COMPLIANCE_URAD_PER_NM`), each simulated with a
realistic encoder and the twin's repeatability (0.02 mm, declared in the robot file as
``repeatability_mm``: the zero readings' mean, :mod:`~wirecal.solver.zero_reading`) and
solved as ``wirecal solve`` does (:func:`~wirecal.app.coverage.compliance_trial`); the
same seeds again with a rigid true arm (compliances 0). Printed per arm:

* which compliances the plan identifies, and per identified c_j the share of runs within
  ±10 % of its truth, and the median |error|/σ;
* the geometry's bias: the largest |mean error| / mean σ over the plan's parameters (the
  issue's goal: below 1/3);
* the median tool-point error of targets compensated offline (geometry and identified
  compliances) on the compliant arm, on the rigid one, and their ratio (goal ≤ 1.2), and
  beside it the patch alone (what the controller applies: the sag left in it).

The designed plan's robot time is printed beside that of the plan designed without the
compliances (issue 30: at most 1.25×).

``--payload``: the robot files also give ``[calibration] payload_kg`` (the arm's rated
payload, :data:`RATED_PAYLOAD_KG`, at 50 mm from the flange) and ``rated_payload_kg``,
so ``plan`` adds the payload step when it pays (:mod:`~wirecal.solver.plan.payload`) and
the twin's arm carries the mass in that step.

    python bench/bench_compliance.py [--truths 100] [--arms ur5e viper_s650 abb_irb120]
        [--plans shipped designed] [--payload]
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

from wirecal.app.coverage import ComplianceTrial, compliance_trial, with_gauge  # noqa: E402
from wirecal.app.demo import plan_beside  # noqa: E402
from wirecal.formats.plan_file import load_plan  # noqa: E402
from wirecal.formats.robot_file import robot_from_dict  # noqa: E402
from wirecal.solver.plan.calibration_plan import Plan  # noqa: E402
from wirecal.solver.plan.planner import design  # noqa: E402
from wirecal.solver.robot import Robot  # noqa: E402
from wirecal.solver.simulate import Unmodelled  # noqa: E402

ARMS = ("viper_s650", "ur5e", "abb_irb120")
"""The arms with a shipped plan (the demo's beside each robot file, :func:`plan_beside`)."""

RATED_PAYLOAD_KG = {"viper_s650": 5.0, "ur5e": 5.0, "abb_irb120": 3.0}
"""The arms' rated payloads (data sheets: Adept Viper s650 5 kg maximum; Universal Robots
UR5e 5 kg; ABB IRB 120 3 kg), the payload step's mass in the bench."""

PAYLOAD_COM_MM = [0.0, 0.0, 50.0]
"""The bench's mass's centre from the flange: a plate 50 mm out along the flange axis."""

REPEATABILITY_MM = 0.02
"""The true arms' repeatability (the twin's), declared in the robot file so that the zero
readings are read as what they are (:mod:`~wirecal.solver.zero_reading`)."""


def _arm(arm: str, payload: bool) -> tuple[Robot, Path]:
    folder = Path(__file__).resolve().parents[1] / "examples" / arm
    data = tomllib.loads((folder / "robot.toml").read_text())
    data["calibration"]["compliances"] = ["c2", "c3", "c4", "c5"]
    data["calibration"]["repeatability_mm"] = REPEATABILITY_MM
    if payload:
        data["calibration"]["rated_payload_kg"] = RATED_PAYLOAD_KG[arm]
        data["calibration"]["payload_kg"] = RATED_PAYLOAD_KG[arm]
        data["calibration"]["payload_com_mm"] = PAYLOAD_COM_MM
    plan_path = plan_beside(folder / "robot.toml")
    assert plan_path is not None
    return with_gauge(robot_from_dict(data, str(folder / "robot.toml"))), plan_path


def _report(robot: Robot, on: list[ComplianceTrial], off: list[ComplianceTrial]) -> list[str]:
    ident = sorted({n for r in on for n in r.std if n in robot.compliances})
    lines = [f"  identified: {', '.join(ident) or 'none'}"]
    for n in ident:
        runs = [r for r in on if n in r.estimate]
        rel = np.array([abs(r.estimate[n] - r.truth[n]) / r.truth[n] for r in runs])
        z = np.array([abs(r.estimate[n] - r.truth[n]) / r.std[n] for r in runs])
        lines.append(
            f"  {n}: within ±10 % in {np.mean(rel <= 0.1):.0%} of {len(runs)} runs; "
            f"median |error| {np.median(rel):.1%}; median |error|/σ {np.median(z):.2f}"
        )
    geometry = list(robot.parameters)
    bias = [
        abs(np.mean([r.estimate[n] - r.truth[n] for r in on])) / np.mean([r.std[n] for r in on])
        for n in geometry
    ]
    worst = int(np.argmax(bias))
    comp_on = np.median([r.error_compensated_mm for r in on])
    comp_off = np.median([r.error_compensated_mm for r in off])
    patch_on = np.median([r.error_patch_mm for r in on])
    patch_off = np.median([r.error_patch_mm for r in off])
    lines += [
        f"  geometry bias: largest |mean error|/σ {bias[worst]:.2f} ({geometry[worst]})",
        f"  compensated error (median mm): compliant {comp_on:.4f}, rigid {comp_off:.4f}, "
        f"ratio {comp_on / comp_off:.2f}; patch alone {patch_on:.4f} (compliant), "
        f"{patch_off:.4f} (rigid)",
    ]
    return lines


def _plans(robot: Robot, shipped: Path, which: list[str]) -> list[tuple[str, Plan]]:
    """Return the plans to run: the shipped one and/or one designed for the compliances."""
    plan = load_plan(shipped, robot)
    out = [(shipped.name, plan)] if "shipped" in which else []
    if "designed" in which:
        t0 = time.perf_counter()
        with_c = design(robot, plan.theta0_deg)
        without = design(replace(robot, compliances=(), payload_kg=None), plan.theta0_deg)
        print(
            f"  designed at θ0 of {shipped.name} in {time.perf_counter() - t0:.0f} s: robot time "
            f"{with_c.robot_time_s:.0f} s, {with_c.robot_time_s / without.robot_time_s:.2f}× "
            f"the plan without compliances ({without.robot_time_s:.0f} s)"
        )
        for line in with_c.compliance_lines:
            print(f"    {line}")
        out.append(("designed for the compliances", with_c.plan))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--truths", type=int, default=100)
    ap.add_argument("--arms", nargs="+", default=list(ARMS), choices=list(ARMS))
    ap.add_argument("--plans", nargs="+", default=["shipped", "designed"])
    ap.add_argument("--payload", action="store_true", help="the payload step (rated payload)")
    args = ap.parse_args()
    for arm in args.arms:
        robot, plan_path = _arm(arm, args.payload)
        extra = f", payload step {robot.payload_kg:g} kg" if args.payload else ""
        print(f"{arm}, gauge{extra}, {args.truths} truths (2–8 µrad/(N·m)):")
        for name, plan in _plans(robot, plan_path, args.plans):
            t0 = time.perf_counter()
            twin = Unmodelled(REPEATABILITY_MM, 0.0)
            runs = {
                compliant: [
                    compliance_trial(robot, plan, seed, twin, compliant)
                    for seed in range(1, args.truths + 1)
                ]
                for compliant in (True, False)
            }
            print(f" {name} ({plan.n_points} points):")
            for line in _report(robot, runs[True], runs[False]):
                print(line)
            print(f"  {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
