"""The θ0 search of ``wirecal plan`` against the full search, per shipped arm and seed.

The full search finishes every one of the first ``THETA0_TRIES`` θ0s and keeps the best
plan; ``wirecal plan`` finishes only those its rule picks by the staged rank
(``planner._best_finished``: the ``THETA0_FINISHED`` ranked first and any within
``THETA0_CLOSE`` of the first). Each θ0 is staged and finished once here; the rule runs on
the same finished designs, so the two searches are compared on the same plans. Per arm and
seed: the θ0 each keeps, their predicted errors (joint, step-by-step, mm) and robot time
(min), the staged position of the full search's θ0 (and its staged rank over the
first's) and how many θ0s the rule finishes. Ends with the count of searches where the
rule keeps another θ0 and where that plan ranks worse. One core (BLAS on one thread),
the joint method.

    python bench/bench_theta0_search.py [--arms viper_s650 ur5e] [--seeds 0-9]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.errors import WirecalError  # noqa: E402
from wirecal.solver.plan import planner  # noqa: E402
from wirecal.solver.plan.design import Design, Steps, design_steps, finish  # noqa: E402
from wirecal.solver.plan.options import PlanOptions  # noqa: E402

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ARMS = ("viper_s650", "ur5e", "abb_irb120", "puma560")


def _finished(staged: list[Steps]) -> list[Design | WirecalError]:
    """Return each staged θ0's finished plan, or why its finish failed."""
    out: list[Design | WirecalError] = []
    for s in staged:
        try:
            out.append(finish(s))
        except WirecalError as exc:
            out.append(exc)
    return out


def _rule_pick(staged: list[Steps], done: list[Design | WirecalError]) -> tuple[Design | None, int]:
    """Return the plan ``wirecal plan``'s rule keeps of ``done`` and how many it finishes."""
    by_id = {id(s): d for s, d in zip(staged, done, strict=True)}
    calls: list[int] = []

    def cached(s: Steps, progress=None) -> Design:
        calls.append(id(s))
        d = by_id[id(s)]
        if isinstance(d, WirecalError):
            raise d
        return d

    real, planner.finish = planner.finish, cached
    try:
        best = planner._best_finished(staged, [], lambda k: None)
    finally:
        planner.finish = real
    return best, len(calls)


def _line(d: Design) -> str:
    """Return a plan's θ0 and predictions in words."""
    p = d.predicted
    return (
        f"{[int(v) for v in d.plan.theta0_deg]} joint {p['joint']:.4f} step {p['stepwise']:.4f} "
        f"{d.robot_time_s / 60:.2f} min"
    )


def compare(arm: str, seed: int) -> tuple[bool, bool]:
    """Print the full search's plan and the rule's for one arm and seed.

    Return whether the rule keeps another θ0 and whether its plan ranks worse.
    """
    robot = load_robot(EXAMPLES / arm / "robot.toml")
    opt = PlanOptions(seed=seed)
    staged: list[Steps] = []
    for t0 in planner._theta0_draws(robot, opt)[: planner.THETA0_TRIES]:
        try:
            staged.append(design_steps(robot, t0, opt))
        except WirecalError:
            continue
    done = _finished(staged)
    plans = [d for d in done if isinstance(d, Design)]
    full = min(plans, key=planner._score) if plans else None  # ties: the first drawn
    rule, n_finished = _rule_pick(staged, done)
    ranked = sorted(range(len(staged)), key=lambda k: staged[k].rank)
    where = next((i for i, k in enumerate(ranked) if done[k] is full), -1)
    ratio = staged[ranked[where]].rank[1] / staged[ranked[0]].rank[1] if where >= 0 else 0.0
    other = full is not rule
    worse = other and (
        rule is None or (full is not None and planner._score(full) < planner._score(rule))
    )
    print(
        f"{arm:11s} seed {seed}: full {_line(full) if full else 'none'} (staged #{where + 1}, "
        f"{ratio:.3f}x the first's rank); "
        f"finished {n_finished}/{len(staged)}"
        + (f"; RULE KEEPS {_line(rule) if rule else 'none'}" if other else "; same")
    )
    return other, worse


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--arms", nargs="+", default=ARMS, choices=ARMS)
    ap.add_argument("--seeds", default="0-9", help="first-last (inclusive)")
    args = ap.parse_args()
    first, last = (int(v) for v in args.seeds.split("-"))
    results = [compare(arm, seed) for arm in args.arms for seed in range(first, last + 1)]
    print(
        f"{len(results)} searches: the rule keeps another θ0 in {sum(o for o, _ in results)}, "
        f"a worse plan in {sum(w for _, w in results)}"
    )


if __name__ == "__main__":
    main()
