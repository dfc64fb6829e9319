"""The paper's Table 4 view of a plan: Ψ of every point in the plan's order, with a verdict."""

from __future__ import annotations

from typing import Any

from wirecal.solver.identifiability import analyse
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import DEFAULT_TOL, PSI_FLOOR, sensitivity, verdict


def psi_table(robot: Robot, plan: Plan, tol: float = DEFAULT_TOL) -> dict[str, Any]:
    """Ψ rows and verdicts for every step and point (1-based step and index), nominal model.

    The dictionary is what ``wirecal psi --json`` prints.
    """
    model = robot.nominal
    q, step_no, index = plan.all_points()
    psi = sensitivity(model, q, plan.theta0_deg, plan.order).psi
    rows = []
    for k in range(len(q)):
        j = int(step_no[k]) - 1
        row = {name: float(psi[k, c]) for c, name in enumerate(plan.order)}
        v = verdict(row, plan.order[j], plan.order[j + 1 :], tol)
        rows.append(
            {
                "step": j + 1,
                "index": int(index[k]),
                "parameter": plan.order[j],
                "joints_deg": [float(x) for x in q[k]],
                "psi": row,
                "ok": v.ok,
                "violations": list(v.violations),
            }
        )
    ident = analyse(model, q, plan.theta0_deg, plan.order)
    return {
        "robot": robot.name,
        "fingerprint": plan.fingerprint(),
        "theta0_deg": [float(x) for x in plan.theta0_deg],
        "tolerance": tol,
        "floor": PSI_FLOOR,
        "order": list(plan.order),
        "rows": rows,
        "identifiability": {
            "parameters": list(ident.names),
            "rank": ident.rank,
            "singular_values": [float(s) for s in ident.singular_values],
            "unobservable": list(ident.unobservable),
            "combinations": [{n: c for n, c in combo} for combo in ident.combinations],
            "indices": ident.indices,
            "summary": ident.describe(),
        },
    }
