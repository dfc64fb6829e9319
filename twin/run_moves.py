"""The moves of a measurement run, named: the same in every controller language.

Every language's run program moves through the plan in the same order (per step θ0 for
its zero reading, the via points, the points; θ0 last for the closing zero reading); the
world counts the moves (``World.moves``), which these functions name.
"""

from __future__ import annotations

from wirecal.solver.plan.calibration_plan import Plan


def run_targets(plan: Plan) -> list[str]:
    """List what each move of the measurement run reaches, in order (move k is entry k-1).

    Per step θ0 (its zero reading), the via points, the points; last θ0 for the closing
    zero reading.
    """
    out = []
    for j, s in enumerate(plan.steps, 1):
        out.append(f"step {j} zero reading at theta0")
        out += [f"step {j} via point {i}" for i in range(1, len(s.via_deg) + 1)]
        out += [f"step {j} point {i}" for i in range(1, len(s.points_deg) + 1)]
    out.append("the closing zero reading at theta0")
    return out


def move_of_step(plan: Plan, step: int, point: int = 1) -> int:
    """Return the 1-based number of the move of the run that reaches a step's point."""
    return run_targets(plan).index(f"step {step} point {point}") + 1


def where_in_run(plan: Plan, moves: int) -> str:
    """Where the run was after ``moves`` moves (the world counts them)."""
    targets = run_targets(plan)
    return targets[moves - 1] if 1 <= moves <= len(targets) else "the start of the run"
