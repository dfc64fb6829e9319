"""The patch file's RAPID section: the joint zero offsets ABB's fine calibration takes.

An IRC5 keeps each axis's calibration as a calibration offset of its motor (the
``MOTOR_CALIB`` instances ``rob1_1`` … ``rob1_6`` of the controller's MOC.cfg, attribute
``-cal_offset``: seen in third-party tools that read backups of MOC.cfg; the unit, motor
radians, is *unconfirmed*: no ABB page was read). The FlexPendant's Calibration → Fine
calibration sets an axis's calibration from where the axis stands (*unconfirmed*). Both
carry joint zero offsets only: wirecal's ``th<i>`` estimates. The link lengths, twists and
d offsets (``a<k>``, ``al<k>``, ``d<i>``) and the tool point have no place in them: only a
model the controller does not hold (a URDF, ``wirecal export-urdf``) or targets rewritten
with the calibrated model can carry those — the section says so, naming them.

Sign: wirecal's ``th<i>`` is the true angle minus the angle the controller reports (the
robot file's model, Craig's θ_i + offset). Fine calibration at the axis's calibration
position (0 deg, *unconfirmed* for every ABB arm) corrects it when the axis is jogged
until the FlexPendant reads −th<i> and then fine-calibrated: the true angle is then 0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from wirecal.solver import params as P
from wirecal.solver.robot import Robot

ACCEPTS = (
    "joint zero offsets (the th<i> estimates): the axes' calibration offsets of the "
    "controller (MOC.cfg MOTOR_CALIB -cal_offset, motor side; or FlexPendant Calibration "
    "-> Fine calibration at the calibration position); unconfirmed, see docs/rapid.md"
)
NOT_CARRIED = (
    "link lengths, twists, d offsets and the tool point: the controller's kinematic model "
    "does not take them; only a URDF (wirecal export-urdf) or targets rewritten with the "
    "calibrated model carry them"
)


def patch_section(robot: Robot, offsets: Mapping[str, float]) -> dict | None:
    """Return the patch file's ``[rapid]`` section for ``offsets`` (name → deg or mm).

    ``axis``, ``offset_rad``, ``offset_deg`` and ``jog_to_deg`` (the FlexPendant reading to
    jog each axis to before its fine calibration) for the th<i> estimates, and the other
    parameters named in ``not_carried``; None when there are no offsets.
    """
    if not offsets:
        return None
    joints: list[tuple[int, float]] = []
    other: list[str] = []
    for name, value in offsets.items():
        p = P.parse(name, robot.n_joints)
        if p.kind == "th":
            joints.append((p.row + 1, float(value)))
        else:
            other.append(name)
    joints.sort()
    return {
        "accepts": ACCEPTS,
        "axis": [a for a, _ in joints],
        "offset_deg": [round(v, 6) for _, v in joints],
        "offset_rad": [round(math.radians(v), 9) for _, v in joints],
        "jog_to_deg": [round(-v, 6) + 0.0 for _, v in joints],
        "not_carried": other,
        "not_carried_why": NOT_CARRIED,
    }
