"""Where people wait: ``wirecal plan`` of every shipped arm, ``wirecal demo`` and (optional)
the quick test loop and the whole suite, each timed as a whole process against the same
command run on the code before, in one run.

Each tree's test loops run as its own README gives them (:func:`readme_tests`), so the code
before runs its whole suite in one process and the code now on pytest-xdist's workers, with
the BLAS thread settings of the bench's shell (the commands timed set one thread, as
``wirecal`` does).
CPU time (user + system of the child and its children, which the machine's load touches far
less than the wall time; the demo's second process and pytest-xdist's workers included) and
wall time, median of
``--runs`` runs (the test loops: ``--test-runs``, one by default, timed whether or not a test
fails); each command runs once unmeasured first; the runs of the code before
and now are interleaved, so a change of the machine's load touches both alike, and each
figure is given as the ratio now / before. The code before is a checkout of it (for example
``git worktree add --detach ../before main``) given as ``--before``; its commands run with
the same interpreter and that checkout first on ``PYTHONPATH``. Every plan file written by
the two is compared byte for byte.

    python bench/bench_speed.py --before ../before [--runs 3] [--arms viper_s650 ur5e]
        [--no-demo] [--quick-loop] [--suite] [--test-runs 1] [--no-bytecode-cache]

The test loops run as a developer's second loop runs: the unmeasured first run writes each
tree's bytecode and rewritten tests (into a folder of the bench's) and Hypothesis's own caches
(its Unicode tables, about 1.5 s of CPU the first time, and the constants it reads from the
sources), in a Hypothesis folder of each tree's under the bench's; its example database is
emptied before every run, so a failure one run saved is not replayed and shrunk in the next.
``--no-bytecode-cache`` times them also with ``PYTHONDONTWRITEBYTECODE=1``, as a shell that
sets it runs them (every module of the tree compiled and every test module's asserts
rewritten again in every run).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import sys
import tempfile
from pathlib import Path

THREADS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
SHELL_THREADS = {var: os.environ.get(var) for var in THREADS}
"""The BLAS thread settings of the shell the bench started in (:func:`_pytest`), read before
``wirecal.cli.main`` (which bench_startup imports) sets them."""

from bench_startup import medians_s  # noqa: E402 - after reading the shell's settings

NOW = Path(__file__).resolve().parents[1]
ARMS = ("viper_s650", "ur5e", "abb_irb120", "puma560")


def _wirecal(tree: Path, *args: str) -> list[str]:
    """Return the command running ``wirecal ARGS`` on the code in ``tree``."""
    main = "from wirecal.cli.main import main; main()"
    # -P: the working folder (which may hold another checkout's wirecal) not on sys.path
    return ["env", f"PYTHONPATH={tree}", sys.executable, "-P", "-c", main, *args]


def readme_tests(tree: Path) -> dict[str, list[str]]:
    """Return the arguments of the quick loop and the whole suite as ``tree``'s README gives them.

    The quick loop: the README's command line ``pytest … -m "not slow"``; the whole suite:
    the first other ``pytest …`` it quotes in backticks (``pytest -q -n auto --dist
    loadfile``, or the code before pytest-xdist's ``pytest -q``).
    """
    text = (tree / "README.md").read_text(encoding="utf-8")
    lines = [line for line in text.splitlines() if line.startswith("pytest ")]
    quick = next(shlex.split(line)[1:] for line in lines if "not slow" in line)
    quoted = re.findall(r"`(pytest [^`]*)`", text)
    suite = next(shlex.split(q)[1:] for q in quoted if "not slow" not in q)
    return {"quick loop": quick, "whole suite": suite}


def _pytest(tree: Path, args: list[str]) -> list[str]:
    """Return the command running ``pytest ARGS`` on the tests of ``tree``.

    With the BLAS thread settings of the bench's shell (none set: numpy's default), as the
    README's command runs there; the commands the bench times set theirs as ``wirecal`` does.
    """
    unset = [arg for var, value in SHELL_THREADS.items() if value is None for arg in ("-u", var)]
    run = ["env", *unset, f"PYTHONPATH={tree}", sys.executable, "-P", "-m", "pytest", *args]
    return [*run, "-p", "no:cacheprovider", "--rootdir", str(tree), str(tree / "tests")]


def _commands(trees: dict[str, Path], tmp: Path, arms, demo: bool):
    """Return the commands of plan and demo to time: (figure, tree's name) → command."""
    out: dict[tuple[str, str], list[str]] = {}
    for arm in arms:
        for name, tree in trees.items():
            robot = str(tree / "examples" / arm / "robot.toml")
            plan = str(tmp / f"{name}_{arm}.toml")
            out[(f"plan {arm}", name)] = _wirecal(tree, "plan", robot, "-o", plan, "--force")
    for name, tree in trees.items():
        if demo:
            folder = str(tmp / f"{name}_demo")
            out[("demo", name)] = _wirecal(tree, "demo", "-o", folder, "--force")
    return out


def _test_commands(trees: dict[str, Path], wanted: dict[str, bool], tmp: Path, uncached: bool):
    """Return the test loops to time: (figure, tree's name) → command.

    Each tree's bytecode and rewritten tests kept in a folder of its own under ``tmp``
    (``PYTHONPYCACHEPREFIX``), as a developer's loop runs; ``uncached`` adds each loop again
    with ``PYTHONDONTWRITEBYTECODE=1`` and no folder, as a shell that sets it runs (the
    installed libraries' bytecode read, every module of the tree compiled and every test
    module's asserts rewritten in every run). Either way, Hypothesis keeps its files in
    :func:`_hypothesis_folder`.
    """
    out: dict[tuple[str, str], list[str]] = {}
    for variant in ("", ", no bytecode cache") if uncached else ("",):
        for name, tree in trees.items():
            for loop, args in readme_tests(tree).items():
                if wanted[loop]:
                    env = "PYTHONDONTWRITEBYTECODE=1" if variant else _cache_of(tmp, name)
                    hypothesis = f"HYPOTHESIS_STORAGE_DIRECTORY={_hypothesis_folder(tmp, name)}"
                    out[(loop + variant, name)] = ["env", env, hypothesis, *_pytest(tree, args)]
    return out


def _cache_of(tmp: Path, name: str) -> str:
    """Return the setting that keeps tree ``name``'s bytecode in a folder under ``tmp``."""
    return f"PYTHONPYCACHEPREFIX={tmp / ('pycache_' + name)}"


def _hypothesis_folder(tmp: Path, name: str) -> Path:
    """Return the folder of Hypothesis's files for tree ``name``'s loops, under ``tmp``."""
    return tmp / f"hypothesis_{name}"


def _test_times(trees: dict[str, Path], args: argparse.Namespace, tmp: Path):
    """Return the test loops' median (wall s, CPU s), keyed (figure, tree's name).

    Each loop runs once unmeasured first (:mod:`bench_speed`'s docstring), and Hypothesis's
    example database of its tree is emptied before every run.
    """
    wanted = {"quick loop": args.quick_loop, "whole suite": args.suite}
    tests = _test_commands(trees, wanted, tmp, args.no_bytecode_cache)
    for tree in trees.values() if args.no_bytecode_cache else ():
        if any(p.is_dir() for p in tree.rglob("__pycache__") if ".venv" not in p.parts):
            print(f"note: {tree} holds __pycache__ folders, which the uncached loops read")
    if not tests:
        return {}
    flat = {f"{fig} | {name}": cmd for (fig, name), cmd in tests.items()}

    def empty_examples(key: str) -> None:
        shutil.rmtree(_hypothesis_folder(tmp, key.split(" | ")[1]) / "examples", True)

    times = medians_s(flat, args.test_runs, warm=True, check=False, before_each=empty_examples)
    return {key: times[f"{key[0]} | {key[1]}"] for key in tests}


def _timed(cmds: dict[tuple[str, str], list[str]], runs: int):
    """Return each command's median (wall s, CPU s), keyed as ``cmds``: warm, checked."""
    if not cmds:
        return {}
    flat = {f"{fig} | {name}": cmd for (fig, name), cmd in cmds.items()}
    times = medians_s(flat, runs)
    return {key: times[f"{key[0]} | {key[1]}"] for key in cmds}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True, help="a checkout of the code before")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--arms", nargs="*", default=list(ARMS), choices=ARMS)
    ap.add_argument("--no-demo", action="store_true", help="leave out wirecal demo")
    ap.add_argument("--quick-loop", action="store_true", help="time pytest -m 'not slow' too")
    ap.add_argument("--suite", action="store_true", help="time the whole suite (pytest) too")
    ap.add_argument("--test-runs", type=int, default=1, help="runs of each test loop")
    ap.add_argument(
        "--no-bytecode-cache",
        action="store_true",
        help="time the test loops also with PYTHONDONTWRITEBYTECODE=1 (nothing cached)",
    )
    args = ap.parse_args()
    trees = {"before": args.before.resolve(), "now": NOW}
    for var in THREADS:
        os.environ.setdefault(var, "1")  # as the command line sets them (not the test loops)
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)  # the children cache bytecode, as CI's
    os.environ.pop("PYTHONPYCACHEPREFIX", None)
    print(f"load average at the start: {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        cmds = _commands(trees, Path(tmp), args.arms, not args.no_demo)
        times = _timed(cmds, args.runs)
        tests = _test_times(trees, args, Path(tmp))
        times |= tests
        same = {
            arm: (Path(tmp) / f"before_{arm}.toml").read_bytes()
            == (Path(tmp) / f"now_{arm}.toml").read_bytes()
            for arm in args.arms
        }
    print(f"load average at the end: {os.getloadavg()[0]:.1f}; median of {args.runs} runs")
    if tests:
        print(
            f"(the test loops: median of {args.test_runs} run(s) after an unmeasured one; "
            "Hypothesis's example database emptied before each)"
        )
    print("| figure | before: CPU s / wall s | now: CPU s / wall s | ratio CPU (wall) |")
    print("|---|---|---|---|")
    for fig in dict.fromkeys(fig for fig, _ in times):
        (bw, bc), (nw, nc) = times[(fig, "before")], times[(fig, "now")]
        ratio = f"{nc / bc:.2f} ({nw / bw:.2f})"
        print(f"| {fig} | {bc:.2f} / {bw:.2f} | {nc:.2f} / {nw:.2f} | {ratio} |")
    for name, tree in trees.items():
        for loop, given in readme_tests(tree).items():
            if (loop, name) in tests:
                print(f"{loop}, {name}: pytest {shlex.join(given)} (its README's)")
    for arm, equal in same.items():
        print(f"plan file of {arm}: {'byte for byte the same' if equal else 'DIFFERS'}")


if __name__ == "__main__":
    main()
