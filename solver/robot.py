"""The robot model: a serial arm's kinematics, limits, wire attachment and encoder.

The robot model: a serial arm's nominal kinematics (Craig's modified DH), joint limits
and speeds, the wire attachment point and the draw-wire encoder. Files are read by
:mod:`wirecal.formats.robot_file`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.cell.model import Capsules, CellModel, Gaps, body_limits, capsules, cell_gaps
from wirecal.solver.counter import Counter
from wirecal.solver.exit_geometry import Exit, Pulley
from wirecal.solver.gravity import MassModel
from wirecal.solver.joint_speeds import placeholder_speeds
from wirecal.solver.kinematics import Frames, Model, with_errors

CONTROLLER_JOINTS = 6
"""Joints of the arms the controller programs and the log format are written for."""

DEFAULT_LINK_RADIUS_MM = 50.0
"""Capsule radius of a link when the robot file gives none (for the wire clearance)."""


DEFAULT_SCALE_TOLERANCE_PPM = 500.0
"""The scale tolerance (ppm) when the robot file gives none: a mm_per_count typed from a
datasheet is good to about 0.02–0.1 % (issue 13's survey of catalogue draw-wire sensors)."""

DEFAULT_DRUM_PPM_PER_K = 23.0
"""The drum's linear expansion (ppm/K) when the robot file gives none: aluminium."""


def near_limits(value_deg: float, lo_deg: float, hi_deg: float, margin_deg: float) -> str:
    """Say where a joint value refused for its margin lies: beyond a limit, or within margin.

    ``lo_deg`` and ``hi_deg`` are the limits themselves (the margin not yet taken off).
    """
    if value_deg < lo_deg or value_deg > hi_deg:
        return "beyond"
    return f"within {margin_deg:g} deg of"


@dataclass(frozen=True)
class Encoder:
    """The draw-wire encoder and how the controller program reads it.

    The draw-wire encoder: scale, measuring range, the width of the controller's counter,
    and how the controller program reads it: ``interface`` "belt" (V+: DEFBELT/BELT, belt
    encoder ``channel``, BELT mode ``belt_mode``), "device" (V+: DEVICE unit ``channel``)
    or "pulse" (URScript: the controller's quadrature pulse decoder, encoder index
    ``channel`` 0 or 1, signals A and B on the digital inputs ``pulse_inputs``).
    ``exit`` is where the wire leaves the housing (:mod:`~wirecal.solver.exit_geometry`):
    an eyelet, a swivel guide pulley, or ``None`` for the ideal point exit.
    """

    mm_per_count: float
    range_mm: float
    counter_bits: int
    interface: str = "belt"
    channel: int = 1
    belt_mode: int = 0
    pulse_inputs: tuple[int, int] = (8, 9)
    exit: Exit | None = None
    max_wire_speed_mm_s: float | None = None  # the wire's speed limit (None: not given)
    max_wire_accel_mm_s2: float | None = None  # the wire's acceleration limit
    scale_tolerance_ppm: float = DEFAULT_SCALE_TOLERANCE_PPM  # the datasheet's scale figure
    reference_length_mm: float | None = None  # a gauge's certified nest distance, if any
    reference_uncertainty_mm: float = 0.0  # its certificate's standard uncertainty
    reference_repeats: int = 3  # nest A/B seatings the program asks for
    temperature_coefficient_ppm_per_k: float = DEFAULT_DRUM_PPM_PER_K  # the drum's expansion

    @property
    def counter(self) -> Counter:
        """The controller's counter of this encoder (``counter_bits`` wide)."""
        return Counter(self.counter_bits)


SOFTWARE_PATTERN = re.compile(r"\d{1,3}(\.\d{1,4}){1,3}")
"""A controller software version as numbers, as PolyScope shows it: "3.15.8", "5.20"."""


@dataclass(frozen=True)
class Controller:
    """The robot's controller: its language, software version and where the PC listens.

    A URScript program has no file output: it sends the log over a TCP socket to
    ``wirecal receive`` on ``host``:``port`` (the robot is the client), first presenting
    the run token derived from ``key`` (:mod:`wirecal.formats.run_token`). ``software`` is
    the controller's software version as written ("5.20", "3.15.8"), or None if not
    declared; generation uses only calls that version has (docs/languages.md).
    """

    language: str = "vplus"  # a robot file without [controller] (the registry's default)
    host: str | None = None
    port: int | None = None
    key: str | None = None
    software: str | None = None

    @property
    def software_version(self) -> tuple[int, ...] | None:
        """The software version as numbers, (5, 20) for "5.20"; None if not declared."""
        if self.software is None:
            return None
        return tuple(int(x) for x in self.software.split("."))


@dataclass(frozen=True)
class UrdfSource:
    """The URDF a robot file was imported from.

    The URDF a robot file was imported from (``[urdf]`` table): its path (resolved against
    the robot file's folder) and the chain's end links. Export re-derives the DH frames from
    it and changes only the chain's joint origins.
    """

    path: str
    base_link: str
    tip_link: str
    parallel_tol_deg: float | None = None  # import-urdf --parallel-tol-deg, if given
    wire_point_mm: tuple[float, float, float] | None = None  # in the tip link's frame


DEFAULT_GRAVITY_SAG_DEG_PER_M = 0.01
"""How far joints 2 and 3 sag under gravity per metre of lever arm to the wrist centre, the
way gravity pulls (deg/m; :func:`~wirecal.solver.gravity.wrist_weight`), when the robot file
does not say: the digital twin's value (≈ 0.05 mm at
full reach of the Viper s650), an assumption for any real arm (unconfirmed)."""


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
    controller: Controller = Controller()
    joint_speed_confirmed: bool | None = None  # false: a URDF's placeholders; None: not stated
    gravity_sag_deg_per_m: float = DEFAULT_GRAVITY_SAG_DEG_PER_M  # joints 2, 3 (the budget's)
    cell: CellModel = field(
        default_factory=CellModel
    )  # the floor, keep-out volumes and body limits
    masses: MassModel | None = None  # [gravity]: the links' and payload's masses (None: rigid)
    compliance_urad_per_nm: np.ndarray | None = None  # [gravity]: c_j, µrad/(N·m) (None: 0)
    compliances: tuple[str, ...] = ()  # [calibration]: compliances to identify (c2, c3, …)
    repeatability_mm: float | None = None  # [calibration]: the arm's (zero_reading); None: 0
    rated_payload_kg: float | None = None  # [calibration]: the data sheet's rated payload
    payload_kg: float | None = None  # [calibration]: the plan's payload step's mass (None: none)
    payload_com_mm: np.ndarray | None = None  # [calibration]: its centre in the last frame

    @property
    def n_joints(self) -> int:
        """Return the number of joints."""
        return int(self.dh.shape[0])

    @cached_property
    def nominal(self) -> Model:
        """The nominal kinematic model (no error offsets); computed once, read-only."""
        dh = np.array(self.dh, dtype=float)
        tool = np.array(self.tool_point, dtype=float)
        dh.flags.writeable = tool.flags.writeable = False
        pulley = self.encoder.exit if isinstance(self.encoder.exit, Pulley) else None
        c = self.compliance_urad_per_nm
        compliance = (
            None if c is None else np.asarray(c, dtype=float) * P.INTERNAL_PER_BOUNDARY["urad/Nm"]
        )
        return Model(dh, tool, pulley, self.masses, compliance)

    @cached_property
    def capsules(self) -> Capsules:
        """The arm's capsules and self-collision pairs (:mod:`~wirecal.solver.cell.model`)."""
        radii = self.link_radius_mm
        if radii is None:
            radii = np.full(self.n_joints - 1, DEFAULT_LINK_RADIUS_MM)
        return capsules(self.dh, radii, self.tool_point, self.cell.margin_mm)

    def limits_deg(
        self, margin_deg: float | np.ndarray = 0.0, *, body: bool = True
    ) -> tuple[np.ndarray, np.ndarray]:
        """Return the lower and upper joint limits (deg), each ``margin_deg`` inside.

        With ``body`` (the default) the joint limits narrowed first by the cell's body
        limits (:func:`~wirecal.solver.cell.model.body_limits`): where plans may go. Without, the
        robot file's joint limits alone: what the controller enforces (inverse kinematics,
        the generated targets). ``margin_deg`` may differ per joint (an array).
        """
        if body:
            lo, hi = body_limits(self.joint_min_deg, self.joint_max_deg, self.cell)
        else:
            lo, hi = self.joint_min_deg, self.joint_max_deg
        return lo + margin_deg, hi - margin_deg

    def cell_gaps(
        self,
        q_deg: np.ndarray,
        p0: np.ndarray,
        model: Model | None = None,
        f: Frames | None = None,
        exact_below_mm: float = np.inf,
    ) -> Gaps:
        """Return the gaps (mm) of configurations ``q_deg`` to the arm's body and the cell.

        ``p0``: the wire's exit (the encoder housing's start); ``model``: the arm as built
        (default nominal); ``f``: the frames of q when the caller has them;
        ``exact_below_mm``: see :func:`~wirecal.solver.cell.model.cell_gaps`.
        """
        model = self.nominal if model is None else model
        q_rad = np.radians(np.atleast_2d(q_deg))
        return cell_gaps(self.cell, self.capsules, model, q_rad, p0, f, exact_below_mm)

    def errors(self, names: Sequence[str] | None = None) -> P.ErrorSet:
        """Return the error parameters ``names`` (default: the robot file's ``parameters``)."""
        return P.ErrorSet(tuple(self.parameters if names is None else names), self.n_joints)

    def model(self, offsets: Mapping[str, float]) -> Model:
        """Return the nominal model with error offsets in boundary units (deg for angles, mm)."""
        if not offsets:
            return self.nominal
        es = self.errors(list(offsets))
        return with_errors(self.nominal, es.names, es.to_internal([offsets[n] for n in es.names]))

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
        if p.kind == "c":
            c = self.compliance_urad_per_nm
            return 0.0 if c is None else float(c[p.row])
        value = float(self.dh[p.row, P.DH_COLUMN[p.kind]])
        return value * P.BOUNDARY_PER_INTERNAL[p.unit]

    def program_problems(self) -> list[str]:
        """Return why no controller program may be written for this robot (none: it may)."""
        return [p for p in (self.controller_problem(), self.speed_problem()) if p]

    def speed_problem(self) -> str | None:
        """Why the joint speeds cannot be trusted to time motion, or None.

        ``wirecal gen`` derives each move's speed (V+ SPEED from the wire's limits, URScript
        joint speed) from ``joint_speed_deg_s``: speeds below the real ones would let the real
        wire run faster than the encoder allows.
        """
        if self.joint_speed_confirmed is False:
            return (
                f"{self.source}: kinematics.joint_speed_confirmed = false: the joint speeds "
                "came from a URDF that gave placeholders; enter the data sheet's maximum joint "
                "speeds in joint_speed_deg_s and set joint_speed_confirmed = true (or re-import "
                "with import-urdf --joint-speed-deg-s)"
            )
        why = placeholder_speeds(self.joint_speed_deg_s)
        if self.joint_speed_confirmed or why is None:
            return None
        return (
            f"{self.source}: kinematics.joint_speed_deg_s: {why}: rad/s written as deg/s? gen "
            "times every move from these speeds, and speeds below the real ones let the wire "
            "run faster than the encoder allows; give the data sheet's maximum joint speeds "
            "in deg/s, or set joint_speed_confirmed = true if they are right"
        )

    def controller_problem(self) -> str | None:
        """Why the controller programs and the log cannot serve this arm, or None.

        Both are written for 6-joint arms (the log has the columns j1..j6).
        """
        if self.n_joints == CONTROLLER_JOINTS:
            return None
        return (
            f"{self.source}: {self.n_joints} joints; the controller programs and the log "
            f"format are for {CONTROLLER_JOINTS}-joint arms"
        )
