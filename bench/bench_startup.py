"""Whole-process start-up of the command line: ``wirecal --help`` and ``wirecal solve``
(the Viper example log), median of several runs, as ratios to a bare Python importing click
and importing numpy + scipy.optimize on the same machine.

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


def median_s(cmd: list[str], runs: int) -> float:
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


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
        figures = {
            "python -c 'import click'": median_s([py, "-c", "import click"], runs),
            "python -c 'import numpy, scipy.optimize'": median_s(
                [py, "-c", "import numpy, scipy.optimize"], runs
            ),
            "wirecal --help": median_s([*cli, "--help"], runs),
            "wirecal solve (Viper log)": median_s([*cli, "solve", robot, plan, log], runs),
        }
    click_s = figures["python -c 'import click'"]
    numpy_s = figures["python -c 'import numpy, scipy.optimize'"]
    print(f"median of {runs} runs each")
    for name, t in figures.items():
        print(
            f"{name:<42}{t * 1000:8.0f} ms  {t / click_s:6.1f}× click  "
            f"{t / numpy_s:5.2f}× numpy+scipy"
        )


if __name__ == "__main__":
    main()
