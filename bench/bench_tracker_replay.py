"""Public laser-tracker data through one wire: held-out 3-D RMS of four calibrations.

Per public data set (read from ``--data DIR``, else ``$WIRECAL_TRACKER_DATA``, else
``../shared/data/tracker`` beside the clone: a folder holding the publishing repositories as
cloned, or the older compressed copies, :mod:`wirecal.formats.tracker_published`;
tests/data/tracker/<set>/PUBLISHED.md says where each is published; the robot files are in
tests/data/tracker/<set>/), or any
table with columns j1…jn (degrees) and x, y, z (mm) with ``--robot R --table T``: over 3 seeds, a
random 50/50 split; from the training half ``wirecal plan --pool``'s planner chooses θ0
and at most 60 poses; on them the nominal model (tool point and base frame fitted), the
3-D tracker calibration, and one wire from the anchor at θ0 (readings: the distance to
the measured point, rounded to the encoder's count, unknown zero) identified by the
wire model with a prior where the readings are weak (:mod:`wirecal.solver.tracker.replay`).
Each is judged on the held-out half after a rigid registration. Prints per set the medians
over the seeds and the wire's ratio to the tracker calibration; ``--json`` prints them as JSON (keys
``nominal_mm``, ``tracker_mm``, ``wire_mm``, ``wire_compliance_mm``, ``anchor_mm``).

``wire_compliance_mm``: the same readings fitted with the compliances (issue 30's model)
of the robot file's ``[calibration] compliances``; null for a robot file that asks none.
``predicted_mm``: the plan's predicted tool-point error at the reading noise, per seed.

``--preflight`` chooses θ0 and the poses as ``plan --pool -o PLAN.toml`` does for a user,
``gen``'s pre-flight applied (:func:`~wirecal.cli.plan_pool_file.safe_plan`: poses whose
move leaves the wire's range or meets the floor left out, the choice made again); the fit
is the same either way (the one ``wirecal solve`` runs on such a plan).

``--anchors`` replays instead the rigid wire from every θ0 the planner tries (each with its
own 60 poses) and from the chosen θ0 with every training pose within the encoder's range
(:func:`~wirecal.solver.tracker.replay.lottery`): per seed the chosen θ0's figure, the best,
median and worst of the others, the rank correlation of the planner's predicted error with
the held-out one, the every-pose figure and the tracker calibration beside them.

    python bench/bench_tracker_replay.py [--data DIR] [--set ur10_ipa ...]
        [--robot R --table T.csv] [--seeds 3] [--points 60] [--anchors | --preflight] [--json]

A set asked for and not found exits 2 naming the folder, the missing files and the
``git clone`` (and commit) that brings them; a file that is not the published bytes at that
commit (git's blob id) is named in a note on stderr.
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
from scipy.stats import spearmanr  # noqa: E402

from wirecal.cli.plan_pool_file import safe_plan  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.formats.tracker_published import (  # noqa: E402
    PUBLISHED_SETS,
    locate_set,
    tracker_data_dir,
    unpublished,
)
from wirecal.formats.tracker_sets import read_tracker  # noqa: E402
from wirecal.solver.errors import WirecalError  # noqa: E402
from wirecal.solver.fit.calibrate import point_model  # noqa: E402
from wirecal.solver.kinematics import tool_position  # noqa: E402
from wirecal.solver.params import TOOL_NAMES  # noqa: E402
from wirecal.solver.plan.options import PlanOptions  # noqa: E402
from wirecal.solver.plan.pool import PoolPlan  # noqa: E402
from wirecal.solver.tracker.fit import calibrate  # noqa: E402
from wirecal.solver.tracker.replay import Replay, lottery, replay  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "tests" / "data" / "tracker"
# Each set's files by their path in the publishing repository (tracker_published).
UR10_B = "Series_B/measurements_joint_configurations.csv"
UR5_GRID, UR5_TEST = (
    "UR5/3D_UR5_uncalibrated_grid_cleaned.csv",
    "UR5/3D_UR5_uncalibrated_random_cleaned.csv",
)
WAM_GRID, WAM_TEST = (
    "WAM/3D_WAM_uncalibrated_grid_cleaned.csv",
    "WAM/3D_WAM_uncalibrated_random_cleaned.csv",
)
SETS = {
    "UR10 IPA B (joint configurations)": ("ur10_ipa", UR10_B),
    "UR10 IPA C (random poses)": ("ur10_ipa", "Series_C/measurements_random_poses.csv"),
    "UR10 IPA D (ISO cubes)": ("ur10_ipa", "Series_D/measurements_iso_cubes.csv"),
    "UR5 Tsinghua grid": ("ur5_jacobi", UR5_GRID),
    "WAM (7 axes) Tsinghua grid": ("wam_jacobi", WAM_GRID),
}
# The Tsinghua sets' own test: calibrate on the grid, test on the 20 random poses (the
# thesis's abstract, quoted in the data set's README: mean absolute position error).
PUBLISHED = {
    "UR5": ("ur5_jacobi", UR5_GRID, UR5_TEST, 2.5664, 0.1549),
    "WAM": ("wam_jacobi", WAM_GRID, WAM_TEST, 17.7661, 2.9178),
}


def preflight_choice(robot, q_deg: np.ndarray, points: int, opt: PlanOptions) -> PoolPlan:
    """Return the choice ``plan --pool -o PLAN.toml`` writes: gen's pre-flight applied."""
    return safe_plan(robot, q_deg, points, opt, "the replay's plan")[0]


def replays(
    robot, table, seeds: int, points: int, preflight: bool
) -> tuple[list[Replay], dict[int, str]]:
    """Return the seeds' replays and, with ``preflight``, why a seed has no plan file."""
    if not preflight:
        return [replay(robot, table, seed=s, points=points) for s in range(seeds)], {}
    runs, no_plan = [], {}
    for s in range(seeds):
        try:
            runs.append(replay(robot, table, seed=s, points=points, choose=preflight_choice))
        except WirecalError as exc:
            no_plan[s] = str(exc)
    return runs, no_plan


def run_set(
    robot_path: Path, table_path: Path, seeds: int, points: int, preflight: bool = False
) -> dict:
    """Return one set's medians over the seeds and each seed's figures.

    With ``preflight`` a seed whose plan file the pre-flight refuses has no figures: named
    in ``no_plan`` (seed → why), the medians over the others.
    """
    robot, table = load_robot(robot_path), read_tracker(table_path)
    runs, no_plan = replays(robot, table, seeds, points, preflight)
    where = {
        "robot": str(
            robot_path.relative_to(ROOT) if robot_path.is_relative_to(ROOT) else robot_path
        ),
        "table": str(
            table_path.relative_to(ROOT) if table_path.is_relative_to(ROOT) else table_path
        ),
        "rows": len(table.q_deg),
        **({"no_plan": no_plan} if preflight else {}),
    }
    if not runs:
        return where

    def median(key: str) -> float | None:
        values = [getattr(r, key) for r in runs]
        return None if None in values else float(np.median(values))

    return {
        **where,
        "points": runs[0].points,
        "nominal_mm": median("nominal_mm"),
        "tracker_mm": median("tracker_mm"),
        "wire_mm": median("wire_mm"),
        "wire_compliance_mm": median("wire_compliance_mm"),
        "anchor_mm": [r.anchor_mm.round(3).tolist() for r in runs],
        "anchor_tracker_mm": [r.anchor_tracker_mm.round(3).tolist() for r in runs],
        "theta0_deg": [r.theta0_deg.round(3).tolist() for r in runs],
        "per_seed": {
            key: [None if getattr(r, key) is None else round(getattr(r, key), 4) for r in runs]
            for key in ("nominal_mm", "tracker_mm", "wire_mm", "wire_compliance_mm")
        },
        "predicted_mm": [round(r.predicted_mm, 4) for r in runs],
    }


def anchor_set(robot_path: Path, table_path: Path, seeds: int, points: int) -> dict:
    """Return one set's anchor lottery per seed (module docstring, ``--anchors``)."""
    robot, table = load_robot(robot_path), read_tracker(table_path)
    runs = [lottery(robot, table, seed=s, points=points) for s in range(seeds)]

    def each(f) -> list[float]:
        return [round(float(f(r)), 4) for r in runs]

    return {
        "theta0_tried": [len(r.wire_mm) for r in runs],
        "chosen_wire_mm": each(lambda r: r.wire_mm[r.chosen]),
        "best_wire_mm": each(lambda r: np.min(r.wire_mm)),
        "median_wire_mm": each(lambda r: np.median(r.wire_mm)),
        "worst_wire_mm": each(lambda r: np.max(r.wire_mm)),
        "spearman": each(lambda r: spearmanr(r.predicted_mm, r.wire_mm).statistic),
        "every_pose_wire_mm": each(lambda r: r.every_pose_mm),
        "tracker_mm": each(lambda r: r.tracker_mm),
        "tracker_every_pose_mm": each(lambda r: r.tracker_every_pose_mm),
    }


def published_test(files: dict[str, Path], arm: str, grid: str, test: str) -> dict:
    """Return the mean 3-D error on the test poses: as measured, nominal, tracker-calibrated.

    Calibrated on every grid pose; the base frame the calibration found is kept (no second
    registration on the test poses), as a calibration is used.
    """
    base = point_model(load_robot(ROBOTS / arm / "robot.toml"))
    g, t = read_tracker(files[grid]), read_tracker(files[test])
    target = np.loadtxt(files[test], delimiter=",", skiprows=1, usecols=(1, 2, 3))

    def mean_error(fit) -> float:
        p = tool_position(fit.model, np.radians(t.q_deg)) @ fit.rotation.T + fit.translation_mm
        return float(np.mean(np.linalg.norm(p - t.xyz_mm, axis=1)))

    qg = np.radians(g.q_deg)
    return {
        "as_measured_mm": float(np.mean(np.linalg.norm(target - t.xyz_mm, axis=1))),
        "nominal_mm": mean_error(calibrate(base, qg, g.xyz_mm, TOOL_NAMES)),
        "tracker_mm": mean_error(calibrate(base, qg, g.xyz_mm)),
    }


def located(data: Path, wanted: set[str]) -> dict[str, dict[str, Path]]:
    """Return each wanted set's files; exit 2 naming every set not found and how to get it.

    A file whose bytes are not the published ones is read, with a note on stderr.
    """
    files, missing = {}, []
    for name in sorted(wanted):
        try:
            files[name] = locate_set(data, name, ROOT)
        except WirecalError as exc:
            missing.append(f"error: {exc}")
    if missing:
        print("\n".join(missing), file=sys.stderr)
        sys.exit(2)
    for name in sorted(wanted):
        if differ := unpublished(name, files[name]):
            commit = PUBLISHED_SETS[name].commit
            print(
                f"note: not the bytes published at {commit}: {', '.join(differ)}; the figures"
                " may differ from docs/benchmarks.md",
                file=sys.stderr,
            )
    return files


def _parser() -> argparse.ArgumentParser:
    """Return the bench's command line."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--data",
        type=Path,
        help="folder holding the clones of the publishing repositories (or <set>/*.csv.gz)",
    )
    ap.add_argument(
        "--set", action="append", choices=sorted(PUBLISHED_SETS), help="only this set (repeatable)"
    )
    ap.add_argument("--robot", type=Path, help="robot file (with --table)")
    ap.add_argument("--table", type=Path, help="a tracker table: j1…jn (deg), x, y, z (mm)")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--points", type=int, default=60)
    ap.add_argument(
        "--anchors", action="store_true", help="one wire from every θ0 tried (module docstring)"
    )
    ap.add_argument(
        "--preflight",
        action="store_true",
        help="choose as 'plan --pool -o PLAN.toml' does: gen's pre-flight applied",
    )
    ap.add_argument("--json", action="store_true", help="print the figures as JSON")
    return ap


def main() -> None:
    ap = _parser()
    args = ap.parse_args()
    if (args.robot is None) != (args.table is None):
        ap.error("give --robot and --table together")
    if args.table and args.set:
        ap.error("give --set or --table, not both")
    wanted = set(args.set or PUBLISHED_SETS)
    files = {} if args.table else located(tracker_data_dir(ROOT, args.data), wanted)
    cases = (
        {str(args.table): (args.robot, args.table)}
        if args.table
        else {
            name: (ROBOTS / arm / "robot.toml", files[arm][f])
            for name, (arm, f) in SETS.items()
            if arm in wanted
        }
    )
    if args.anchors and args.preflight:
        ap.error("give --anchors or --preflight, not both")
    try:
        out = {
            name: anchor_set(r, t, args.seeds, args.points)
            if args.anchors
            else run_set(r, t, args.seeds, args.points, args.preflight)
            for name, (r, t) in cases.items()
        }
        if not args.table and not args.anchors:
            out["published"] = {
                name: {
                    **published_test(files[arm], arm, *tests),
                    "published_uncalibrated_mm": before,
                    "published_hybrid_mm": after,
                }
                for name, (arm, *tests, before, after) in PUBLISHED.items()
                if arm in wanted
            }
    except WirecalError as exc:
        sys.exit(f"error: {exc}")
    if args.json:
        print(json.dumps(out, indent=2))
    elif args.anchors:
        print_anchors(out)
    else:
        print_text(out, args.seeds)


def print_text(out: dict, seeds: int) -> None:
    """Print the figures as a table, then the Tsinghua sets' own test."""
    published = out.pop("published", {})
    head = f"{'data set':<36}{'rows':>6}{'nominal':>9}{'tracker':>9}{'wire':>8}{'wire/tr':>9}"
    print(head + f"{'wire+c':>8}{'(w+c)/tr':>10}")
    for name, r in out.items():
        if "wire_mm" not in r:
            print(f"{name:<36}{r['rows']:>6}  no plan file on any seed (the pre-flight)")
            continue
        wc = r["wire_compliance_mm"]
        tail = "     n/a       n/a" if wc is None else f"{wc:>8.3f}{wc / r['tracker_mm']:>10.2f}"
        print(
            f"{name:<36}{r['rows']:>6}{r['nominal_mm']:>9.3f}{r['tracker_mm']:>9.3f}"
            f"{r['wire_mm']:>8.3f}{r['wire_mm'] / r['tracker_mm']:>9.2f}" + tail
        )
        if r.get("no_plan"):
            seeds_left = ", ".join(str(k) for k in r["no_plan"])
            print(f"  no plan file on seed {seeds_left} (the pre-flight): medians of the others")
    print(f"medians over {seeds} seeds, mm (n/a: the robot file asks no compliances)")
    for name, r in published.items():
        print(
            f"{name} grid → 20 random poses, mean error mm: as measured {r['as_measured_mm']:.3f} "
            f"(published {r['published_uncalibrated_mm']}), nominal {r['nominal_mm']:.3f}, "
            f"tracker {r['tracker_mm']:.3f} (published hybrid {r['published_hybrid_mm']})"
        )


def print_anchors(out: dict) -> None:
    """Print each set's anchor lottery (``--anchors``), one line a seed."""
    print(
        f"{'data set':<36}{'seed':>5}{'chosen':>8}{'best':>7}{'median':>8}{'worst':>7}"
        f"{'rho':>7}{'every':>7}{'tracker':>9}{'tr every':>10}"
    )
    keys = ("chosen_wire_mm", "best_wire_mm", "median_wire_mm", "worst_wire_mm")
    for name, r in out.items():
        for s, row in enumerate(zip(*(r[k] for k in keys), strict=True)):
            print(
                f"{name:<36}{s:>5}{row[0]:>8.3f}{row[1]:>7.3f}{row[2]:>8.3f}{row[3]:>7.3f}"
                f"{r['spearman'][s]:>7.2f}{r['every_pose_wire_mm'][s]:>7.3f}"
                f"{r['tracker_mm'][s]:>9.3f}{r['tracker_every_pose_mm'][s]:>10.3f}"
            )
    print(
        "one rigid wire's held-out 3-D RMS (mm) from the planner's θ0 (chosen) and the best, "
        "median and worst of the θ0s it tried, each with its own planned poses; rho: rank "
        "correlation of the predicted error with it; every: the chosen θ0 read at every "
        "training pose in range; the tracker calibration of the planned poses and of every one"
    )


if __name__ == "__main__":
    main()
