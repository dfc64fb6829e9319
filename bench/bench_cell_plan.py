"""The safety sweeps and the pool planner: CPU of the code now against the code before.

The work the quick test loop and the twins ask of solver/cell and solver/plan most often,
each timed in a fresh process per tree (:mod:`interleaved`), the trees' runs alternating:

* ``pool plan``: the UR10's choice of θ0 and 30 poses from a pool of 300 configurations
  (:func:`~wirecal.solver.plan.pool.anchor_plans`, 24 θ0s tried), as the tracker tests
  and ``wirecal plan --pool`` make it;
* ``short moves``, per shipped arm: a random walk of 60 moves of 0.05–3° from each of 10
  random poses, each move checked with every gap exact
  (:func:`~wirecal.solver.cell.check.move_sweep`) and by a twin's successive checks
  (:class:`~wirecal.solver.cell.sweep.Sweeps`), as tests/test_sweeps.py does;
* ``cell checks``: the pre-flight's cell check (:func:`~wirecal.solver.cell.check.check_cell`)
  of each shipped plan and of the two colliding examples, 4 times each;
* ``fingerprints``: each shipped plan's fingerprint, 50 times.

Every memory of frames is forgotten before each timed call. What each made (the pool
plans' rows and predicted errors, the sweeps' answers and last gaps, the cell checks'
refusals, the fingerprints) is digested: the two trees must make the same, byte for byte.

    python bench/bench_cell_plan.py [--runs N] [--before CHECKOUT]
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path

from interleaved import bench_main

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
ARMS = ("viper_s650", "ur5e", "abb_irb120")
PLANS = {"viper_s650": "paper_plan.toml", "ur5e": "plan.toml", "abb_irb120": "plan.toml"}
COLLIDING = ("viper_s650", "ur5e")


def forget() -> None:
    """Forget the frames kept by their joints (each timed call computes its own)."""
    from wirecal.solver import kinematics

    kinematics._kept_frames.cache_clear()


def cpu_s(work: Callable[[], object], repeat: int = 3) -> tuple[float, object]:
    """Median CPU time (s) of ``repeat`` calls of ``work``, memory forgotten first; its output."""
    spent, out = [], None
    for _ in range(repeat):
        forget()
        t0 = time.process_time()
        out = work()
        spent.append(time.process_time() - t0)
    return sorted(spent)[len(spent) // 2], out


def pool_plan() -> Callable[[], bytes]:
    """Return the UR10's pool plan from 300 configurations (seed 4), as bytes of its choices."""
    import numpy as np

    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.plan.options import PlanOptions
    from wirecal.solver.plan.pool import anchor_plans

    robot = load_robot(ROOT / "tests" / "data" / "tracker" / "ur10_ipa" / "robot.toml")
    rng = np.random.default_rng(4)
    lo = np.array([-90.0, -150.0, 30.0, -150.0, 30.0, -90.0])
    hi = np.array([90.0, -40.0, 140.0, -30.0, 150.0, 90.0])
    q = rng.uniform(lo, hi, (300, 6))

    def plan() -> bytes:
        plans = anchor_plans(robot, q, 30, PlanOptions())
        return b"".join(p.rows.tobytes() + repr(p.predicted_mm).encode() for p in plans)

    return plan


def short_moves(arm: str) -> Callable[[], str]:
    """Return the checks of 10 random walks of 60 short moves (tests/test_sweeps.py's)."""
    import numpy as np

    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.cell.check import move_sweep
    from wirecal.solver.cell.sweep import Sweeps
    from wirecal.solver.kinematics import tool_position

    robot = load_robot(EXAMPLES / arm / "robot.toml")
    model = robot.model({"th2": 0.5})
    lo, hi = robot.limits_deg(body=False)

    def walks() -> str:
        answers = []
        for seed in range(10):
            rng = np.random.default_rng(seed)
            p0 = tool_position(model, np.radians(rng.uniform(lo, hi))[None])[0]
            sweeps = Sweeps(robot, model, p0, contact=bool(seed % 2))
            q = rng.uniform(lo, hi)
            for _ in range(60):
                target = np.clip(q + rng.normal(0.0, rng.choice([0.05, 0.5, 3.0]), 6), lo, hi)
                hit, last, smallest = move_sweep(robot, model, p0, q, target, bool(seed % 2))
                answers.append((hit, last.tobytes().hex(), repr(smallest)))
                answers.append(sweeps.collision(q, target))
                q = target if hit is None else q
            answers.append(sweeps.skipped)
        return json.dumps(answers)

    return walks


def cell_checks() -> Callable[[], list]:
    """Return the pre-flight's cell check of the shipped and the colliding plans: refusals."""
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.cell.check import check_cell
    from wirecal.solver.errors import WirecalError

    cases = []
    for arm, name in [*PLANS.items(), *((a, "colliding_plan.toml") for a in COLLIDING)]:
        robot = load_robot(EXAMPLES / arm / "robot.toml")
        cases.append((robot, load_plan(EXAMPLES / arm / name, robot)))

    def checked(robot, plan) -> list[str]:
        try:
            check_cell(robot, plan)
        except WirecalError as exc:
            return exc.problems
        return []

    return lambda: [checked(robot, plan) for robot, plan in cases for _ in range(4)]


def fingerprints() -> Callable[[], list[str]]:
    """Return the shipped plans' fingerprints, each asked 50 times."""
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot

    plans = [
        load_plan(EXAMPLES / arm / name, load_robot(EXAMPLES / arm / "robot.toml"))
        for arm, name in PLANS.items()
    ]
    return lambda: [p.fingerprint() for p in plans for _ in range(50)]


def child() -> None:
    """One run in this process: each figure's CPU seconds and a digest of what it made."""
    found: dict[str, dict] = {"cpu_s": {}, "digest": {}}
    made = hashlib.sha256()
    works = {"UR10 pool plan, 300 configurations": pool_plan()}
    works |= {f"{arm} 600 short moves, checked twice": short_moves(arm) for arm in ARMS}
    works["cell checks of 5 plans (2 refused), 4 each"] = cell_checks()
    works["fingerprints of 3 plans, 50 times each"] = fingerprints()
    for name, work in works.items():
        found["cpu_s"][name], out = cpu_s(work)
        made.update(name.encode() + (out if isinstance(out, bytes) else repr(out).encode()))
    found["digest"]["all"] = made.hexdigest()[:16]
    print(json.dumps(found))


def main() -> None:
    """Time this tree and ``--before``'s alternately; print the medians and ratios."""
    bench_main("bench_cell_plan", child, __doc__, "plans, answers and fingerprints")


if __name__ == "__main__":
    main()
