"""Whole-process start-up of the command line: ``wirecal --help``, ``wirecal CMD --help``
and ``wirecal solve`` (the Viper example log), median of several runs, as ratios to a bare
Python importing what they cannot avoid, measured in the same run: click for the help texts
(target ≤ 3×), numpy + scipy.optimize for ``solve`` (target ≤ 1.4×). The runs of all
commands are interleaved, so a change of the machine's load touches each alike.

    python bench/bench_startup.py [--runs N]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"


def medians_s(commands: dict[str, list[str]], runs: int) -> dict[str, float]:
    """Median wall time of each command, the commands run in turn ``runs`` times."""
    times: dict[str, list[float]] = {name: [] for name in commands}
    for _ in range(runs):
        for name, cmd in commands.items():
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            times[name].append(time.perf_counter() - t0)
    return {name: statistics.median(t) for name, t in times.items()}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=7)
    runs = parser.parse_args().runs
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
                "python -c 'import click'": [py, "-c", "import click"],
                "python -c 'import numpy, scipy.optimize'": [
                    py,
                    "-c",
                    "import numpy, scipy.optimize",
                ],
                "wirecal --help": [*cli, "--help"],
                "wirecal demo --help": [*cli, "demo", "--help"],
                "wirecal solve --help": [*cli, "solve", "--help"],
                "wirecal solve (Viper log)": [*cli, "solve", robot, plan, log],
            },
            runs,
        )
    click_s = figures["python -c 'import click'"]
    numpy_s = figures["python -c 'import numpy, scipy.optimize'"]
    print(f"median of {runs} runs each, interleaved")
    for name, t in figures.items():
        print(
            f"{name:<42}{t * 1000:8.0f} ms  {t / click_s:6.1f}× click  "
            f"{t / numpy_s:5.2f}× numpy+scipy"
        )


if __name__ == "__main__":
    main()
