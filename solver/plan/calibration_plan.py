"""A calibration plan: θ0, the identification order and the point sets.

A calibration plan: θ0, the identification order and one point set per step (paper
§2.3), with the fingerprint that ties a measurement log to it. Files are read and written
by :mod:`wirecal.formats.plan_file`.

The fingerprint (sha256 of a normalised form of θ0, order, points and via points) ties a
measurement log to the plan it was taken with; comments, spacing and Ω do not change it.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Step:
    """One identification step: its parameter, points and via points (deg).

    The payload step (:data:`PAYLOAD_STEP`, after the parameters' steps) has no
    parameter: its points are measured with a mass ``payload_kg`` mounted at the flange,
    its centre ``payload_com_mm`` in the last frame, after its zero reading at θ0; the
    compliances are solved from them (:mod:`~wirecal.solver.plan.payload`).
    """

    parameter: str
    points_deg: np.ndarray  # (k, n)
    via_deg: np.ndarray  # (v, n), possibly empty
    omega: float | None = None
    payload_kg: float = 0.0
    payload_com_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)


PAYLOAD_STEP = "payload"
"""The ``parameter`` of the payload step, the last of a plan that has one."""


@dataclass(frozen=True)
class Plan:
    """A calibration plan: θ0, the identification order and one step per parameter."""

    theta0_deg: np.ndarray
    order: tuple[str, ...]
    steps: tuple[Step, ...]
    robot: str | None = None
    description: str | None = None
    source: str = field(default="<memory>", compare=False)
    joint_only: bool = False
    """The steps split poses chosen for the joint method (``plan --pool``): none isolates
    its parameter, so the step-by-step estimate does not apply."""

    @property
    def payload_step(self) -> Step | None:
        """Return the payload step (the last step, with a mass mounted), or None."""
        last = self.steps[-1] if self.steps else None
        return last if last is not None and last.parameter == PAYLOAD_STEP else None

    def loads(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Return the mass (kg) at each point and its centre (mm), or None without one."""
        step = self.payload_step
        if step is None:
            return None
        return self.point_load_kg(), np.array(step.payload_com_mm, dtype=float)

    def point_load_kg(self) -> np.ndarray:
        """Return the mass (kg) mounted at each point of :meth:`all_points`, (N,)."""
        return np.concatenate(
            [np.full(len(s.points_deg), s.payload_kg) for s in self.steps] or [np.zeros(0)]
        )

    @property
    def n_points(self) -> int:
        """Return the number of calibration points over all steps."""
        return sum(len(s.points_deg) for s in self.steps)

    def all_points(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every calibration point (N, n) with its 1-based step and index."""
        q = np.concatenate([s.points_deg for s in self.steps])
        step = np.concatenate([np.full(len(s.points_deg), j + 1) for j, s in enumerate(self.steps)])
        index = np.concatenate([np.arange(1, len(s.points_deg) + 1) for s in self.steps])
        return q, step, index

    def fingerprint(self) -> str:
        """Return the plan's sha256 fingerprint (see :func:`fingerprint`)."""
        return fingerprint(self)


def _num(x: float) -> str:
    """Canonical number text: six decimals, no negative zero."""
    s = f"{float(x):.6f}"
    return "0.000000" if s == "-0.000000" else s


def _nums(values: np.ndarray) -> list:
    """Return :func:`_num`'s text of each number of a vector or a table, nested alike.

    The numbers as Python floats first (``tolist``: the same values, each converted once).
    """
    return _num_texts(np.asarray(values, float).tolist())


def _num_texts(values: list) -> list:
    return [_num_texts(v) if isinstance(v, list) else _num(v) for v in values]


def fingerprint(plan: Plan) -> str:
    """sha256 (hex) of the normalised plan: θ0, order, and each step's points and vias.

    The payload step's mass and centre are in it; a plan without one has the
    fingerprint it had before payload steps existed.
    """
    canon = {
        "theta0_deg": _nums(plan.theta0_deg),
        "order": list(plan.order),
        "steps": [
            {
                "parameter": s.parameter,
                "points_deg": _nums(s.points_deg),
                "via_deg": _nums(s.via_deg),
                **_payload_canon(s),
            }
            for s in plan.steps
        ],
    }
    text = json.dumps(canon, separators=(",", ":"), sort_keys=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _payload_canon(step: Step) -> dict[str, object]:
    """Return the payload step's mass and centre as the fingerprint has them (others: none)."""
    if step.parameter != PAYLOAD_STEP:
        return {}
    return {
        "payload_kg": _num(step.payload_kg),
        "payload_com_mm": [_num(v) for v in step.payload_com_mm],
    }
