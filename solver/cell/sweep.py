"""A run's successive collision checks, each skipped where a bound proves the move clear.

A twin checks every move of a run (:func:`~wirecal.solver.cell.check.move_sweep`), and
most moves of a probe's search are a millimetre or less. Along a joint path, a point of
the arm beyond joint j turns about axis j at a distance of at most L_j, the length of the
chain beyond it (|a| and |d| of its own and the later rows, and the tool point), so it moves
by at most Σ_j |Δq_j|·L_j (rad, mm). A gap between two capsules then changes by at most
twice that, a gap to the floor, a half-space or the housing by that, and a gap to a box
by that and half the box's sampling step (:data:`~wirecal.solver.cell.model.BOX_STEP_MM`:
the sampled points may miss by that much). The samples of a move a → b lie on the joint
segment between a and b, each joint within max(|a_j − q_j|, |b_j − q_j|) of an anchor q, so
a move whose every gap at the anchor exceeds the bound is clear: the check's answer
(None) without evaluating it. A model that bends under gravity turns its joints by the
torques too; its moves are always evaluated. A move evaluated takes the capsule pairs' gaps
beyond :data:`~wirecal.solver.cell.model.SURE_GAP_MM` as lower bounds (the same answers and
words; an anchor's smallest gap then bounds its true one from below, so a skip stays sound).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from wirecal.solver.cell.check import collision_below_mm, move_sweep
from wirecal.solver.cell.model import BOX_STEP_MM, SURE_GAP_MM
from wirecal.solver.kinematics import Model, bends
from wirecal.solver.robot import Robot

ROUNDING_MM = 1e-6
"""Slack of the bound for the rounding of the gaps' arithmetic (mm)."""


def chain_reach_mm(model: Model) -> np.ndarray:
    """Return L_j (n,): a bound on the distance from axis j of any point of the arm beyond it."""
    dh = np.asarray(model.dh)
    lengths = np.abs(dh[:, 1]) + np.abs(dh[:, 3])
    return np.cumsum(lengths[::-1])[::-1] + float(np.linalg.norm(model.tool_point))


@dataclass
class Sweeps:
    """The collision checks of one arm's successive moves (module docstring).

    ``model`` the arm as built, ``p0`` the wire's exit; ``contact``: as
    :func:`~wirecal.solver.cell.check.move_sweep`'s.
    """

    robot: Robot
    model: Model
    p0: np.ndarray
    contact: bool = False
    anchor: tuple[np.ndarray, float] | None = field(default=None, init=False)
    skipped: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        """Derive the chain's reach (None: a bending arm, every move evaluated)."""
        reach = chain_reach_mm(self.model) * (np.pi / 180.0)
        self.mm_per_deg = None if bends(self.model) else reach
        self.below = collision_below_mm(self.robot.cell.margin_mm, self.contact)

    def collision(self, a_deg: np.ndarray, b_deg: np.ndarray) -> str | None:
        """Return where the move a → b (deg) collides, or None (as ``move_sweep``)."""
        if self._clear(a_deg, b_deg):
            self.skipped += 1
            return None
        hit, last, smallest = move_sweep(
            self.robot, self.model, self.p0, a_deg, b_deg, self.contact, SURE_GAP_MM
        )
        if hit is None:
            self.anchor = (last, smallest)
        return hit

    def _clear(self, a_deg: np.ndarray, b_deg: np.ndarray) -> bool:
        """Whether the bound proves every sample of a → b clear of the anchor's gaps."""
        if self.anchor is None or self.mm_per_deg is None:
            return False
        q, smallest = self.anchor
        moved = float(np.maximum(np.abs(a_deg - q), np.abs(b_deg - q)) @ self.mm_per_deg)
        return smallest - 2 * moved - BOX_STEP_MM / 2 - ROUNDING_MM >= self.below
