"""What reading a log costs: the shipped arms' logs and a 10,000-row log, now and before.

The logs are written once, by this tree: a simulated run of each shipped arm's plan (the
Puma has none; the nominal robot, seed 1), each as the file the controller writes and as a
terminal capture of it (progress lines between the rows, broken at 60 columns), a
10,000-row log (the Viper's rows repeated, renumbered) in both forms, and a damaged log the
reader refuses. Each run is a fresh process per tree (``--before``: a checkout of the code
before, run with the same interpreter and that checkout first on ``PYTHONPATH``), the two
trees' runs interleaved; a run reads every log ``--repeat`` times (``parse_log``, the text
in memory). CPU seconds (``time.process_time``) per reading, median of ``--runs``, the
ratio now / before, and whether the two trees read each log alike: a digest of the
readings (every field, the joints' bits), the notes, the version, or of the refusal's
messages.

    python bench/bench_log.py --before ../before [--runs 5] [--repeat 20]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import statistics
import tempfile
import time
from pathlib import Path

from interleaved import interleaved

NOW = Path(__file__).resolve().parents[1]
EXAMPLES = NOW / "examples"
ARMS = {
    "viper_s650": "paper_plan.toml",
    "ur5": "plan.toml",
    "ur5e": "plan.toml",
    "abb_irb120": "plan.toml",
}
BIG_ROWS = 10_000
WIDTH = 60


def _capture(text: str) -> str:
    """``text`` as a terminal shows it: a progress line every tenth row, rows broken."""
    from wirecal.formats.capture import fold

    lines = text.splitlines()
    shown = []
    for k, line in enumerate(lines):
        if k % 10 == 9:
            shown.append(f"Moving to position {k} of {len(lines)}")
        shown.append(line)
    return "> wc_run started\n" + fold(shown, WIDTH)


def _renumbered(row: str, k: int) -> str:
    """``row`` with index ``k + 1``: every row of the long log a distinct text."""
    kind, step, _index, rest = row.split(",", 3)
    return f"{kind},{step},{k + 1},{rest}"


def logs() -> dict[str, str]:
    """Every log the bench reads, by name (the texts written by this tree)."""
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.formats.simulated_log import simulate_log

    texts = {}
    for arm, plan in ARMS.items():
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        texts[arm] = simulate_log(robot, load_plan(EXAMPLES / arm / plan, robot), {}, seed=1)
    lines = texts["viper_s650"].splitlines()
    head = [line for line in lines if line.startswith("#") or line.startswith("kind,")]
    rows = [line for line in lines if line not in head]
    big = [_renumbered(row, k) for k, row in enumerate((rows * BIG_ROWS)[:BIG_ROWS])]
    texts["10000 rows"] = "\n".join(head + big) + "\n"
    for name in list(texts):
        texts[name + " (capture)"] = _capture(texts[name])
    damaged = [*head, *rows[:40]]
    damaged[len(head) + 3] = damaged[len(head) + 3].replace(",", ",x", 1)
    damaged[len(head) + 7] = "point,1,2,nan" + damaged[len(head) + 7][13:]
    damaged[len(head) + 9] = damaged[len(head) + 9].rsplit(",", 2)[0] + ",-1,3.0"
    texts["damaged (refused)"] = "\n".join(damaged) + "\n"
    return texts


def _digest(text: str) -> str:
    """A digest of what ``parse_log`` makes of ``text``: the log read, or its refusal."""
    from wirecal.formats.log import parse_log
    from wirecal.solver.errors import WirecalError

    try:
        log = parse_log(text, "run.csv")
    except WirecalError as e:
        return hashlib.sha256(str(e).encode()).hexdigest()[:16]
    fields = [
        (r.kind, r.step, r.index, r.joints_deg.tobytes().hex(), r.counts.hex(), r.samples)
        for r in log.readings
    ]
    times = [(r.spread.hex(), r.line, r.t_s, r.settle_s) for r in log.readings]
    whole = (
        fields,
        times,
        log.notes,
        log.version,
        log.robot,
        log.plan,
        log.mm_per_count,
        log.sha256,
    )
    return hashlib.sha256(repr(whole).encode()).hexdigest()[:16]


def child(path: str, repeat: str) -> None:
    """One run in this process: print each log's CPU seconds per reading and digest (JSON)."""
    from wirecal.formats.log import parse_log
    from wirecal.solver.errors import WirecalError

    texts = json.loads(Path(path).read_text(encoding="utf-8"))
    found = {}
    for name, text in texts.items():
        t0 = time.process_time()
        for _ in range(int(repeat)):
            try:
                parse_log(text, "run.csv")
            except WirecalError:
                pass
        found[name] = ((time.process_time() - t0) / int(repeat), _digest(text))
    print(json.dumps(found))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, help="a checkout of the code before")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=20, help="readings of each log per run")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "logs.json")
        texts = logs()
        Path(path).write_text(json.dumps(texts), encoding="utf-8")
        runs = interleaved("bench_log", args.before, args.runs, path, str(args.repeat))
    print(f"CPU ms per reading, median of {args.runs} runs each ({args.repeat} readings each)")
    print(f"{'log':30} {'lines':>6} {'before':>8} {'now':>8} {'ratio':>6}  same result")
    totals = {"before": 0.0, "now": 0.0}
    for name, text in texts.items():
        ms = {k: statistics.median(r[name][0] for r in rs) * 1e3 for k, rs in runs.items()}
        same = {r[name][1] for rs in runs.values() for r in rs}
        for k in totals:
            totals[k] += ms[k]
        lines = text.count("\n")
        ratio = ms["now"] / ms["before"]
        figures = f"{ms['before']:8.2f} {ms['now']:8.2f} {ratio:6.2f}"
        print(f"{name:30} {lines:6d} {figures}  {len(same) == 1}")
    ratio = totals["now"] / totals["before"]
    print(f"{'all logs':30} {'':6} {totals['before']:8.2f} {totals['now']:8.2f} {ratio:6.2f}")


if __name__ == "__main__":
    main()
