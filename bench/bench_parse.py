"""What the three parsers cost: the golden and payload programs parsed, now against the code before.

Each run is a fresh process per tree (``--before``: a checkout of the code before, run with
the same interpreter and that checkout first on ``PYTHONPATH``), the two trees' runs
interleaved: it builds the three grammars (timed), then parses each language's programs
(tests/golden, tests/data/payload_*) once, nothing kept before (a RAPID module; a V+ module
and a URScript program read line by line, each distinct line parsed once), then again with
the modules forgotten but the lines kept (as a process parsing another module of the same
robot meets them). CPU seconds (``time.process_time``), median of ``--runs``, and the
ratio now / before.

    python bench/bench_parse.py --before ../before [--runs 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

NOW = Path(__file__).resolve().parents[1]
TESTS = NOW / "tests"
PROGRAMS = {
    "rapid": ["golden/abb_irb120/WIRECAL.mod", "data/payload_abb_irb120/WIRECAL.mod"],
    "vplus": ["golden/viper_s650/WIRECAL.V2", "data/payload_viper_s650/WIRECAL.V2"],
    "urscript": [
        "golden/ur5/wc_run.script",
        "golden/ur5e/wc_run.script",
        "data/payload_ur5e/wc_run.script",
    ],
}


def _parsers() -> dict:
    """Each language's (parse a text, forget the modules kept); the grammars built."""
    from wirecal.lang.rapid import parser as rapid
    from wirecal.lang.urscript import parser as urscript
    from wirecal.lang.vplus import parser as vplus

    def rapid_forget() -> None:
        rapid._parse_long.cache_clear()
        rapid._parse_short.cache_clear()

    rapid._parser()
    vplus._parser()
    urscript._parser()
    return {
        "rapid": (rapid.parse_module, rapid_forget),
        "vplus": (lambda t: vplus.parse_module(t, "m"), vplus._parse_module.cache_clear),
        "urscript": (
            lambda t: urscript.parse_program(t, "p"),
            urscript._parse_program.cache_clear,
        ),
    }


def child() -> None:
    """One run in this process: print the CPU seconds of each step as JSON."""
    texts = {
        key: [(TESTS / p).read_text(encoding="utf-8") for p in paths]
        for key, paths in PROGRAMS.items()
    }
    t0 = time.process_time()
    parsers = _parsers()
    found = {"grammars": time.process_time() - t0}
    for key, (parse, forget) in parsers.items():
        for step in ("", " again"):
            forget()
            t0 = time.process_time()
            for text in texts[key]:
                parse(text)
            found[key + step] = time.process_time() - t0
    print(json.dumps(found))


def _run(tree: Path) -> dict[str, float]:
    """Run :func:`child` on the code in ``tree``; its figures."""
    bench = str(NOW / "bench")
    code = f"import sys; sys.path.insert(0, {bench!r}); import bench_parse; bench_parse.child()"
    out = subprocess.run(
        [sys.executable, "-P", "-c", code],
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, help="a checkout of the code before")
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    runs: dict[str, list[dict[str, float]]] = {"before": [], "now": []}
    for _ in range(args.runs):
        runs["before"].append(_run(args.before.resolve()))
        runs["now"].append(_run(NOW))
    print(f"CPU s, median of {args.runs} runs each, interleaved")
    print(f"{'step':24} {'before':>8} {'now':>8} {'ratio':>6}")
    for step in runs["now"][0]:
        before = statistics.median(r[step] for r in runs["before"])
        now = statistics.median(r[step] for r in runs["now"])
        print(f"{step:24} {before:8.3f} {now:8.3f} {now / before:6.2f}")
    total = {
        k: statistics.median(sum(v for s, v in r.items() if s != "grammars") for r in rs)
        for k, rs in runs.items()
    }
    ratio = total["now"] / total["before"]
    print(f"{'all parses':24} {total['before']:8.3f} {total['now']:8.3f} {ratio:6.2f}")


if __name__ == "__main__":
    main()
