"""How much chain the identification and the fit ask for, and their CPU, before and now.

Issue 34 (the quick test loop): the solvers' evaluations of the model are the largest
share of the kinematics in the loop. Four figures of one process each run:

* **solve** — ``wirecal solve``'s computation (stepwise, joint, budgets) of 10 simulated
  logs of the Viper s650's paper plan (69 points, the paper's Table 5 errors), each new;
* **solved again** — the same 10 logs solved again (as the report and the tests do);
* **fit** — ``wirecal fit`` of two simulated tables of 400 rows (``--holdout none``);
* **fitted again** — the same tables with ``--holdout half`` (the whole table's fit
  again, then its halves').

Per figure the CPU seconds and a digest of every output (bits of every number); in a
fresh process, the chain's work of one solve and one fit by phase (chains computed: calls
of the recurrence; rotations: two per joint turned; Jacobians: ``tool_jacobian`` and
``tool_gradient`` calls). With ``--before CHECKOUT`` (for example
``git archive main | tar -x -C /tmp/before``) the same in processes of that code,
interleaved run by run: medians, ratios now/before, the counts side by side, and whether
the outputs are bit for bit the same.

    python bench/bench_evaluations.py [--before CHECKOUT] [--runs R]
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import hashlib
import json
import sys
import time
from pathlib import Path

from interleaved import interleaved, print_ratios

NOW = Path(__file__).resolve().parents[1]
VIPER = NOW / "examples" / "viper_s650"
COUNTED = ("_recurrence", "_recurrence_floats", "_turn", "tool_jacobian", "tool_gradient")


def _feed(h: hashlib._Hash, o: object) -> None:
    """Add ``o`` to ``h``: arrays by their bytes, dataclasses field by field (no timings)."""
    import numpy as np

    if isinstance(o, np.ndarray) and o.dtype != object:
        h.update(f"{o.dtype}{o.shape}".encode() + np.ascontiguousarray(o).tobytes())
    elif dataclasses.is_dataclass(o) and not isinstance(o, type):
        for f in dataclasses.fields(o):
            if f.name != "seconds":  # the Monte Carlo's own timing
                h.update(f.name.encode())
                _feed(h, getattr(o, f.name))
    elif isinstance(o, dict):
        for k, v in o.items():
            h.update(repr(k).encode())
            _feed(h, v)
    elif isinstance(o, list | tuple):
        h.update(b"[")
        for v in o:
            _feed(h, v)
    elif isinstance(o, float):
        h.update(np.float64(o).tobytes())
    else:
        h.update(repr(o).encode())


def _counting(phases: list[str]) -> collections.Counter:
    """Wrap the kinematics' counted functions to count their calls by the phase they are in.

    ``phases``: a stack the solvers' wrappers (:func:`_phase`) push their name on.
    """
    from wirecal.solver import kinematics as K

    counts: collections.Counter = collections.Counter()
    for name in COUNTED:
        original = getattr(K, name)

        def counted(*args, _original=original, _name=name, **kw):
            counts[f"{phases[-1]} {_name}"] += 1
            return _original(*args, **kw)

        for module in [m for n, m in sys.modules.items() if n.startswith("wirecal")]:
            if getattr(module, name, None) is original:  # imported by name there too
                setattr(module, name, counted)
    return counts


def _phase(module: object, function: str, phases: list[str], label: str) -> None:
    """Wrap ``module.function`` so that the counts inside it are ``label``'s."""
    original = getattr(module, function)

    def inside(*args, **kw):
        phases.append(label)
        try:
            return original(*args, **kw)
        finally:
            phases.pop()

    setattr(module, function, inside)


def _inputs() -> tuple:
    """Return the Viper, its paper plan, 11 simulated logs' measurements and 3 fits' tables."""
    from wirecal.formats.log import parse_log
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.formats.simulated_log import simulate_log
    from wirecal.formats.truth import load_errors
    from wirecal.solver.fit.synth import synthetic_table
    from wirecal.solver.log.measurements import check_log

    robot = load_robot(VIPER / "robot.toml")
    plan = load_plan(VIPER / "paper_plan.toml", robot)
    errors = load_errors(VIPER / "paper_table5_errors.toml", robot)
    logs = [
        check_log(parse_log(simulate_log(robot, plan, errors, seed=s), "b.csv"), plan, robot)
        for s in range(LOGS + 1)
    ]
    tables = [synthetic_table(robot, 400, seed=s).table for s in range(3)]
    return robot, plan, logs, tables


LOGS = 10
"""Logs solved per run (and one more, first, to load what a solve loads)."""


def child(mode: str = "time") -> None:
    """One run in this process: print each figure's CPU s and the outputs' digest (JSON).

    ``mode`` "count": instead, the chain's work of one solve and one fit in a fresh process,
    by phase (the stepwise steps, the joint method's minimisation, the fit's, the rest).
    """
    from wirecal.solver import identify
    from wirecal.solver.fit import calibrate
    from wirecal.solver.fit.result import FitOptions, fit_table
    from wirecal.solver.solve import solve

    robot, plan, logs, tables = _inputs()
    if mode == "count":
        phases = ["other"]
        _phase(identify, "_solve_step", phases, "stepwise")
        _phase(identify, "_minimise", phases, "joint")
        _phase(calibrate, "minimised", phases, "fit LM")
        counts = _counting(phases)
        solve(robot, plan, logs[0])
        fit_table(robot, tables[0], FitOptions("none"))
        print(json.dumps({"counts": dict(counts)}))
        return
    solve(robot, plan, logs[0])  # what a first solve and fit load
    fit_table(robot, tables[0], FitOptions("none"))
    figures = {
        f"solve, {LOGS} logs of the Viper's paper plan": lambda: [
            solve(robot, plan, m) for m in logs[1:]
        ],
        "the same logs solved again": lambda: [solve(robot, plan, m) for m in logs[1:]],
        "fit, 2 tables of 400 rows of the Viper": lambda: [
            fit_table(robot, t, FitOptions("none")) for t in tables[1:]
        ],
        "the same tables, held-out half (fitted again)": lambda: [
            fit_table(robot, t, FitOptions("half")) for t in tables[1:]
        ],
    }
    cpu, h = {}, hashlib.sha256()
    for name, run in figures.items():
        t0 = time.process_time()
        out = run()
        cpu[name] = time.process_time() - t0
        _feed(h, out)
    print(json.dumps({"cpu_s": cpu, "digest": h.hexdigest()}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, help="a checkout of the code before")
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    before = args.before or NOW
    found = interleaved("bench_evaluations", before, args.runs)
    print_ratios(found)
    same = {r["digest"] for rs in found.values() for r in rs}
    print(f"every output bit for bit the same before and now: {'yes' if len(same) == 1 else 'NO'}")
    counts = {
        k: rs[0]["counts"] for k, rs in interleaved("bench_evaluations", before, 1, "count").items()
    }
    print(f"\nthe chain's work of one solve and one fit, fresh process {'before':>9} {'now':>8}")
    for key in sorted(set(counts["before"]) | set(counts["now"])):
        phase, name = key.split(" ", 1) if not key.startswith("fit LM") else ("fit LM", key[7:])
        label = {
            "_recurrence": "chains (arrays)",
            "_recurrence_floats": "chains (floats)",
            "_turn": "rotations (2 per joint)",
        }.get(name, name + " calls")
        pair = counts["before"].get(key, 0), counts["now"].get(key, 0)
        print(f"  {phase:9} {label:36} {pair[0]:9d} {pair[1]:8d}")


if __name__ == "__main__":
    main()
