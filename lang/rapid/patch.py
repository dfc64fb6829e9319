"""The patch's RAPID companion: the joint zero offsets ABB's fine calibration takes.

An IRC5 keeps each axis's calibration as a calibration offset of its motor (the
``MOTOR_CALIB`` instances ``rob1_1`` … ``rob1_6`` of the controller's MOC.cfg, attribute
``-cal_offset``: seen in third-party tools that read backups of MOC.cfg; the unit, motor
radians, is *unconfirmed*: no ABB page was read). The FlexPendant's Calibration → Fine
calibration sets an axis's calibration from where the axis stands (*unconfirmed*). Both
carry joint zero offsets only: wirecal's ``th<i>`` estimates. The link lengths, twists and
d offsets (``a<k>``, ``al<k>``, ``d<i>``) and the tool point have no place in them: only a
model the controller does not hold (a URDF, ``wirecal export-urdf``) or targets rewritten
with the calibrated model can carry those — the companion says so, naming them.

Sign: wirecal's ``th<i>`` is the true angle minus the angle the controller reports (the
robot file's model, Craig's θ_i + offset). Fine calibration at the axis's calibration
position (0 deg, *unconfirmed* for every ABB arm) corrects it when the axis is jogged
until the FlexPendant reads −th<i> and then fine-calibrated: the true angle is then 0.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping

from wirecal.solver import params as P
from wirecal.solver.robot import Robot

SUFFIX = ".abb_calibration.toml"
"""The file beside a patch ``<name>.toml``: ``<name>.abb_calibration.toml``."""

HEADER = (
    "# wirecal: ABB fine calibration, the joint zero offsets of a calibration (the patch's",
    "# companion; docs/rapid.md). What the controller takes: joint zero offsets, the axes'",
    "# calibration offsets (MOC.cfg MOTOR_CALIB -cal_offset, motor side: the unit and the",
    "# gear ratio are unconfirmed), or by hand: jog each axis until the FlexPendant reads",
    "# jog_to_deg, at the calibration position 0 deg, then Calibration -> Fine calibration",
    "# of that axis (unconfirmed). offset = true angle - reported angle (wirecal's th<i>).",
)
NOT_CARRIED = (
    "link lengths, twists, d offsets and the tool point: the controller's kinematic model "
    "does not take them; only a URDF (wirecal export-urdf) or targets rewritten with the "
    "calibrated model carry them"
)


def _list(values: list) -> str:
    return "[" + ", ".join(json.dumps(v) for v in values) + "]"


def patch_section(robot: Robot, offsets: Mapping[str, float]) -> str:
    """Return the companion's TOML text for ``offsets`` (name → deg or mm).

    ``[joint_offsets]``: ``axis``, ``offset_deg``, ``offset_rad`` and ``jog_to_deg`` (the
    FlexPendant reading to jog each axis to before its fine calibration) of the th<i>
    estimates; ``[not_carried]``: the other parameters, with why.
    """
    joints: list[tuple[int, float]] = []
    other: list[str] = []
    for name, value in offsets.items():
        p = P.parse(name, robot.n_joints)
        if p.kind == "th":
            joints.append((p.row + 1, float(value)))
        else:
            other.append(name)
    joints.sort()
    lines = [
        *HEADER,
        f"robot = {json.dumps(robot.name)}",
        "",
        "[joint_offsets]",
        f"axis = {_list([a for a, _ in joints])}",
        f"offset_deg = {_list([round(v, 6) + 0.0 for _, v in joints])}",
        f"offset_rad = {_list([round(math.radians(v), 9) + 0.0 for _, v in joints])}",
        f"jog_to_deg = {_list([round(-v, 6) + 0.0 for _, v in joints])}",
        "",
        "[not_carried]",
        f"parameters = {_list(other)}",
        f"why = {json.dumps(NOT_CARRIED)}",
    ]
    return "\n".join(lines) + "\n"
