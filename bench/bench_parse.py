"""What the three parsers and checkers cost: now against the code before, and the same outcomes.

Each run is a fresh process per tree (``--before``: a checkout of the code before, run with
the same interpreter and that checkout first on ``PYTHONPATH``), the two trees' runs
interleaved: it builds the three grammars (timed), refuses a RAPID expression nested too
deep (the tree parser that names its line built then, timed), then parses each language's shipped
generated programs (tests/golden, tests/data/payload_*) once, nothing kept before (a RAPID
module; a V+ module and a URScript program read line by line, each distinct line parsed
once), then again with the modules forgotten but the lines kept (as a process parsing
another module of the same robot meets them), then checks them (lint, the parses kept);
last the tests' texts (the parse identity corpus of ``tests/parse_reference.py``: examples,
windows of the golden programs, nested expressions; each parsed and, if short, linted).
CPU seconds (``time.process_time``; the garbage collected before each step, so that
a full collection falls into the same step in both trees), median of ``--runs``, and the
ratio now / before.

``--mutated N`` compares instead what the two trees make of N texts that are not in the
repository, drawn with ``--seed``: windows of the golden programs and whole ones, most
mutated (lines dropped, doubled or swapped, characters dropped or inserted, numbers
changed): each text's parse (the node tree written out in full, or the problems) and, for a
short one, its lint problems must be the same; it prints how many were compared, how many
each tree refused, and every text that differs.

    python bench/bench_parse.py --before ../before [--runs 5]
    python bench/bench_parse.py --before ../before --mutated 3000 [--seed 1]
"""

from __future__ import annotations

import argparse
import gc
import importlib.util
import json
import random
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

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


def _reference() -> Any:
    """This tree's ``tests/parse_reference.py`` (the corpus, the outcomes written out)."""
    spec = importlib.util.spec_from_file_location("parse_reference", TESTS / "parse_reference.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _forget_modules() -> None:
    """Forget every module and program kept (the lines stay kept)."""
    from wirecal.lang.rapid import parser as rapid
    from wirecal.lang.urscript import parser as urscript
    from wirecal.lang.vplus import parser as vplus

    for kept in (rapid._parse_long, rapid._parse_short):
        kept.cache_clear()
    vplus._parse_module.cache_clear()
    urscript._parse_program.cache_clear()


def child() -> None:
    """One run in this process: print the CPU seconds of each step as JSON."""
    from wirecal.lang.registry import language

    texts = {
        key: [(TESTS / p).read_text(encoding="utf-8") for p in paths]
        for key, paths in PROGRAMS.items()
    }
    reference = _reference()
    corpus = reference.corpus()
    t0 = time.process_time()
    parsers = _parsers()
    found = {"grammars": time.process_time() - t0}
    from wirecal.lang.rapid.parser import SyntaxProblem

    gc.collect()
    t0 = time.process_time()
    try:  # an expression 101 deep: the parse stops, the tree parser names the line
        parsers["rapid"][0](reference._module("x := 1" + " + 1" * 101 + ";"))
        raise AssertionError("an expression 101 deep was not refused")
    except SyntaxProblem:
        found["rapid too deep"] = time.process_time() - t0
    for key, (parse, forget) in parsers.items():
        for step in ("", " again"):
            forget()
            gc.collect()  # each step from the same collector's state in both trees
            t0 = time.process_time()
            for text in texts[key]:
                parse(text)
            found[key + step] = time.process_time() - t0
    for key in parsers:
        _forget_modules()
        for text in texts[key]:  # parsed and kept: the check alone is timed
            parsers[key][0](text)
        if key != "rapid":  # V+'s and URScript's checks are their modules' parse
            _forget_modules()
        gc.collect()  # each step from the same collector's state in both trees
        t0 = time.process_time()
        for text in texts[key]:
            assert language(key).lint(text, "t") == []
        found[key + " check"] = time.process_time() - t0
    _forget_modules()
    gc.collect()  # each step from the same collector's state in both trees
    t0 = time.process_time()
    for key, text in corpus.values():
        reference.outcome(key, text)
    found["tests' texts"] = time.process_time() - t0
    print(json.dumps(found))


def _mutated(text: str, rng: random.Random) -> str:
    """``text`` with none to three mutations (see the module's docstring)."""
    lines = text.split("\n")
    for _ in range(rng.randint(0, 3)):
        k = rng.randrange(len(lines))
        how = rng.randrange(6)
        if how == 0 and len(lines) > 1:
            del lines[k]
        elif how == 1:
            lines.insert(k, lines[k])
        elif how == 2 and k + 1 < len(lines):
            lines[k], lines[k + 1] = lines[k + 1], lines[k]
        elif how == 3 and lines[k]:
            at = rng.randrange(len(lines[k]))
            lines[k] = lines[k][:at] + lines[k][at + 1 :]
        elif how == 4:
            at = rng.randrange(len(lines[k]) + 1)
            lines[k] = lines[k][:at] + rng.choice(_INSERTED) + lines[k][at:]
        else:
            number = str(rng.choice([0, 1, 7, 99999999999]))
            lines[k] = re.sub(r"\d+", number, lines[k], count=1)
    return "\n".join(lines)


_INSERTED = [*"()[]{};:,.=+-*/\\\"'!#%$^ \t", "\n", "END", "ENDIF", "IF", "x", "1e400"]


def mutated_texts(count: int, seed: int) -> list[tuple[str, str]]:
    """``count`` mutated texts (language key, text) drawn with ``seed``: one in 50 whole."""
    reference = _reference()
    rng = random.Random(seed)
    wraps = {"rapid": reference._module, "vplus": reference._vplus, "urscript": reference._urscript}
    sources = {k: [(TESTS / p).read_text(encoding="utf-8") for p in v] for k, v in PROGRAMS.items()}
    out = []
    for n in range(count):
        key = list(PROGRAMS)[n % 3]
        text = rng.choice(sources[key])
        if n % 50:
            lines = text.splitlines()
            k = rng.randrange(len(lines))
            text = wraps[key](*lines[k : k + rng.randint(1, 60)])
        out.append((key, _mutated(text, rng)))
    return out


def child_outcomes(count: int, seed: int) -> None:
    """Print, as JSON, the outcome of each of :func:`mutated_texts`."""
    reference = _reference()
    found = [reference.outcome(key, text) for key, text in mutated_texts(count, seed)]
    print(json.dumps(found))


def _run(tree: Path, call: str = "child()") -> Any:
    """Run ``call`` (of this module) on the code in ``tree``; what it printed, read as JSON."""
    bench = str(NOW / "bench")
    code = f"import sys; sys.path.insert(0, {bench!r}); import bench_parse; bench_parse.{call}"
    out = subprocess.run(
        [sys.executable, "-P", "-c", code],
        env={"PYTHONPATH": str(tree), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def compare(before: Path, count: int, seed: int) -> None:
    """Print how the two trees' outcomes of :func:`mutated_texts` compare."""
    call = f"child_outcomes({count}, {seed})"
    old, new = _run(before, call), _run(NOW, call)
    texts = mutated_texts(count, seed)
    differ = [k for k in range(count) if old[k] != new[k]]
    refused = [sum(not str(o["parse"]).startswith("tree") for o in r) for r in (old, new)]
    linted = sum("lint" in o for o in new)
    print(
        f"{count} mutated texts (seed {seed}; {linted} linted too): parses refused before "
        f"{refused[0]}, now {refused[1]}; outcomes that differ: {len(differ)}"
    )
    for k in differ:
        print(f"--- {texts[k][0]} text {k}:\n{texts[k][1]}\nbefore: {old[k]}\nnow: {new[k]}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, help="a checkout of the code before")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--mutated", type=int, default=0, help="compare the outcomes of N texts")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    if args.mutated:
        compare(args.before.resolve(), args.mutated, args.seed)
        return
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
