"""The paper's Table 4 view of a plan: Ψ of every point in the plan's order, with a verdict."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.identifiability import Identifiability, analyse
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.sensitivity import DEFAULT_TOL, PSI_FLOOR, sensitivity, verdict


@dataclass(frozen=True)
class PsiRow:
    """One calibration point: Ψ of every parameter (paper Table 4) and its verdict."""

    step: int  # 1-based
    index: int  # 1-based within the step
    parameter: str  # the step's parameter
    joints_deg: np.ndarray  # (n,)
    psi: dict[str, float]  # per parameter, the plan's order (mm/deg or mm/mm)
    ok: bool
    violations: tuple[str, ...]  # later parameters whose |Ψ| exceeds the tolerance


@dataclass(frozen=True)
class PsiTable:
    """Ψ rows and verdicts for every step and point of a plan, nominal model."""

    robot: str
    fingerprint: str
    theta0_deg: np.ndarray
    tolerance: float
    floor: float
    order: tuple[str, ...]
    rows: tuple[PsiRow, ...]
    identifiability: Identifiability

    @property
    def n_ok(self) -> int:
        """Return the number of rows that pass."""
        return sum(r.ok for r in self.rows)


def psi_table(robot: Robot, plan: Plan, tol: float = DEFAULT_TOL) -> PsiTable:
    """Ψ rows and verdicts for every step and point (1-based step and index), nominal model.

    The parameters' steps: a payload step isolates none (it is for the compliances).
    """
    model = robot.nominal
    q, step_no, index = plan.all_points()
    psi = sensitivity(model, q, plan.theta0_deg, plan.order).psi
    rows = []
    for k in np.flatnonzero(step_no <= len(plan.order)):
        j = int(step_no[k]) - 1
        row = {name: float(psi[k, c]) for c, name in enumerate(plan.order)}
        v = verdict(row, plan.order[j], plan.order[j + 1 :], tol)
        rows.append(PsiRow(j + 1, int(index[k]), plan.order[j], q[k], row, v.ok, v.violations))
    return PsiTable(
        robot=robot.name,
        fingerprint=plan.fingerprint(),
        theta0_deg=plan.theta0_deg,
        tolerance=tol,
        floor=PSI_FLOOR,
        order=plan.order,
        rows=tuple(rows),
        identifiability=analyse(model, q, plan.theta0_deg, plan.order),
    )
