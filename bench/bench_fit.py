"""``wirecal fit`` on simulated tables: held-out RMS of the cable length beside the floor.

Three arms (Viper s650, ABB IRB 120, UR5e), tables from
:func:`~wirecal.solver.fit.synth.synthetic_table`: random configurations in the middle 80 %
of the joint ranges (or, "narrow", ±20° about mid-range: rows that carry little), joints
logged to 0.1°, lengths to 0.01 mm with 0.02 mm reading noise, an anchor anywhere in the
cell, three sessions with offset jumps of 3–30 mm, three snagged and two mistyped rows.
Three sections, medians over the seeds:

1. **Parameter choice** — first half trains, second half held out (``--holdout half``):
   RMS/floor, DH errors kept and the error budget, *before* (every identified DH error, the
   choice up to issue 31: :func:`~wirecal.solver.fit.calibrate.generalise` replaced by the identity)
   and *after* (BIC backward elimination). Goal: after ≤ 1.3 floors.
2. **Held-out, refined joints** — random 20 %, 5 repeats; the same with joints refined from
   x, y, z; sessions found within ±2 rows; the time of one fit (one BLAS thread).
3. **Rows** — one fit (``--holdout none``) of 10,000 and 100,000 rows, each in its own
   process: CPU and wall seconds of the fit and the process's peak memory; with
   ``--before CHECKOUT`` (for example ``git archive main | tar -x -C ../before``) the same
   fit by the code there, interleaved run by run, the ratio of CPU times and the largest
   shift of an estimate between the two in σ (before issue 31, 20,000 rows took 6.4 GB and
   100,000 ended in a 74.5 GiB allocation: an N × N matrix).

4. **RobotCali** — with ``WIRECAL_ROBOTCALI_DATA`` the path of ``RobotCali-new.xlsx``
   (github.com/Lizhibing1490183152/RobotCali, no licence: read where it is, never copied
   into the repository): ``--holdout half`` and ``random:0.2`` before and after BIC.

5. **Cost** (``--cost``, issue 34: the quick test loop's fits) — CPU of the fits the tests
   run most: ``wirecal fit`` of 300 simulated rows (three sessions, ``--holdout half``) and
   of 1,000 rows, the wire prior's MAP fit of 80 readings (a pool plan's), a 3-D tracker
   calibration of 80 poses, and the covariance then the identifiability of a 200,000 × 30
   Jacobian (FT30's); each by the code now and, with ``--before CHECKOUT``, by the code there, in
   processes interleaved run by run (:func:`compare_trees`): medians, the ratio now/before
   and whether the two codes' outputs are bit for bit the same.

    python bench/bench_fit.py [--seeds N] [--skip-rows | --rows-only] [--before CHECKOUT]
        [--runs R]
    python bench/bench_fit.py --cost [--before CHECKOUT] [--runs R]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402
from unittest import mock  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.formats.cable_table import read_cable_table  # noqa: E402
from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.fit import calibrate as fit  # noqa: E402
from wirecal.solver.fit.gate import fit_budget  # noqa: E402
from wirecal.solver.fit.result import FitOptions, fit_table  # noqa: E402
from wirecal.solver.fit.synth import synthetic_table  # noqa: E402
from wirecal.solver.robot import Robot  # noqa: E402

NOW = Path(__file__).resolve().parents[1]
EXAMPLES = NOW / "examples"
ARMS = ("viper_s650", "abb_irb120", "ur5e")
SIZES = (100, 300, 1000, 2000)
NARROW_DEG = 20.0


def _narrow(robot: Robot) -> Robot:
    """Return the robot with its joint limits ±NARROW_DEG about mid-range (for the tables)."""
    mid = (robot.joint_min_deg + robot.joint_max_deg) / 2
    return replace(
        robot,
        joint_min_deg=np.maximum(robot.joint_min_deg, mid - NARROW_DEG),
        joint_max_deg=np.minimum(robot.joint_max_deg, mid + NARROW_DEG),
    )


def _half(robot: Robot, table) -> tuple[float, int, float]:
    """Return RMS/floor of the half split, the DH errors kept and the error budget (mm)."""
    r = fit_table(robot, table, FitOptions(holdout="half"))
    kept = sum(not n.startswith("tool_") for n in r.main.core.layout.geometry)
    return r.main.holdout.ratio, kept, fit_budget(r, r.main).total


def _every_identified(base, layout, x, data, rows):
    """The choice up to issue 31: every identified DH error kept (no BIC)."""
    return fit.evaluate(base, layout, x, data, rows), ()


def choice(seeds: int) -> None:
    """Section 1: the parameter choice before and after, first half → second half."""
    print("1. parameter choice: first half -> second half (medians)")
    print(f"{'arm':<12}{'table':>12}{'ratio':>14}{'DH kept':>12}{'budget mm':>16}")
    for arm in ARMS:
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        for label, n, source in (
            ("300", 300, robot),
            ("1000", 1000, robot),
            ("300 narrow", 300, _narrow(robot)),
        ):
            rows = []
            for seed in range(seeds):
                table = synthetic_table(source, n, seed=seed).table
                with mock.patch.object(fit, "generalise", _every_identified):
                    before = _half(robot, table)
                rows.append((*before, *_half(robot, table)))
            m = np.median(np.array(rows, dtype=float), axis=0)
            print(
                f"{arm:<12}{label:>12}{m[0]:>7.2f}→{m[3]:<6.2f}{m[1]:>5.0f}→{m[4]:<6.0f}"
                f"{m[2]:>8.3f}→{m[5]:<7.3f}"
            )


def holdout(seeds: int) -> None:
    """Section 2: random 20 % held out, the refined joints, the sessions, the time."""
    print("\n2. held-out random 20 %, 5 repeats (medians)")
    print(
        f"{'arm':<12}{'rows':>6}{'held-out':>10}{'floor':>8}{'ratio':>7}"
        f"{'refined':>9}{'floor':>8}{'ratio':>7}{'sessions':>10}{'fit s':>7}"
    )
    for arm in ARMS:
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        for n in SIZES:
            rows = []
            for seed in range(seeds):
                syn = synthetic_table(robot, n, seed=seed)
                t0 = time.perf_counter()
                fit_table(robot, syn.table, FitOptions(holdout="none"))
                seconds = time.perf_counter() - t0
                r = fit_table(robot, syn.table, FitOptions(refine_joints=True))
                m, f = r.main, r.refined
                assert f is not None
                found = np.array(m.core.starts)
                ok = found.size == len(syn.starts) and np.all(np.abs(found - syn.starts) <= 2)
                ho, hf = m.holdout, f.holdout
                rows.append((ho.rms_mm, ho.floor_mm, hf.rms_mm, hf.floor_mm, ok, seconds))
            a = np.array(rows, dtype=float)
            md = np.median(a, axis=0)
            print(
                f"{arm:<12}{n:>6}{md[0]:>10.4f}{md[1]:>8.4f}{md[0] / md[1]:>7.2f}"
                f"{md[2]:>9.4f}{md[3]:>8.4f}{md[2] / md[3]:>7.2f}"
                f"{int(a[:, 4].sum()):>6}/{seeds:<3}{md[5]:>7.2f}"
            )


FIT_CHILD = """
import json, os, resource, sys, time
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"
from pathlib import Path
from wirecal.solver.fit.result import FitOptions, fit_table
from wirecal.solver.fit.synth import synthetic_table
from wirecal.formats.robot_file import load_robot
robot = load_robot(Path(sys.argv[1]))
table = synthetic_table(robot, int(sys.argv[2]), seed=0).table
cpu, wall = time.process_time(), time.perf_counter()
core = fit_table(robot, table, FitOptions(holdout="none")).main.core
cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
per = core.layout.boundary_per_internal
print(json.dumps({"cpu": cpu, "wall": wall,
    "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    "x": dict(zip(core.layout.names, (core.x * per).tolist())),
    "std": dict(zip(core.layout.names, (core.std * per).tolist()))}))
"""


def _fit_in(tree: Path, rows: int) -> dict:
    """Return the figures of one fit of ``rows`` rows by the code in ``tree`` (a process)."""
    robot = str(tree / "examples" / "viper_s650" / "robot.toml")
    cmd = [sys.executable, "-P", "-c", FIT_CHILD, robot, str(rows)]
    env = {**os.environ, "PYTHONPATH": str(tree)}
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, env=env).stdout)


def _shift_sigma(now: dict, before: dict) -> float:
    """Return the largest |x_now − x_before| / σ over the parameters both fits hold."""
    common = now["x"].keys() & before["x"].keys()
    return max(abs(now["x"][k] - before["x"][k]) / now["std"][k] for k in common)


def many_rows(before: Path | None, runs: int) -> None:
    """Section 3: CPU, wall and peak memory of one fit of 10,000 and 100,000 rows."""
    print("\n3. rows: one fit, --holdout none (viper_s650; medians of each process's figures)")
    trees = {"now": NOW} if before is None else {"before": before, "now": NOW}
    print(f"{'rows':>8}{'code':>8}{'CPU s':>8}{'wall s':>8}{'peak MB':>9}{'kept':>6}")
    for n in (10_000, 100_000):
        got: dict[str, list[dict]] = {name: [] for name in trees}
        for _ in range(runs):  # interleaved: a change of the machine's load touches both
            for name, tree in trees.items():
                got[name].append(_fit_in(tree, n))
        for name, figs in got.items():
            med = [np.median([f[key] for f in figs]) for key in ("cpu", "wall", "peak_mb")]
            kept = len(figs[0]["x"])
            print(f"{n:>8}{name:>8}{med[0]:>8.2f}{med[1]:>8.2f}{med[2]:>9.0f}{kept:>6}")
        if before is not None:
            cpu = [np.median([f["cpu"] for f in got[t]]) for t in ("now", "before")]
            shift = _shift_sigma(got["now"][0], got["before"][0])
            print(f"{'':>8}  CPU now/before {cpu[0] / cpu[1]:.2f}; largest shift {shift:.2g} σ")


COST_CHILD = """
import hashlib, json, os, sys, time
for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[var] = "1"
from pathlib import Path
import numpy as np
from wirecal.formats.robot_file import load_robot
from wirecal.solver.fit.result import FitOptions, fit_table
from wirecal.solver.fit.synth import synthetic_table
from wirecal.solver.identifiability import analyse_jacobian, covariance
robot = load_robot(Path(sys.argv[1]))
figures, outputs = {}, {}
for rows, holdout in ((300, "half"), (1000, "none")):
    table = synthetic_table(robot, rows, seed=1).table
    cpu = time.process_time()
    core = fit_table(robot, table, FitOptions(holdout=holdout)).main.core
    figures[f"fit, {rows} rows"] = time.process_time() - cpu
    outputs[f"fit, {rows} rows"] = hashlib.sha256(core.x.tobytes() + core.std.tobytes()).hexdigest()
from wirecal.solver.fit.calibrate import Data, point_model
from wirecal.solver.kinematics import tool_position
from wirecal.solver.tracker.fit import calibrate
from wirecal.solver.wire_prior import map_fit, wire_layout
rng = np.random.default_rng(2)
lo, hi = 0.8 * np.radians(robot.joint_min_deg), 0.8 * np.radians(robot.joint_max_deg)
q = rng.uniform(lo, hi, (80, robot.n_joints))
truth, base = robot.model({"th2": 0.05, "a2": 0.6, "d4": 0.3}), point_model(robot)
p = tool_position(truth, q)
length = np.linalg.norm(p - [400.0, -300.0, 200.0], axis=1) + rng.normal(0, 0.01, len(q))
data = Data(q, length + 50.0, np.zeros(len(q), dtype=int), 0.007)
name = "wire prior: MAP fit, 80 readings"
cpu = time.process_time()
wire = map_fit(base, wire_layout(base), data, 0.5)
figures[name] = time.process_time() - cpu
outputs[name] = hashlib.sha256(wire.x.tobytes() + repr(wire.sigma_mm).encode()).hexdigest()
name = "tracker: 3-D calibration, 80 poses"
cpu = time.process_time()
tr = calibrate(base, q, p + rng.normal(0, 0.02, p.shape))
figures[name] = time.process_time() - cpu
outputs[name] = hashlib.sha256(tr.values.tobytes() + repr(tr.rms_mm).encode()).hexdigest()
J = np.random.default_rng(0).normal(size=(200_000, 30))
J[:, 29] = J[:, 28]
cpu = time.process_time()
cov = covariance(J, 1.0)[0]
ident = analyse_jacobian(J, tuple(f"p{k}" for k in range(30)))
figures["covariance + identifiability, 200,000 x 30"] = time.process_time() - cpu
outputs["covariance + identifiability, 200,000 x 30"] = hashlib.sha256(
    cov.tobytes() + repr(ident.combinations).encode()).hexdigest()
print(json.dumps({"figures": figures, "outputs": outputs}))
"""


def compare_trees(child: str, args: list[str], before: Path | None, runs: int) -> None:
    """Print the CPU of ``child``'s figures by the code now and ``before``, interleaved.

    ``child`` prints ``{"figures": {name: CPU s}, "outputs": {name: digest}}`` run with
    ``args`` (paths relative to the tree); each run is a process of its own, the trees
    alternating so that a change of the machine's load touches both. Medians over ``runs``,
    the ratio now/before, and whether the outputs are the same.
    """
    trees = {"now": NOW} if before is None else {"before": before.resolve(), "now": NOW}
    got: dict[str, list[dict]] = {name: [] for name in trees}
    for _ in range(runs):
        for name, tree in trees.items():
            cmd = [sys.executable, "-P", "-c", child, *(str(tree / a) for a in args)]
            env = {**os.environ, "PYTHONPATH": str(tree)}
            out = subprocess.run(cmd, check=True, capture_output=True, env=env).stdout
            got[name].append(json.loads(out))
    print(f"{'figure':<46}" + "".join(f"{t + ' CPU s':>14}" for t in trees), end="")
    print(f"{'now/before':>12}{'same output':>13}" if before is not None else "")
    for fig in got["now"][0]["figures"]:
        med = {t: float(np.median([r["figures"][fig] for r in got[t]])) for t in trees}
        line = f"{fig:<46}" + "".join(f"{med[t]:>14.3f}" for t in trees)
        if before is not None:
            same = got["now"][0]["outputs"][fig] == got["before"][0]["outputs"][fig]
            line += f"{med['now'] / med['before']:>12.2f}{'yes' if same else 'NO':>13}"
        print(line)


def cost(before: Path | None, runs: int) -> None:
    """Section 5: the CPU of the quick test loop's fits, now and before (module docstring)."""
    print(f"\n5. cost: CPU of the tests' fits (viper_s650; medians of {runs} runs, one thread)")
    compare_trees(COST_CHILD, ["examples/viper_s650/robot.toml"], before, runs)


ROBOTCALI_MAP = "j1=q1,j2=q2,j3=q3,j4=q4,j5=q5,j6=q6,length=L,x=x,y=y,z=z"


def robotcali(path: Path) -> None:
    """Section 4: the public RobotCali table (ABB IRB 120), before and after BIC."""
    robot = load_robot(EXAMPLES / "abb_irb120" / "robot.toml")
    table = read_cable_table(path, ROBOTCALI_MAP)
    print(f"\n4. RobotCali ({path.name}: {len(table.length_mm)} rows, ABB IRB 120)")
    print(
        f"{'holdout':<14}{'choice':<8}{'held-out mm':>12}{'floor':>8}{'ratio':>7}"
        f"{'DH kept':>9}{'budget mm':>11}"
    )
    for scheme in ("half", "random:0.2"):
        for label in ("before", "after"):
            patch = _every_identified if label == "before" else fit.generalise
            with mock.patch.object(fit, "generalise", patch):
                r = fit_table(robot, table, FitOptions(holdout=scheme))
            ho = r.main.holdout
            kept = sum(not n.startswith("tool_") for n in r.main.core.layout.geometry)
            budget = fit_budget(r, r.main).total
            print(
                f"{scheme:<14}{label:<8}{ho.rms_mm:>12.4f}{ho.floor_mm:>8.4f}"
                f"{ho.ratio:>7.2f}{kept:>9}{budget:>11.3f}"
            )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--skip-rows", action="store_true", help="leave out section 3")
    ap.add_argument("--rows-only", action="store_true", help="section 3 only")
    ap.add_argument("--before", type=Path, help="a checkout of the code before (section 3)")
    ap.add_argument("--runs", type=int, default=1, help="runs per tree in sections 3 and 5")
    ap.add_argument("--cost", action="store_true", help="section 5 only")
    args = ap.parse_args()
    if args.cost:
        cost(args.before, args.runs)
        return
    cali = os.environ.get("WIRECAL_ROBOTCALI_DATA")
    if cali:
        robotcali(Path(cali))
    if not args.rows_only:
        choice(args.seeds)
        holdout(args.seeds)
    if not args.skip_rows:
        many_rows(args.before, args.runs)


if __name__ == "__main__":
    main()
