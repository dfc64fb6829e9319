"""What the URScript programs do differently on CB3 (software 3.x): the count and the clock.

The CB3 manuals document the filtered count only (``encoder_get_tick_count(encoder_index)``,
from 3.8: :data:`~wirecal.lang.urscript.versions.CONVEYOR_GUIDE`); ``opt="raw"`` and
``time()`` are read on e-Series pages only (:mod:`wirecal.lang.urscript.versions`). So a
CB3 program

* reads the filtered count, a float in [0; 65536[ that wraps (SW5.20 page; its range on
  3.x is *unconfirmed*), rounds it to a whole count and unwraps it against the previous
  reading: the step to the nearest count modulo 2^16. That is right while the wire moves
  less than half the range between two readings, so every move is cut into legs whose
  nominal wire change is at most :data:`LEG_FRACTION` of the range, with a reading at the
  end of each (:func:`move_legs`): the legs lie on the same straight joint-space line as
  the move, so the path is the one the plan checked;
* moves each leg as a move of its own (it stops there): a move runs at the speed its
  slowest leg allows the wire (:func:`leg_speeds_pct`);
* has no clock: it writes a version 1 log (no ``t_s``, ``settle_s``: its readings carry no
  time, which the log reader takes, :mod:`wirecal.formats.log`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from wirecal.gen.targets import joint_target
from wirecal.lang.urscript.versions import version_of
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import move_profiles, move_speeds_pct
from wirecal.solver.wire_range import nominal_wire_mm, run_moves

CB3 = 3
"""The major software version of the CB3 line."""

FILTERED_RANGE = 2**16
"""The filtered count's range [0; 65536[ (SW5.20 encoder_get_tick_count page)."""

LEG_FRACTION = 0.25
"""A leg changes the nominal wire by at most this fraction of the filtered range: half of
what the unwrapping tolerates, the rest for the model's errors."""

MAX_LEGS = 64
"""More legs than this for one move: the encoder's counts are too fine for the filtered count."""


def is_cb3(software: str | None) -> bool:
    """Tell whether a declared controller software is of the CB3 line (3.x)."""
    return software is not None and version_of(software)[0] == CB3


def move_legs(
    legs: list[np.ndarray], target: Callable[[np.ndarray], str]
) -> list[list[dict[str, str]]]:
    """Return each move's intermediate joint targets of its ``legs`` (:func:`leg_joints`).

    ``target`` writes a joint target.
    """
    return [[joint_target(x, target) for x in q[1:-1]] for q in legs]


def leg_joints(robot: Robot, plan: Plan) -> list[np.ndarray]:
    """Return each move's legs as its joints (deg), start to end, in ``run_moves`` order.

    A move is cut into the fewest equal joint-space legs whose nominal wire change is at
    most :data:`LEG_FRACTION` of the filtered range. Raises :class:`WirecalError` naming
    the move when more than :data:`MAX_LEGS` would be needed.
    """
    limit_mm = LEG_FRACTION * FILTERED_RANGE * abs(robot.encoder.mm_per_count)
    out = []
    for where, start, end, _ in run_moves(plan):
        for n in range(1, MAX_LEGS + 1):
            q = start + np.linspace(0.0, 1.0, n + 1)[:, None] * (end - start)
            if np.all(np.abs(np.diff(nominal_wire_mm(robot, plan.theta0_deg, q))) <= limit_mm):
                break
        else:
            raise WirecalError(
                f"{plan.source}: {where}: the wire changes more than {MAX_LEGS} x "
                f"{limit_mm:.0f} mm: the CB3 programs read the filtered count, which wraps "
                f"every {FILTERED_RANGE * abs(robot.encoder.mm_per_count):.0f} mm"
            )
        out.append(q)
    return out


def leg_speeds_pct(
    robot: Robot, plan: Plan, legs: list[np.ndarray], speed_pct: float
) -> np.ndarray:
    """Return each move's SPEED (%) its ``legs`` (:func:`leg_joints`) allow, in ``run_moves`` order.

    Each leg stops, so it is a move of its own to the wire's limits
    (:func:`~wirecal.solver.run_parameters.move_speeds_pct`, nominal model): the move
    takes its slowest leg's.
    """
    model = robot.nominal
    p0 = tool_position(model, np.radians(plan.theta0_deg)[None])[0]
    moves = move_profiles(
        robot, model, p0, np.vstack([q[:-1] for q in legs]), np.vstack([q[1:] for q in legs])
    )
    pct = move_speeds_pct(robot, moves, speed_pct)
    ends = np.cumsum([len(q) - 1 for q in legs])
    return np.array([pct[e - len(q) + 1 : e].min() for e, q in zip(ends, legs, strict=True)])
