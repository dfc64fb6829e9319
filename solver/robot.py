"""The robot model: a serial arm's nominal kinematics (Craig's modified DH), joint limits
and speeds, the wire attachment point and the draw-wire encoder. Files are read by
:mod:`wirecal.solver.formats.robot_file`."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from wirecal.solver import params as P

CONTROLLER_JOINTS = 6
"""Joints of the arms the controller programs and the log format are written for."""

DEFAULT_LINK_RADIUS_MM = 50.0
"""Capsule radius of a link when the robot file gives none (for the wire clearance)."""


@dataclass(frozen=True)
class Encoder:
    """The draw-wire encoder: scale, measuring range, the width of the controller's counter,
    and how the controller program reads it: ``interface`` "belt" (DEFBELT/BELT, belt
    encoder ``channel``, BELT mode ``belt_mode``) or "device" (DEVICE unit ``channel``)."""

    mm_per_count: float
    range_mm: float
    counter_bits: int
    interface: str = "belt"
    channel: int = 1
    belt_mode: int = 0


@dataclass(frozen=True)
class UrdfSource:
    """The URDF a robot file was imported from (``[urdf]`` table): its path (resolved against
    the robot file's folder) and the chain's end links. Export re-derives the DH frames from
    it and changes only the chain's joint origins."""

    path: str
    base_link: str
    tip_link: str
    parallel_tol_deg: float | None = None  # import-urdf --parallel-tol-deg, if given


@dataclass(frozen=True)
class Robot:
    """Nominal model of a serial arm in Craig's modified DH convention.

    ``dh`` rows are (α_{i-1} [rad], a_{i-1} [mm], θ_i offset [rad], d_i [mm]).
    """

    name: str
    dh: np.ndarray
    joint_min_deg: np.ndarray
    joint_max_deg: np.ndarray
    joint_speed_deg_s: np.ndarray
    tool_point: np.ndarray
    encoder: Encoder
    parameters: tuple[str, ...]
    source: str = field(default="<memory>", compare=False)
    link_radius_mm: np.ndarray | None = None  # capsules between joint frames; see clearance
    urdf: UrdfSource | None = None

    @property
    def n_joints(self) -> int:
        return int(self.dh.shape[0])

    def dh_deg(self) -> np.ndarray:
        """DH table in file units: degrees for α and θ offset, mm for a and d."""
        out = self.dh.copy()
        out[:, [0, 2]] = np.degrees(out[:, [0, 2]])
        return out

    def nominal_value(self, name: str) -> float:
        """Nominal value of a parameter in boundary units (deg or mm)."""
        p = P.parse(name, self.n_joints)
        if p.kind == "tool":
            return float(self.tool_point[p.row])
        col = {"al": 0, "a": 1, "th": 2, "d": 3}[p.kind]
        value = float(self.dh[p.row, col])
        return math.degrees(value) if p.angular else value

    def controller_problem(self) -> str | None:
        """Why the controller programs and the log cannot serve this arm, or None.

        Both are written for 6-joint arms (the log has the columns j1..j6)."""
        if self.n_joints == CONTROLLER_JOINTS:
            return None
        return (
            f"{self.source}: {self.n_joints} joints; the controller programs and the log "
            f"format are for {CONTROLLER_JOINTS}-joint arms"
        )
