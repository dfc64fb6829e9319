"""The plan's fingerprint: its canonical text, each number's written out (issue 34).

The fingerprint converts a table's numbers to Python floats once (``tolist``); its text
must stay the definition's: each number ``f"{float(x):.6f}"``, no negative zero, every
key sorted, so every log and program written before still names its plan.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.solver.plan.calibration_plan import fingerprint

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _written_out(plan) -> str:
    """The fingerprint's definition, a number at a time."""

    def num(x):
        s = f"{float(x):.6f}"
        return "0.000000" if s == "-0.000000" else s

    canon = {
        "theta0_deg": [num(v) for v in plan.theta0_deg],
        "order": list(plan.order),
        "steps": [
            {
                "parameter": s.parameter,
                "points_deg": [[num(v) for v in row] for row in s.points_deg],
                "via_deg": [[num(v) for v in row] for row in s.via_deg],
            }
            for s in plan.steps
        ],
    }
    text = json.dumps(canon, separators=(",", ":"), sort_keys=True)
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def test_the_shipped_ur5e_plan_keeps_its_fingerprint():
    """The value main wrote before the change (2026-11-27), in the programs and logs."""
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", load_robot(EXAMPLES / "ur5e" / "robot.toml"))
    assert fingerprint(plan) == "7cd33136670c3c85482209c3ef2a70fd9e7171a587f99ccee01aa01e63955254"


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    scale=st.sampled_from([1e-7, 5e-7, 1.0, 1e6]),
    vias=st.integers(0, 2),
)
def test_the_fingerprint_is_its_definition_written_out(seed, scale, vias):
    rng = np.random.default_rng(seed)
    robot = load_robot(EXAMPLES / "ur5e" / "robot.toml")
    plan = load_plan(EXAMPLES / "ur5e" / "plan.toml", robot)
    steps = tuple(
        replace(
            s,
            points_deg=rng.normal(0.0, scale, s.points_deg.shape),  # negative zeros among them
            via_deg=rng.normal(0.0, scale, (vias, robot.n_joints)),
        )
        for s in plan.steps
    )
    moved = replace(plan, steps=steps, theta0_deg=-rng.uniform(0.0, 1e-6, robot.n_joints))
    assert fingerprint(moved) == _written_out(moved)
