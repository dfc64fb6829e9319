"""Figures of the code now against a checkout of the code before, measured in one run.

A bench's ``child()`` measures in its own process and prints its figures as JSON (CPU
seconds, and anything else it names, such as digests of what it made); :func:`interleaved`
runs it on each tree in turn, ``runs`` times, each run a fresh process with the same
interpreter and the tree first on ``PYTHONPATH`` (the checkout of the code before, e.g.
``git archive main | tar -x -C ../before``, or this one), so a change of the machine's
load touches both alike. :func:`print_ratios` prints the medians and the ratio now / before.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import statistics
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

NOW = Path(__file__).resolve().parents[1]
ONE_THREAD = {v: "1" for v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
"""The BLAS threads of a child: one, as ``wirecal`` sets them."""


def child_figures(tree: Path, bench: str, *args: str) -> dict:
    """Run ``bench.child(*args)`` (a module of bench/) on the code in ``tree``; its figures."""
    code = (
        f"import sys; sys.path.insert(0, {str(NOW / 'bench')!r}); import {bench}; "
        f"{bench}.child(*{list(args)!r})"
    )
    out = subprocess.run(
        [sys.executable, "-P", "-c", code],
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin", **ONE_THREAD},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def interleaved(bench: str, before: Path, runs: int, *args: str) -> dict[str, list[dict]]:
    """Return each tree's figures ("before", "now") of ``runs`` runs taken in turn."""
    found: dict[str, list[dict]] = {"before": [], "now": []}
    for _ in range(runs):
        found["before"].append(child_figures(before.resolve(), bench, *args))
        found["now"].append(child_figures(NOW, bench, *args))
    return found


def print_ratios(found: dict[str, list[dict]], key: str = "cpu_s", width: int = 42) -> None:
    """Print each figure under ``key`` (name → CPU s): medians before and now, and the ratio."""
    print(
        f"{'CPU s (median of ' + str(len(found['now'])) + ' runs)':{width}} before      now  ratio"
    )
    for name in found["now"][0][key]:
        before = statistics.median(run[key][name] for run in found["before"])
        now = statistics.median(run[key][name] for run in found["now"])
        print(f"{name:{width}} {before:7.3f}  {now:7.3f}  {now / before:5.2f}")


def bench_main(bench: str, child: Callable[[], None], doc: str, made: str) -> None:
    """A bench's command line: ``--runs N``, ``--before CHECKOUT``; its figures printed.

    Without ``--before``, ``child`` runs in this process and each figure's median is printed;
    with it, :func:`interleaved` and :func:`print_ratios`, and whether both trees ``made`` the
    same (the runs' ``digest``, byte for byte).
    """
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--before", type=Path, help="a checkout of the code before")
    args = ap.parse_args()
    if args.before is None:
        runs = []
        for _ in range(args.runs):
            with contextlib.redirect_stdout(io.StringIO()) as buf:
                child()
            runs.append(json.loads(buf.getvalue()))
        for name in runs[0]["cpu_s"]:
            print(f"{name:42} {statistics.median(r['cpu_s'][name] for r in runs):7.3f} s CPU")
        return
    found = interleaved(bench, args.before, args.runs)
    print_ratios(found)
    same = all(r["digest"] == found["before"][0]["digest"] for rs in found.values() for r in rs)
    print(f"the same {made}, byte for byte, before and now: {'yes' if same else 'NO'}")
