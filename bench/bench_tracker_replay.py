"""Public laser-tracker data through one wire: held-out 3-D RMS of four calibrations.

Per public data set (read from ``--data DIR``, else ``$WIRECAL_TRACKER_DATA``, else
``../shared/data/tracker`` beside the clone: one folder per set, as
tests/data/tracker/<set>/PUBLISHED.md says where each is published; the robot files are in
tests/data/tracker/<set>/), or any
table with columns j1…jn (degrees) and x, y, z (mm) with ``--robot R --table T``: over 3 seeds, a
random 50/50 split; from the training half ``wirecal plan --pool``'s planner chooses θ0
and at most 60 poses; on them the nominal model (tool point and base frame fitted), the
3-D tracker calibration, and one wire from the anchor at θ0 (readings: the distance to
the measured point, rounded to the encoder's count, unknown zero) identified by
``wirecal fit``'s estimator (:mod:`wirecal.solver.tracker_replay`). Each is judged on the
held-out half after a rigid registration. Prints per set the medians over the seeds and
the wire's ratio to the tracker calibration; ``--json`` prints them as JSON (keys
``nominal_mm``, ``tracker_mm``, ``wire_mm``, ``wire_compliance_mm``, ``anchor_mm``).

``wire_compliance_mm``: the same readings refitted with the compliances (issue 30's model)
among the robot file's ``[calibration] compliances`` that they identify; null for a robot
file that asks none.

    python bench/bench_tracker_replay.py [--data DIR] [--set ur10_ipa ...]
        [--robot R --table T.csv] [--seeds 3] [--points 60] [--json]

A set asked for and not found exits 2 naming the folder, the missing files and how to get
them.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.solver.errors import WirecalError  # noqa: E402
from wirecal.solver.fit import point_model  # noqa: E402
from wirecal.solver.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.formats.tracker_sets import (  # noqa: E402
    SET_FILES,
    missing_set,
    read_tracker,
    tracker_data_dir,
)
from wirecal.solver.kinematics import tool_position  # noqa: E402
from wirecal.solver.params import TOOL_NAMES  # noqa: E402
from wirecal.solver.tracker_fit import calibrate  # noqa: E402
from wirecal.solver.tracker_replay import replay  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "tests" / "data" / "tracker"
SETS = {
    "UR10 IPA B (joint configurations)": (
        "ur10_ipa",
        "ur10_ipa/series_b_joint_configurations.csv.gz",
    ),
    "UR10 IPA C (random poses)": ("ur10_ipa", "ur10_ipa/series_c_random_poses.csv.gz"),
    "UR10 IPA D (ISO cubes)": ("ur10_ipa", "ur10_ipa/series_d_iso_cubes.csv.gz"),
    "UR5 Tsinghua grid": ("ur5_jacobi", "ur5_jacobi/ur5_grid.csv.gz"),
    "WAM (7 axes) Tsinghua grid": ("wam_jacobi", "wam_jacobi/wam_grid.csv.gz"),
}
# The Tsinghua sets' own test: calibrate on the grid, test on the 20 random poses (the
# thesis's abstract, quoted in the data set's README: mean absolute position error).
PUBLISHED = {
    "UR5": (
        "ur5_jacobi",
        "ur5_jacobi/ur5_grid.csv.gz",
        "ur5_jacobi/ur5_random.csv",
        2.5664,
        0.1549,
    ),
    "WAM": (
        "wam_jacobi",
        "wam_jacobi/wam_grid.csv.gz",
        "wam_jacobi/wam_random.csv",
        17.7661,
        2.9178,
    ),
}


def run_set(robot_path: Path, table_path: Path, seeds: int, points: int) -> dict:
    """Return one set's medians over the seeds and each seed's figures."""
    robot, table = load_robot(robot_path), read_tracker(table_path)
    runs = [replay(robot, table, seed=s, points=points) for s in range(seeds)]

    def median(key: str) -> float | None:
        values = [getattr(r, key) for r in runs]
        return None if None in values else float(np.median(values))

    return {
        "robot": str(
            robot_path.relative_to(ROOT) if robot_path.is_relative_to(ROOT) else robot_path
        ),
        "table": str(
            table_path.relative_to(ROOT) if table_path.is_relative_to(ROOT) else table_path
        ),
        "rows": len(table.q_deg),
        "points": runs[0].points,
        "nominal_mm": median("nominal_mm"),
        "tracker_mm": median("tracker_mm"),
        "wire_mm": median("wire_mm"),
        "wire_compliance_mm": median("wire_compliance_mm"),
        "compliances": [list(r.compliances) for r in runs],
        "anchor_mm": [r.anchor_mm.round(3).tolist() for r in runs],
        "anchor_tracker_mm": [r.anchor_tracker_mm.round(3).tolist() for r in runs],
        "theta0_deg": [r.theta0_deg.round(3).tolist() for r in runs],
        "per_seed": {
            key: [None if getattr(r, key) is None else round(getattr(r, key), 4) for r in runs]
            for key in ("nominal_mm", "tracker_mm", "wire_mm", "wire_compliance_mm")
        },
        "wire_parameters": [list(r.wire_parameters) for r in runs],
    }


def published_test(data: Path, arm: str, grid: str, test: str) -> dict:
    """Return the mean 3-D error on the test poses: as measured, nominal, tracker-calibrated.

    Calibrated on every grid pose; the base frame the calibration found is kept (no second
    registration on the test poses), as a calibration is used.
    """
    base = point_model(load_robot(ROBOTS / arm / "robot.toml"))
    g, t = read_tracker(data / grid), read_tracker(data / test)
    target = np.loadtxt(data / test, delimiter=",", skiprows=1, usecols=(1, 2, 3))

    def mean_error(fit) -> float:
        p = tool_position(fit.model, np.radians(t.q_deg)) @ fit.rotation.T + fit.translation_mm
        return float(np.mean(np.linalg.norm(p - t.xyz_mm, axis=1)))

    qg = np.radians(g.q_deg)
    return {
        "as_measured_mm": float(np.mean(np.linalg.norm(target - t.xyz_mm, axis=1))),
        "nominal_mm": mean_error(calibrate(base, qg, g.xyz_mm, TOOL_NAMES)),
        "tracker_mm": mean_error(calibrate(base, qg, g.xyz_mm)),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, help="folder holding the public sets' folders")
    ap.add_argument(
        "--set", action="append", choices=sorted(SET_FILES), help="only this set (repeatable)"
    )
    ap.add_argument("--robot", type=Path, help="robot file (with --table)")
    ap.add_argument("--table", type=Path, help="a tracker table: j1…jn (deg), x, y, z (mm)")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--points", type=int, default=60)
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    args = ap.parse_args()
    if (args.robot is None) != (args.table is None):
        ap.error("give --robot and --table together")
    if args.table and args.set:
        ap.error("give --set or --table, not both")
    data = tracker_data_dir(ROOT, args.data)
    wanted = set(args.set or SET_FILES)
    missing = [m for s in sorted(wanted) if (m := missing_set(data, s, ROOT))]
    if missing and not args.table:
        print("\n".join(f"error: {m}" for m in missing), file=sys.stderr)
        sys.exit(2)
    cases = (
        {str(args.table): (args.robot, args.table)}
        if args.table
        else {
            name: (ROBOTS / arm / "robot.toml", data / f)
            for name, (arm, f) in SETS.items()
            if arm in wanted
        }
    )
    try:
        out = {name: run_set(r, t, args.seeds, args.points) for name, (r, t) in cases.items()}
        if not args.table:
            out["published"] = {
                name: {
                    **published_test(data, *files),
                    "published_uncalibrated_mm": before,
                    "published_hybrid_mm": after,
                }
                for name, (*files, before, after) in PUBLISHED.items()
                if files[0] in wanted
            }
    except WirecalError as exc:
        sys.exit(f"error: {exc}")
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print_text(out, args.seeds)


def print_text(out: dict, seeds: int) -> None:
    """Print the figures as a table, then the Tsinghua sets' own test."""
    published = out.pop("published", {})
    head = f"{'data set':<36}{'rows':>6}{'nominal':>9}{'tracker':>9}{'wire':>8}{'wire/tr':>9}"
    print(head + f"{'wire+c':>8}{'(w+c)/tr':>10}")
    for name, r in out.items():
        wc = r["wire_compliance_mm"]
        tail = "     n/a       n/a" if wc is None else f"{wc:>8.3f}{wc / r['tracker_mm']:>10.2f}"
        print(
            f"{name:<36}{r['rows']:>6}{r['nominal_mm']:>9.3f}{r['tracker_mm']:>9.3f}"
            f"{r['wire_mm']:>8.3f}{r['wire_mm'] / r['tracker_mm']:>9.2f}" + tail
        )
    print(f"medians over {seeds} seeds, mm (n/a: the robot file asks no compliances)")
    for name, r in published.items():
        print(
            f"{name} grid → 20 random poses, mean error mm: as measured {r['as_measured_mm']:.3f} "
            f"(published {r['published_uncalibrated_mm']}), nominal {r['nominal_mm']:.3f}, "
            f"tracker {r['tracker_mm']:.3f} (published hybrid {r['published_hybrid_mm']})"
        )


if __name__ == "__main__":
    main()
