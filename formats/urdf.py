"""URDF files: read the kinematic tree, find a serial chain, write new joint origins.

URDF files: read the kinematic tree, find the serial chain from a base link to a tip link,
and write a copy with new joint origins (everything else — links, visuals, collisions,
inertias, comments — kept as it is).

A small reader on the standard library (``xml.etree``) rather than a URDF package: wirecal
needs only joints' origins, axes, types and limits, and the packages that parse URDF fully
(yourdfpy, urdfpy) pull in mesh libraries (trimesh, networkx, lxml) to load geometry that is
never used here. Units are the URDF's (m, rad) in :class:`Joint`; mm at :func:`origin_mm`.

Hostile files are refused before they cost memory or time: a file larger than
:data:`MAX_URDF_BYTES`, elements nested deeper than :data:`MAX_DEPTH` or more than
:data:`MAX_ELEMENTS` of them, and any entity declaration (a URDF needs none; entities are how
"billion laughs" files expand) — all found by a streaming pass of expat before the tree is
built. The joints must form a tree: a link with two parent joints, a joint naming an
undeclared link, or a loop of joints is an error naming them.
"""

from __future__ import annotations

import copy
import math
import xml.etree.ElementTree as ET
import xml.parsers.expat
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.formats.fileio import read_input
from wirecal.formats.robot_values import MAX_SPEED_DEG_S
from wirecal.solver.dh_from_axes import dh_frames
from wirecal.solver.errors import WirecalError

MOVING = ("revolute", "continuous")
SUPPORTED = (*MOVING, "fixed")

MAX_URDF_BYTES = 32 * 1024 * 1024
"""Largest URDF read (bytes): vendor URDFs are 10–500 kB; a humanoid's with inline
collision boxes a few MB."""
MAX_DEPTH = 64
"""Deepest element nesting accepted: a URDF's is 5 (robot/link/visual/geometry/mesh), with
Gazebo plugin blocks about 10."""
MAX_ELEMENTS = 500_000
"""Most elements accepted: a 100-link URDF has a few thousand."""
LINKS_SHOWN = 20
"""Links a message lists before "and N more"."""


@dataclass(frozen=True)
class Joint:
    """One URDF joint: its type, links, origin, axis and limits."""

    name: str
    type: str
    parent: str
    child: str
    xyz_m: np.ndarray  # origin translation
    rpy_rad: np.ndarray  # origin rotation: fixed-axis roll, pitch, yaw
    axis: np.ndarray  # unit vector in the joint frame
    lower_rad: float | None
    upper_rad: float | None
    velocity_rad_s: float | None
    mimic: bool = False


@dataclass(frozen=True)
class Urdf:
    """A parsed URDF: its links and joints, and the document to write back."""

    path: Path
    name: str
    root: ET.Element  # the parsed document, comments kept
    links: tuple[str, ...]
    joints: dict[str, Joint]


def _floats(text: str | None, default: str, where: str, count: int = 3) -> np.ndarray:
    parts = (text if text is not None else default).split()
    try:
        values = np.array([float(v) for v in parts])
    except ValueError:
        raise WirecalError(f"{where}: {text!r} is not {count} numbers") from None
    if values.shape != (count,) or not np.all(np.isfinite(values)):
        raise WirecalError(f"{where}: {text!r} is not {count} finite numbers")
    return values


MAX_LINK_MASS_KG = 10_000.0
"""Largest link mass an ``<inertial>`` may give (kg): the robot file's own bound."""


def inertial(urdf: Urdf, link: str) -> tuple[float, np.ndarray] | None:
    """Return a link's ``<inertial>`` mass (kg) and centre of mass (mm, in the link's frame).

    None when the link has no ``<inertial>``; a mass that is missing, negative or not a
    number is refused naming the link. The centre's ``rpy`` does not move it.
    """
    el = next((e for e in urdf.root.iter("link") if e.get("name") == link), None)
    block = None if el is None else el.find("inertial")
    if block is None:
        return None
    where = f"{urdf.path}: link {link!r}: <inertial>"
    mass_el = block.find("mass")
    try:
        mass = float(mass_el.get("value", "")) if mass_el is not None else math.nan
    except ValueError:
        mass = math.nan
    if not 0.0 <= mass <= MAX_LINK_MASS_KG:
        raise WirecalError(
            f"{where}: <mass value> is not a mass of 0 to {MAX_LINK_MASS_KG:g} kg; correct the "
            "URDF or remove the <inertial> (the masses are then assumed)"
        )
    origin = block.find("origin")
    xyz = _floats(None if origin is None else origin.get("xyz"), "0 0 0", f"{where} origin xyz")
    _check_metres(xyz, f"{where} origin xyz")
    return mass, xyz * 1000.0


def _limit(el: ET.Element | None, key: str, where: str) -> float | None:
    if el is None or el.get(key) is None:
        return None
    try:
        value = float(el.get(key, ""))
    except ValueError:
        raise WirecalError(f"{where}: limit {key}={el.get(key)!r} is not a number") from None
    if not math.isfinite(value):
        raise WirecalError(f"{where}: limit {key}={el.get(key)!r} is not finite")
    return value


def _screen(data: bytes, path: Path) -> None:
    """Refuse entity declarations, deep nesting and too many elements (one streaming pass)."""
    parser = xml.parsers.expat.ParserCreate()
    depth = count = 0

    def where() -> str:
        return f"{path}: line {parser.CurrentLineNumber}"

    def start(name: str, _attrs: dict) -> None:
        nonlocal depth, count
        depth += 1
        count += 1
        if depth > MAX_DEPTH:
            raise WirecalError(
                f"{where()}: <{name}> is nested {depth} elements deep (at most {MAX_DEPTH} "
                "accepted): not a URDF"
            )
        if count > MAX_ELEMENTS:
            raise WirecalError(
                f"{where()}: more than {MAX_ELEMENTS} elements: not a URDF wirecal reads"
            )

    def end(_name: str) -> None:
        nonlocal depth
        depth -= 1

    def entity(name: str, *_args: object) -> None:
        raise WirecalError(
            f"{where()}: declares the entity {name!r}; a URDF needs none and wirecal expands "
            "none (remove the <!DOCTYPE …> block)"
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.EntityDeclHandler = entity
    try:
        parser.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        raise WirecalError(f"{path}: not valid XML: {exc}") from None


def _joint(el: ET.Element, path: Path, links: set[str]) -> Joint:
    """Return one <joint> element as a :class:`Joint`; raise naming the joint."""
    name = el.get("name") or ""
    where = f"{path}: joint {name!r}"
    if not name:
        raise WirecalError(f"{path}: a <joint> has no name")
    parent, child = el.find("parent"), el.find("child")
    if parent is None or child is None or not parent.get("link") or not child.get("link"):
        raise WirecalError(f"{where}: needs <parent link=…/> and <child link=…/>")
    for role, link in (("parent", parent.get("link", "")), ("child", child.get("link", ""))):
        if link not in links:
            raise WirecalError(
                f"{where}: its {role} link {link!r} is not a <link> of this URDF; declare it "
                "or correct the name"
            )
    origin = el.find("origin")
    axis_el = el.find("axis")
    axis = _floats(None if axis_el is None else axis_el.get("xyz"), "1 0 0", f"{where}: <axis xyz>")
    norm = float(np.linalg.norm(axis))
    if norm == 0 and el.get("type") in MOVING:  # a fixed joint's axis is ignored
        raise WirecalError(f"{where}: <axis xyz> is the zero vector")
    limit = el.find("limit")
    joint = Joint(
        name=name,
        type=el.get("type", ""),
        parent=parent.get("link", ""),
        child=child.get("link", ""),
        xyz_m=_floats(
            None if origin is None else origin.get("xyz"), "0 0 0", f"{where}: origin xyz"
        ),
        rpy_rad=_floats(
            None if origin is None else origin.get("rpy"), "0 0 0", f"{where}: origin rpy"
        ),
        axis=axis / norm if norm else axis,
        lower_rad=_limit(limit, "lower", where),
        upper_rad=_limit(limit, "upper", where),
        velocity_rad_s=_limit(limit, "velocity", where),
        mimic=el.find("mimic") is not None,
    )
    _check_units(joint, where)
    return joint


MAX_ANGLE_RAD = 2 * math.pi
"""An origin angle beyond this is in degrees (a URDF's angles are radians)."""
MAX_LIMIT_RAD = 4 * math.pi
"""A joint limit beyond this is in degrees (the widest arms turn ±2 turns)."""
MAX_OFFSET_M = 10.0
"""An origin offset beyond this is in millimetres (a URDF's lengths are metres)."""
MAX_VELOCITY_RAD_S = math.radians(MAX_SPEED_DEG_S)
"""A joint velocity beyond the robot file's bound is in deg/s (a URDF's are rad/s)."""


def _check_units(j: Joint, where: str) -> None:
    """Refuse angles and speeds in degrees and lengths in millimetres, naming the attribute."""
    for k, v in enumerate(j.rpy_rad):
        if abs(v) > MAX_ANGLE_RAD:
            raise WirecalError(
                f"{where}: origin rpy value {k + 1} is {v:g}, beyond ±2π: URDF angles are "
                "radians; written in degrees? Convert them (× π/180) and import again"
            )
    for key, v in (("lower", j.lower_rad), ("upper", j.upper_rad)):
        if v is not None and abs(v) > MAX_LIMIT_RAD and j.type in MOVING:
            raise WirecalError(
                f"{where}: limit {key}={v:g}, beyond ±4π: URDF limits are radians; written "
                "in degrees? Convert them (× π/180) and import again"
            )
    if j.type in MOVING and (j.velocity_rad_s or 0.0) > MAX_VELOCITY_RAD_S:
        raise WirecalError(
            f"{where}: limit velocity={j.velocity_rad_s:g}, beyond {MAX_VELOCITY_RAD_S:.4g} "
            f"rad/s ({MAX_SPEED_DEG_S:g} deg/s): URDF velocities are rad/s; written in deg/s? "
            "Convert them (× π/180) and import again"
        )
    _check_metres(j.xyz_m, f"{where}: origin xyz")


def check_reach(reach_m: float, what: str, fix: str = "") -> None:
    """Refuse a length in millimetres: a reach beyond :data:`MAX_OFFSET_M` (or NaN).

    ``reach_m``: how far an origin offset or a shape reaches from its frame's origin (m);
    ``what`` says so, ending where the message goes on with "beyond 10 m"; ``fix`` adds
    to "Divide them by 1000".
    """
    if not reach_m <= MAX_OFFSET_M:
        raise WirecalError(
            f"{what} beyond {MAX_OFFSET_M:g} m: URDF lengths are metres; written in "
            f"millimetres? Divide them by 1000{fix} and import again"
        )


def _check_metres(xyz_m: np.ndarray, what: str) -> None:
    """Refuse an origin offset ``what`` names that is in millimetres (:func:`check_reach`)."""
    check_reach(math.hypot(*xyz_m), f"{what} {' '.join(f'{v:g}' for v in xyz_m)} is")


def read_urdf(path: str | Path) -> Urdf:
    """Parse a URDF; any problem is a :class:`WirecalError` naming the file and joint."""
    path = Path(path)
    data = read_input(path, "URDF", MAX_URDF_BYTES)[0]
    _screen(data, path)
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    try:
        parser.feed(data)
        root = parser.close()
    except ET.ParseError as exc:
        raise WirecalError(f"{path}: not valid XML: {exc}") from None
    if root.tag != "robot":
        raise WirecalError(f"{path}: the root element is <{root.tag}>, not <robot>: not a URDF")
    links = tuple(el.get("name", "") for el in root.findall("link"))
    for x, count in Counter(links).items():
        if count > 1:
            raise WirecalError(f"{path}: link {x!r} is defined {count} times")
    joints: dict[str, Joint] = {}
    for el in root.findall("joint"):
        j = _joint(el, path, set(links))
        if j.name in joints:
            raise WirecalError(f"{path}: joint {j.name!r}: defined twice")
        joints[j.name] = j
    urdf = Urdf(path, root.get("name", ""), root, links, joints)
    _check_tree(urdf)
    return urdf


def chain(urdf: Urdf, base: str | None, tip: str) -> list[Joint]:
    """Return the joints from ``base`` (default: the root of the tree ``tip`` is in) to ``tip``."""
    by_child = _parent_joints(urdf)
    for link, what in ((tip, "--tip"), (base, "--base")):
        if link is not None and link not in urdf.links:
            shown = ", ".join(urdf.links[:LINKS_SHOWN])
            more = (
                f" and {len(urdf.links) - LINKS_SHOWN} more"
                if len(urdf.links) > LINKS_SHOWN
                else ""
            )
            raise WirecalError(
                f"{urdf.path}: {what} {link!r} is not a link of this URDF (links: {shown}{more})"
            )
    if base is None:  # the root the tip descends from (a URDF may hold several trees)
        base = tip
        seen = {tip}
        while base in by_child and by_child[base].parent not in seen:
            base = by_child[base].parent
            seen.add(base)
    path: list[Joint] = []
    link = tip
    while link != base:
        if link not in by_child:
            raise WirecalError(
                f"{urdf.path}: there is no serial path from {base!r} to {tip!r} "
                f"({tip!r} does not descend from {base!r}); choose --base and --tip on one branch"
            )
        j = by_child[link]
        path.append(j)
        link = j.parent
    path.reverse()
    _check_supported(urdf, path)
    return path


def _parent_joints(urdf: Urdf) -> dict[str, Joint]:
    """Return each child link's joint; raise on a link with two parent joints."""
    by_child: dict[str, Joint] = {}
    for j in urdf.joints.values():
        if j.child in by_child:
            raise WirecalError(
                f"{urdf.path}: link {j.child!r} is the child of joints {by_child[j.child].name!r} "
                f"and {j.name!r}: a URDF must be a tree"
            )
        by_child[j.child] = j
    return by_child


def _check_tree(urdf: Urdf) -> None:
    """Raise on two parents of a link or a loop of joints, naming the joints.

    Each link is walked up towards its root once (links already known to reach a root
    end the walk), so the check is linear in the number of joints.
    """
    by_child = _parent_joints(urdf)
    rooted: set[str] = set()
    for start in by_child:
        walk: list[str] = []
        on_walk: set[str] = set()
        link = start
        while link in by_child and link not in rooted:
            if link in on_walk:
                loop = walk[walk.index(link) :]
                names = " → ".join(by_child[x].name for x in reversed(loop))
                raise WirecalError(
                    f"{urdf.path}: the joints {names} form a loop (link {link!r} is its own "
                    "ancestor): a URDF must be a tree; remove one of them"
                )
            walk.append(link)
            on_walk.add(link)
            link = by_child[link].parent
        rooted.update(walk)


def _check_supported(urdf: Urdf, path: list[Joint]) -> None:
    """Raise on a joint of the chain that is not an independent revolute (or fixed) joint."""
    for j in path:
        if j.type not in SUPPORTED:
            kind = "a prismatic joint" if j.type == "prismatic" else f"type {j.type!r}"
            raise WirecalError(
                f"{urdf.path}: joint {j.name!r} is {kind}: wirecal models arms of revolute "
                "joints only (fixed joints are folded in)"
            )
        if j.mimic:
            raise WirecalError(
                f"{urdf.path}: joint {j.name!r} mimics another joint: not an independent axis"
            )


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """URDF's rotation: R = Rz(yaw)·Ry(pitch)·Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(R: np.ndarray) -> np.ndarray:
    """Return the roll, pitch and yaw of a rotation (the inverse of :func:`rpy_matrix`).

    The inverse of :func:`rpy_matrix` (pitch in [−π/2, π/2]). Near pitch ±90° roll and
    yaw are ill-conditioned one by one (only their sum or difference is not), so the first
    guess is refined by least squares on the rotation itself: rpy_matrix of the result
    equals R to round-off at any pitch.
    """
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.hypot(R[0, 0], R[1, 0]) > 1e-12:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: yaw absorbs the rotation about z
        roll = 0.0
        yaw = math.atan2(-R[0, 1], R[1, 1])
    rpy = np.array([roll, pitch, yaw])
    for _ in range(3):
        E = R @ rpy_matrix(rpy).T
        w = 0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])
        cy, sy, cp, sp = math.cos(rpy[2]), math.sin(rpy[2]), math.cos(rpy[1]), math.sin(rpy[1])
        # angular velocity in the parent frame per unit roll, pitch, yaw rate
        J = np.array([[cy * cp, -sy, 0.0], [sy * cp, cy, 0.0], [-sp, 0.0, 1.0]])
        rpy = rpy + np.linalg.lstsq(J, w, rcond=1e-12)[0]
    return rpy


def origin_mm(j: Joint) -> np.ndarray:
    """Return the joint's origin as a 4×4 transform, translation in mm."""
    T = np.eye(4)
    T[:3, :3] = rpy_matrix(j.rpy_rad)
    T[:3, 3] = 1000.0 * j.xyz_m
    return T


def urdf_with_origins(urdf: Urdf, origins_mm: dict[str, np.ndarray]) -> str:
    """Return the URDF's text with the named joints' origins replaced.

    The URDF's text with the named joints' origins replaced (4×4, mm), full precision;
    everything else as it was (re-indented).
    """
    root = copy.deepcopy(urdf.root)
    by_name = {el.get("name"): el for el in root.findall("joint")}
    for name, T in origins_mm.items():
        el = by_name[name]
        origin = el.find("origin")
        if origin is None:
            origin = ET.Element("origin")
            el.insert(0, origin)
        xyz = T[:3, 3] / 1000.0
        origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
        origin.set("rpy", " ".join(repr(float(v)) for v in matrix_rpy(T[:3, :3])))
    ET.indent(root)
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def dh_urdf_text(
    name: str,
    dh: np.ndarray,
    tool_point_mm: np.ndarray,
    lo_deg: np.ndarray,
    hi_deg: np.ndarray,
    speed_deg_s: np.ndarray,
    floor_z_mm: float = 0.0,
) -> str:
    """Return a URDF of a modified-DH chain with no geometry.

    A URDF of a modified-DH chain with no geometry: the root link ``mount`` on the mounting
    face (``floor_z_mm`` below DH frame 0: ``import-urdf`` takes its plane as the floor), a
    fixed joint to ``link0`` (DH frame 0) … ``link<n>`` (DH frames), joints ``joint<i>``
    turning about their link's z within ``lo_deg``..``hi_deg``, and a fixed joint to
    ``wire_point`` at the tool point. Lengths in m, angles in rad, full precision.
    """
    n = len(dh)
    F = dh_frames(dh, np.zeros((1, n)))[0]
    lines = ['<?xml version="1.0"?>', f'<robot name="{_xml(name)}">', '  <link name="mount"/>']
    lines += [f'  <link name="link{i}"/>' for i in range(n + 1)]
    lines.append('  <link name="wire_point"/>')

    def origin(T: np.ndarray) -> str:
        xyz = " ".join(repr(float(v) / 1000.0) for v in T[:3, 3])
        rpy = " ".join(repr(float(v)) for v in matrix_rpy(T[:3, :3]))
        return f'<origin xyz="{xyz}" rpy="{rpy}"/>'

    mount = np.eye(4)
    mount[2, 3] = -floor_z_mm
    lines += [
        '  <joint name="mount_joint" type="fixed">',
        '    <parent link="mount"/><child link="link0"/>',
        f"    {origin(mount)}",
        "  </joint>",
    ]
    for i in range(n):
        T = np.linalg.solve(F[i], F[i + 1])
        lines += [
            f'  <joint name="joint{i + 1}" type="revolute">',
            f'    <parent link="link{i}"/><child link="link{i + 1}"/>',
            f"    {origin(T)}",
            '    <axis xyz="0 0 1"/>',
            f'    <limit lower="{math.radians(lo_deg[i])!r}" upper="{math.radians(hi_deg[i])!r}" '
            f'effort="0" velocity="{math.radians(speed_deg_s[i])!r}"/>',
            "  </joint>",
        ]
    tool = np.eye(4)
    tool[:3, 3] = tool_point_mm
    lines += [
        '  <joint name="wire_point_joint" type="fixed">',
        f'    <parent link="link{n}"/><child link="wire_point"/>',
        f"    {origin(tool)}",
        "  </joint>",
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


def _xml(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")
