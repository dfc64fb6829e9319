"""The twins' fused statements: CPU of whole twin runs with them and without, in one run.

For each shipped language's arm (the Viper: V+, the UR5e: URScript, the IRB 120: RAPID),
the measurement run (mounting and measuring programs, ``measure_in_twin``) and the
controller solver's run(s) on its log (``controller_runs``), each timed with
``time.process_time``, alternately with the fused statements (the code as it is) and
without (every statement and expression compiled node by node into closures, as before
they were written out: ``twin/fused_code.py``). The outputs must be the same: the log's
bytes, the outcomes, the solvers' results, operation counts and console lines.

    python bench/bench_twins_fused.py [--runs 3] [--arms viper_s650 ur5e abb_irb120]
        [--before ../before]

With ``--before`` (a checkout of the code before, e.g. ``git worktree add --detach
../before main``) each run is a process of its own importing wirecal from that tree or
this one, alternately, with the programs generated first; in it three runs are timed, as
a test session meets them: the first (seed 1: the modules' first run, "first"), one with
another truth and log (seed 2: "new log"), and that one again ("again"). The outputs of
each are compared by a digest of their text, printed beside the figures.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from contextlib import ExitStack
from pathlib import Path
from unittest import mock

import numpy as np

from wirecal.app.compare import controller_runs
from wirecal.app.twin_runs import generate, measure_in_twin
from wirecal.formats.log import load_measurements
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors
from wirecal.twin.rapid import interp as rapid_interp
from wirecal.twin.urscript import interp as urscript_interp
from wirecal.twin.vplus import interp as vplus_interp

NOW = Path(__file__).resolve().parents[1]
EXAMPLES = NOW / "examples"
PLANS = {"viper_s650": "paper_plan.toml", "ur5e": "plan.toml", "abb_irb120": "plan.toml"}
UNFUSED = [
    (vplus_interp, "fused_value", lambda *args: None),
    (vplus_interp, "fused_steps", lambda c, steps, one: [(s, one(s)) for s in steps]),
    (urscript_interp, "fused_value", lambda *args: None),
    (rapid_interp, "fused_value", lambda *args: None),
    (urscript_interp, "fused_steps", lambda c, steps, one: [one(s) for s in steps]),
    (rapid_interp, "fused_steps", lambda c, steps, one: [one(s) for s in steps]),
]
"""The hooks that write statements out, and what leaves every statement to the closures."""


def unfused() -> ExitStack:
    """Return a context in which no statement is written out (the closures only)."""
    stack = ExitStack()
    for module, name, nodes in UNFUSED:
        stack.enter_context(mock.patch.object(module, name, nodes))
    return stack


def one_run(arm: str, folder: Path, seed: int = 1, programs=None) -> tuple[float, float, tuple]:
    """Return the CPU seconds of the measurement run and of the solver runs, and what they gave."""
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    plan = load_plan(EXAMPLES / arm / PLANS[arm], robot)
    programs = programs or generate(robot, plan)
    truth = random_errors(robot, 1.0, np.random.default_rng(seed))
    t0 = time.process_time()
    run = measure_in_twin(robot, plan, truth, folder / "run", programs, seed=seed)
    t1 = time.process_time()
    m = load_measurements(run.log, plan, robot)
    t2 = time.process_time()
    solved = controller_runs(robot, plan, m, folder / "solve", programs=programs)
    t3 = time.process_time()
    outputs = (
        run.log.read_bytes(),
        run.mount,
        run.run,
        {k: (r.offsets, r.operations, r.console) for k, r in sorted(solved.items())},
    )
    return t1 - t0, t3 - t2, outputs


PHASES = (("first", 1), ("new log", 2), ("again", 2))
"""The runs a child times: the modules' first, one with another truth and log, that again."""


def child(arm: str) -> None:
    """Print, as JSON, each phase's CPU (measurement, solver) and its outputs' digest."""
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    programs = generate(robot, load_plan(EXAMPLES / arm / PLANS[arm], robot))
    got = []
    with tempfile.TemporaryDirectory() as tmp:
        for k, (_, seed) in enumerate(PHASES):
            *cpu, outputs = one_run(arm, Path(tmp) / str(k), seed, programs)
            got.append((cpu, hashlib.sha256(repr(outputs).encode()).hexdigest()))
    print(json.dumps(got))


def in_child(tree: Path, arm: str) -> list[tuple[tuple[float, float], str]]:
    """Run :func:`child` in a process importing wirecal from ``tree``: each phase's figures."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    command = [sys.executable, str(Path(__file__).resolve()), "--child", arm]
    out = subprocess.run(command, cwd=tree, env=env, capture_output=True, text=True, check=True)
    return [((c[0], c[1]), d) for c, d in json.loads(out.stdout.splitlines()[-1])]


def compare_trees(before: Path, arms: list[str], runs: int) -> None:
    """Print each arm's phases, before and now (medians of ``runs`` processes each), digests."""
    print(f"CPU s per run (time.process_time), medians of {runs}; before: the code in {before}")
    print(f"{'arm':<11} {'run':<18} {'phase':<8} {'before':>7} {'now':>7} {'ratio':>6}  digests")
    for arm in arms:
        got: dict[str, list] = {"before": [], "now": []}
        for _ in range(runs):
            for mode, tree in (("before", before.resolve()), ("now", NOW)):
                got[mode].append(in_child(tree, arm))
        for p, (phase, _) in enumerate(PHASES):
            digests = {mode: {g[p][1] for g in got[mode]} for mode in got}
            same = len(digests["before"]) == 1 and digests["before"] == digests["now"]
            for j, run in enumerate(("measurement run", "controller solver")):
                b, n = (statistics.median(g[p][0][j] for g in got[m]) for m in ("before", "now"))
                shown = f"{min(digests['now'])[:12]} {'same' if same else 'DIFFERENT'}"
                print(f"{arm:<11} {run:<18} {phase:<8} {b:7.2f} {n:7.2f} {n / b:6.2f}  {shown}")
            if not same:
                raise SystemExit(f"{arm}, {phase}: the outputs differ from the code before")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--arms", nargs="+", default=list(PLANS))
    parser.add_argument("--before", type=Path, help="a checkout of the code before")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    if args.before:
        compare_trees(args.before, args.arms, args.runs)
        return
    print(f"CPU s per run (time.process_time), medians of {args.runs}; before: node by node")
    print(f"{'arm':<12} {'run':<22} {'before':>8} {'now':>8} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for arm in args.arms:
            times: dict[str, list[tuple[float, float]]] = {"before": [], "now": []}
            outputs: dict[str, object] = {}
            for k in range(args.runs):
                for mode in ("before", "now"):
                    with unfused() if mode == "before" else ExitStack():
                        *cpu, outputs[mode] = one_run(arm, Path(tmp) / f"{arm}{mode}{k}")
                    times[mode].append((cpu[0], cpu[1]))
            same = outputs["before"] == outputs["now"]
            for j, run in enumerate(("measurement run", "controller solver")):
                before = statistics.median(t[j] for t in times["before"])
                now = statistics.median(t[j] for t in times["now"])
                print(f"{arm:<12} {run:<22} {before:8.2f} {now:8.2f} {now / before:6.2f}")
            print(f"{arm:<12} outputs the same (log bytes, outcomes, results, counts): {same}")
            if not same:
                raise SystemExit(f"{arm}: the fused statements changed an output")


if __name__ == "__main__":
    main()
