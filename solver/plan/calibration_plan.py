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
    """One identification step: its parameter, points and via points (deg)."""

    parameter: str
    points_deg: np.ndarray  # (k, n)
    via_deg: np.ndarray  # (v, n), possibly empty
    omega: float | None = None


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


def fingerprint(plan: Plan) -> str:
    """sha256 (hex) of the normalised plan: θ0, order, and each step's points and vias."""
    canon = {
        "theta0_deg": [_num(v) for v in plan.theta0_deg],
        "order": list(plan.order),
        "steps": [
            {
                "parameter": s.parameter,
                "points_deg": [[_num(v) for v in row] for row in s.points_deg],
                "via_deg": [[_num(v) for v in row] for row in s.via_deg],
            }
            for s in plan.steps
        ],
    }
    text = json.dumps(canon, separators=(",", ":"), sort_keys=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()
