"""``wirecal import-urdf``: a robot file from a URDF's chain, ready for ``plan`` and ``gen``.

Everything the robot file needs comes from the URDF, the options or a stated rule, and the
file says which: the DH rows, limits and speeds from the URDF's joints
(:mod:`wirecal.formats.urdf_model`); the wire attachment point from ``--wire-point-mm`` in
the tip link's frame; the encoder interface and counter width from the controller language's
declaration (:class:`wirecal.lang.base.Capabilities`); the link radii from the URDF's
geometry or lengths (:mod:`wirecal.formats.urdf_geometry`); the mounting plane from
the URDF's root link.

Joint speeds a URDF gives as placeholders — every joint the same whole number of rad/s, or
any joint below :data:`~wirecal.solver.joint_speeds.MIN_PLAUSIBLE_SPEED_DEG_S` — are written with
``joint_speed_confirmed = false``: ``plan`` works (its times are estimates), ``gen`` refuses
until the data sheet's speeds are entered, because the programs time every move from them
(:meth:`wirecal.solver.robot.Robot.speed_problem`).
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wirecal.formats.robot_file import robot_file_text, robot_from_dict
from wirecal.formats.urdf import MOVING, chain, matrix_rpy, origin_mm, read_urdf
from wirecal.formats.urdf_geometry import (
    RADIUS_PER_LENGTH,
    RADIUS_PER_REACH,
    WIDE_RATIO,
    LinkRadii,
    link_radii,
    wide_links,
)
from wirecal.formats.urdf_model import (
    UrdfChain,
    chain_masses,
    fk_difference_mm,
    read_chain,
)
from wirecal.lang.registry import default_language, first_channel, language
from wirecal.solver.angle_units import TURN_RAD, within_a_turn
from wirecal.solver.dh_from_axes import PARALLEL_TOL
from wirecal.solver.errors import WirecalError
from wirecal.solver.identifiability import propose_parameters
from wirecal.solver.joint_speeds import placeholder_speeds
from wirecal.solver.kinematics import Model
from wirecal.solver.robot import (
    Controller,
    Encoder,
    Robot,
    UrdfSource,
)

CONTINUOUS_DEG = 360.0
"""Range written for a URDF ``continuous`` joint (no limits in the file): one turn each way."""
PROPOSAL_POINTS = 300
EXACT_MM = 1e-9
CELL_MARGIN_MM = 10.0
"""``[cell] margin_mm`` written by the import."""


@dataclass(frozen=True)
class ImportOptions:
    """What ``import-urdf`` takes beyond the URDF (see the command's options)."""

    tip: str
    base: str | None = None
    name: str | None = None
    language: str = field(default_factory=lambda: default_language().key)
    wire_point_mm: tuple[float, float, float] | None = None
    mm_per_count: float = 0.025488
    range_mm: float = 1250.0
    counter_bits: int | None = None  # None: the language's
    interface: str | None = None  # None: the language's
    joint_speed_deg_s: tuple[float, ...] | None = None  # None: the URDF's
    host: str | None = None
    port: int | None = None
    parallel_tol_deg: float | None = None


@dataclass(frozen=True)
class Imported:
    """The robot file's text and what the command reports."""

    text: str
    chain: UrdfChain
    parameters: tuple[str, ...]
    notes: list[str]  # printed as "note:" and written in the file's header
    warnings: list[str]  # printed as "warning:": the user must act on them


def urdf_robot_file(urdf: str | Path, out_path: Path, opt: ImportOptions) -> Imported:
    """Return the robot file for ``opt.tip``'s chain of ``urdf``, checked to read back."""
    encoder = _encoder(opt)
    doc = read_urdf(urdf)
    tol = PARALLEL_TOL if opt.parallel_tol_deg is None else math.radians(opt.parallel_tol_deg)
    wire = None if opt.wire_point_mm is None else np.array(opt.wire_point_mm, dtype=float)
    ch = read_chain(doc, opt.base, opt.tip, tol, wire)
    lo, hi, urdf_speed, notes = _limits(ch)
    speed, confirmed, speed_notes = _speeds(ch, urdf_speed, opt.joint_speed_deg_s)
    q_deg = lo + np.random.default_rng(0).uniform(0, 1, (PROPOSAL_POINTS, len(lo))) * (hi - lo)
    params = _parameters(ch, q_deg, (lo + hi) / 2, notes)
    notes += _fk_check(ch, q_deg, urdf)
    radii = link_radii(ch)
    cell, cell_note = _cell_lines(ch)
    robot = Robot(
        name=opt.name or doc.name or Path(urdf).stem,
        dh=ch.dh.dh,
        joint_min_deg=lo,
        joint_max_deg=hi,
        joint_speed_deg_s=speed,
        tool_point=ch.tool_point,
        encoder=encoder,
        parameters=params,
        link_radius_mm=radii.radius_mm,
        urdf=UrdfSource(
            str(urdf), ch.base_link, ch.tip_link, opt.parallel_tol_deg, opt.wire_point_mm
        ),
        controller=_controller(opt),
        joint_speed_confirmed=confirmed,
        masses=chain_masses(ch),
    )
    source = os.path.relpath(Path(urdf).resolve(), out_path.resolve().parent)
    notes += [_radii_note(radii), *([cell_note] if cell_note else [])]
    text = robot_file_text(
        robot,
        header=_header(robot, ch, source, notes),
        row_notes=[j.name for j in ch.moving],
        encoder_note=f"not in a URDF: {language(opt.language).title}'s interface and counter "
        "width, scale and range from the import's options (defaults: a Unimeasure EP-50)",
        urdf_source=source,
        speed_notes=speed_notes,
        geometry_notes=_geometry_notes(radii),
        tables=cell,
        write_cell=False,  # the mounting plane from the URDF's root link, or a note why not
    )
    _reads_back(text, urdf, out_path)
    warnings = ([] if confirmed else speed_notes) + _wide_warning(radii)
    return Imported(text, ch, params, notes, warnings)


def _reads_back(text: str, urdf: str | Path, out_path: Path) -> None:
    """Raise unless the robot file ``text`` passes the robot file's checks.

    Its values are the URDF's, so the problems name the URDF, not the file not yet written.
    """
    try:
        robot_from_dict(tomllib.loads(text), f"{urdf} (as the robot file {out_path})")
    except WirecalError as exc:
        raise WirecalError(
            [
                *exc.problems,
                f"{urdf}: the robot file made from it fails the check(s) above: its values "
                "are the URDF's (joint origins in m, limits in rad, velocities in rad/s) and, "
                "in [encoder], the options --mm-per-count, --range-mm and --counter-bits; "
                "correct them and import again",
            ]
        ) from None


def _controller(opt: ImportOptions) -> Controller:
    """Return the controller of the options; --host and --port only for a language with sockets."""
    lang = language(opt.language)
    given = [name for name, v in (("--host", opt.host), ("--port", opt.port)) if v is not None]
    if given and not lang.capabilities.sockets:
        raise WirecalError(
            f"{' and '.join(given)}: the {lang.title} programs (--language {opt.language}) "
            "write their log to the controller's disk, not over TCP: leave them out"
        )
    return Controller(opt.language, opt.host, opt.port)


def _encoder(opt: ImportOptions) -> Encoder:
    """Return the encoder of the options, the language's interface and counter by default."""
    lang = language(opt.language)
    readable = lang.capabilities.encoder_interfaces
    if opt.interface is not None and opt.interface not in readable:
        raise WirecalError(
            f"--interface {opt.interface} is not read by the {lang.title} "
            f"programs (--language {opt.language}); give " + " or ".join(readable)
        )
    interface = opt.interface or readable[0]
    bits = lang.capabilities.counter_bits
    return Encoder(
        opt.mm_per_count,
        opt.range_mm,
        bits if opt.counter_bits is None else opt.counter_bits,
        interface,
        channel=first_channel(interface),
    )


def _limits(ch: UrdfChain) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Return the joint limits and speeds (deg, deg/s) of the chain, and notes."""
    lo, hi, speed, notes, problems = [], [], [], [], []
    for j in ch.moving:
        where = f"{ch.urdf.path}: joint {j.name!r}"
        if j.type == "continuous":
            lo.append(-CONTINUOUS_DEG)
            hi.append(CONTINUOUS_DEG)
            notes.append(
                f"joint {j.name!r} is continuous (no limits in the URDF): written as "
                f"±{CONTINUOUS_DEG:g}°; narrow it to what the cabling allows"
            )
        elif j.lower_rad is None or j.upper_rad is None or j.lower_rad >= j.upper_rad:
            problems.append(f"{where}: needs <limit lower=… upper=…> with lower < upper")
            lo.append(0.0)
            hi.append(0.0)
        else:
            lo.append(math.degrees(j.lower_rad))
            hi.append(math.degrees(j.upper_rad))
        if j.velocity_rad_s is None or j.velocity_rad_s <= 0:
            problems.append(f"{where}: needs <limit velocity=…> > 0 (rad/s)")
            speed.append(0.0)
        else:
            speed.append(math.degrees(j.velocity_rad_s))
    if problems:
        raise WirecalError(problems)
    return np.array(lo), np.array(hi), np.array(speed), notes


def _speeds(
    ch: UrdfChain, urdf_speed: np.ndarray, given: tuple[float, ...] | None
) -> tuple[np.ndarray, bool, list[str]]:
    """Return the joint speeds (deg/s), whether they are confirmed, and comments on them."""
    n = len(ch.moving)
    if given is not None:
        if len(given) != n or not all(math.isfinite(v) and v > 0 for v in given):
            raise WirecalError(
                f"--joint-speed-deg-s: give {n} positive speeds (deg/s), one per joint of "
                f"{ch.base_link} → {ch.tip_link}"
            )
        if within_a_turn(np.array(given)):
            raise WirecalError(
                f"--joint-speed-deg-s: every speed is within 2π ({TURN_RAD:.2f} °/s, slower "
                "than any arm's joint): they look like rad/s; give deg/s (× 180/π)"
            )
        return np.array(given, dtype=float), True, ["from import-urdf --joint-speed-deg-s"]
    why = placeholder_speeds(urdf_speed)
    if why is None:
        return urdf_speed, True, []
    return (
        urdf_speed,
        False,
        [
            f"ACTION NEEDED: {why}. wirecal gen times every move from these speeds, so it "
            "refuses until you enter the data sheet's maximum joint speeds here and set "
            "joint_speed_confirmed = true (or re-import with --joint-speed-deg-s)",
        ],
    )


def _parameters(
    ch: UrdfChain, q_deg: np.ndarray, middle_deg: np.ndarray, notes: list[str]
) -> tuple[str, ...]:
    """Return the calibration parameters proposed over ``q_deg``; note an unobservable θn."""
    n = len(ch.moving)
    model = Model(ch.dh.dh, ch.tool_point)
    params = tuple(propose_parameters(model, q_deg, middle_deg, ch.dh.dh))
    if f"th{n}" not in params:
        notes.append(
            f"th{n} is not proposed: the wire point lies on the last joint's axis, so no wire "
            "length depends on it; give --wire-point-mm (the attachment off the axis)"
        )
    return params


def _fk_check(ch: UrdfChain, q_deg: np.ndarray, urdf: str | Path) -> list[str]:
    """Compare the DH model's wire point with the URDF's over ``q_deg``; notes on snapped axes."""
    notes = [
        f"the axes of {ch.moving[i].name!r} and {ch.moving[i + 1].name!r} are {angle:.2g} rad "
        "from parallel (a rounded π/2 in the URDF): taken as parallel"
        for i, angle in ch.dh.snapped
    ]
    diff = fk_difference_mm(ch, np.radians(q_deg))
    if ch.dh.snapped:
        notes.append(
            f"so the DH tip differs from the URDF's by up to {diff:.2g} mm "
            f"({len(q_deg)} configurations within the limits)"
        )
    elif diff > EXACT_MM:  # a guard: the construction is exact
        raise WirecalError(
            f"{urdf}: the DH model's tip differs from the URDF's by {diff:.3g} mm; "
            "please report this URDF"
        )
    return notes


def _geometry_notes(radii: LinkRadii) -> list[str]:
    """Return the ``[geometry]`` comments: where each radius came from."""
    measured = [
        f"link {k}: from the geometry of {', '.join(links)}"
        for k, links in enumerate(radii.measured, 1)
        if links
    ]
    return [
        "capsule radius (mm) of each link between joint frames k and k+1 (k = 1 … n-1), for",
        "the wire clearance: estimates by wirecal import-urdf; replace them with measured ones",
        *measured,
        *(
            f"{note}: {RADIUS_PER_LENGTH:.0%} of its length, at least {RADIUS_PER_REACH:.0%} "
            "of the arm's"
            for note in radii.notes
        ),
        *([radii.uncovered] if radii.uncovered else []),
    ]


def _wide_warning(radii: LinkRadii) -> list[str]:
    """Return a warning when radii from geometry are far wider than the length rule's."""
    wide = wide_links(radii)
    if not wide:
        return []
    which = ", ".join(f"{k} ({radii.radius_mm[k - 1]:g} mm)" for k in wide)
    return [
        f"link(s) {which}: the capsules containing the URDF's geometry are over "
        f"{WIDE_RATIO:g}× the length rule's (bodies off the DH lines, wide housings); plan may "
        "find no wire path: measure the links' radii and write them in [geometry]"
    ]


def _radii_note(radii: LinkRadii) -> str:
    """Return the printed summary of the link radii and where they came from."""
    by_length = [str(k) for k, links in enumerate(radii.measured, 1) if not links]
    values = ", ".join(f"{r:g}" for r in radii.radius_mm)
    why = "no readable geometry beside them"
    if radii.only_beyond:
        why += (
            f"; link(s) {', '.join(map(str, radii.only_beyond))}: geometry read, but only "
            "beyond the link's ends"
        )
    if not by_length:
        source = "all from the URDF's collision geometry"
    elif len(by_length) == len(radii.measured):
        source = f"all from link lengths ({why}; see [geometry])"
    else:
        source = (
            f"link(s) {', '.join(by_length)} from link lengths ({why}; see [geometry]), the "
            "others from the URDF's collision geometry"
        )
    return f"link radii {values} mm: {source}; measure them if you can"


def _cell_lines(ch: UrdfChain) -> tuple[list[str], str | None]:
    """Return the ``[cell]`` table's lines, or none and why (a note)."""
    root_to_base = np.eye(4)
    try:
        below = chain(ch.urdf, None, ch.base_link)
    except WirecalError as exc:
        return [], f"no [cell]: the base link's place under the URDF's root is unclear ({exc})"
    for j in below:
        if j.type in MOVING:
            return [], (
                f"no [cell]: joint {j.name!r} moves the base link {ch.base_link!r} against the "
                "URDF's root, so the mounting plane is not fixed in frame 0"
            )
        root_to_base = root_to_base @ origin_mm(j)
    T = root_to_base @ ch.dh.frame0  # root link → frame 0
    if T[2, 2] < 1 - 1e-9:
        return [], (
            "no [cell]: frame 0's z axis is not the root link's z axis, so the root link's "
            "xy plane is not a plane z = const in frame 0; give [cell] by hand"
        )
    floor = -float(T[:3, 2] @ T[:3, 3])  # the root origin's z in frame 0
    return [
        "",
        "[cell]",
        "# the mounting plane in frame 0: the URDF's root link's origin (its xy plane) expressed",
        "# in wirecal's frame 0; check that the arm stands there",
        f"floor_z_mm = {round(floor, 6) + 0.0!r}",
        f"margin_mm = {CELL_MARGIN_MM!r}",
    ], None


def _header(robot: Robot, ch: UrdfChain, source: str, notes: list[str]) -> list[str]:
    """Return the robot file's header comments."""
    f0 = ch.dh.frame0
    frame0 = (
        ["frame 0 is the base link's frame"]
        if np.allclose(f0, np.eye(4), atol=0)
        else [
            "frame 0 is not the base link's frame (row 1 cannot place joint 1's axis in it;",
            f"wire lengths do not depend on it): base link → frame 0 is {_pose_text(f0)}",
        ]
    )
    return [
        f"{robot.name}: imported from {source} (chain {ch.base_link} → {ch.tip_link}) by",
        "wirecal import-urdf. Each number below is derived from that URDF: the DH rows from its",
        "joint origins and axes, the limits and speeds from its <limit> tags (rad → deg).",
        *frame0,
        *notes,
        "",
    ]


def _pose_text(T: np.ndarray) -> str:
    xyz = ", ".join(f"{v:.6g}" for v in T[:3, 3])
    rpy = ", ".join(f"{v:.6g}" for v in np.degrees(matrix_rpy(T[:3, :3])))
    return f"xyz ({xyz}) mm, rpy ({rpy}) deg"
