"""Whole-process start-up of the command line: ``wirecal --help``, ``wirecal CMD --help``
and ``wirecal solve`` (the Viper example log), median of several runs, as ratios to a bare
Python importing what they cannot avoid (with the command line's BLAS thread and garbage
collector settings), measured in the same run: click for the help texts
(target ≤ 3×), numpy + scipy.optimize for ``solve`` (target ≤ 1.4×). The runs of all
commands are interleaved, so a change of the machine's load touches each alike; wall and CPU
time (user + system of the child) are both reported.

Every command runs once first, unmeasured, with bytecode caching on (a PYTHONDONTWRITEBYTECODE
in the environment is dropped for the children): numpy and scipy are measured from the
``.pyc`` files their install wrote, so wirecal is too, as after its first run on a user's
machine — compiling wirecal's sources on every start cost about 40 ms more.

    python bench/bench_startup.py [--runs N]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from wirecal.cli.main import GC_THRESHOLD

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"


def medians_s(
    commands: dict[str, list[str]],
    runs: int,
    warm: bool = True,
    check: bool = True,
    before_each: Callable[[str], None] | None = None,
) -> dict[str, tuple[float, float]]:
    """Median wall and CPU time (user + system) of each command, run in turn ``runs`` times.

    The CPU time counts the command's own children (those it waits for, as a process pool
    it shuts down). The CPU time of a child process hardly depends on what else the machine
    runs; the wall time does, two- to threefold on a shared machine. ``warm``: each command
    runs once unmeasured first (writing the bytecode caches); ``check``: a command that fails
    stops the benchmark; ``before_each``: called with a command's name before each of its
    runs, unmeasured, the first included.
    """
    times: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
    for name, cmd in commands.items() if warm else ():
        if before_each:
            before_each(name)
        subprocess.run(cmd, check=check, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(runs):
        for name, cmd in commands.items():
            if before_each:
                before_each(name)
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run(cmd, check=check, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            wall = time.perf_counter() - t0
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
            times[name].append((wall, cpu))
    return {
        name: (statistics.median(w for w, _ in t), statistics.median(c for _, c in t))
        for name, t in times.items()
    }


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=9)
    runs = parser.parse_args().runs
    # one BLAS thread and the collector's thresholds, as the command line sets them
    # (cli/main.py): the bare imports it is compared with start under the same settings
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")
    same_gc = f"import gc; gc.set_threshold(*{GC_THRESHOLD}); "
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)  # the children cache bytecode
    py = sys.executable
    cli = [str(Path(py).parent / "wirecal")]  # the installed console script
    robot, plan = str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")
    with tempfile.TemporaryDirectory() as tmp:
        log = str(Path(tmp) / "log.csv")
        subprocess.run(
            [*cli, "simulate", robot, plan, "-o", log], check=True, stdout=subprocess.DEVNULL
        )
        figures = medians_s(
            {
                "python -c 'import click'": [py, "-c", same_gc + "import click"],
                "python -c 'import numpy, scipy.optimize'": [
                    py,
                    "-c",
                    same_gc + "import numpy, scipy.optimize",
                ],
                "wirecal --help": [*cli, "--help"],
                "wirecal demo --help": [*cli, "demo", "--help"],
                "wirecal solve --help": [*cli, "solve", "--help"],
                "wirecal solve (Viper log)": [*cli, "solve", robot, plan, log],
            },
            runs,
        )
    click = figures["python -c 'import click'"]
    numpy = figures["python -c 'import numpy, scipy.optimize'"]
    print(
        f"median of {runs} runs each, interleaved; load average {os.getloadavg()[0]:.1f}; "
        f"bare imports with one BLAS thread and gc thresholds {GC_THRESHOLD}, as wirecal's"
    )
    print(f"{'':<42}{'wall':>8}    {'CPU':>6}    wall (CPU) ratio")
    for name, (wall, cpu) in figures.items():
        base, label = (
            (numpy, "numpy+scipy") if name.startswith("wirecal solve (") else (click, "click")
        )
        if name.startswith("python"):
            base, label = (wall, cpu), "itself"
        print(
            f"{name:<42}{wall * 1000:6.0f} ms {cpu * 1000:6.0f} ms  "
            f"{wall / base[0]:5.2f}× ({cpu / base[1]:4.2f}×) {label}"
        )


if __name__ == "__main__":
    main()
