"""The plans the tests design for the shipped arms at a fixed θ0, each designed once a session.

Several test files design the same plan (the Viper's at the θ0 ``wirecal plan`` chooses, for
each method); the planner gives the same plan for the same inputs
(``test_planner.py::test_the_same_inputs_give_the_same_plan`` checks it, designing again), so
they share one.
"""

from __future__ import annotations

import functools

import numpy as np

from wirecal.formats.robot_file import load_robot
from wirecal.solver.plan.design import Design
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.planner import design
from wirecal.solver.robot import Robot

from .conftest import ROOT

THETA0 = {
    "viper_s650": (-72, -156, 235, 3, 64, 41),
    "puma560": (112, -123, -32, 8, -53, -288),
    "abb_irb120": (21, 5, -36, -43, -43, -184),
    "ur5e": (-195, 236, -54, -181, -127, 56),  # inside its [cell] (issue 21)
}
"""θ0 as ``wirecal plan`` chooses them (seed 0), fixed to keep the tests quick."""


@functools.cache
def designed(arm: str, method: str) -> tuple[Robot, Design]:
    """Return the shipped ``arm`` and its plan for ``method`` designed at :data:`THETA0`."""
    robot = load_robot(ROOT / "examples" / arm / "robot.toml")
    return robot, design(robot, np.array(THETA0[arm], float), PlanOptions(method=method))
