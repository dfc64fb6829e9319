"""Link radii for the wire clearance, estimated from a URDF's geometry or its link lengths.

The clearance (:mod:`wirecal.solver.cell.clearance`) models link k as a capsule from DH frame k's
origin to frame k+1's (k = 1 … n−1) with a radius from ``[geometry] link_radius_mm``. Every
URDF link on the chain is rigid with one DH frame
(:class:`~wirecal.formats.urdf_model.UrdfChain` ``link_offsets``). With the arm at
q = 0, each point of the moving links' geometry is taken by the nearest capsule segment; the
radius of capsule k is the largest distance of the points beside segment k (their foot
between its ends), so the capsule contains them. Points beyond every segment's ends (the base
column under frame 1, joint housings) are counted and reported, not covered; a link whose
own geometry lies only there is named (its unit is not guessed: housings stand past joints,
and millimetres read as metres reach beyond ``MAX_OFFSET_M``, refused). The geometry
read:

* ``<collision>`` elements (``<visual>`` when a link has none): cylinders (their end discs),
  boxes (their corners), spheres (centre plus radius) and STL meshes (their vertices, with the
  mesh's ``scale``), each placed by its ``<origin>``;
* when a capsule's links have no geometry, or name a mesh that is absent or not STL, its
  radius comes from lengths instead: the larger of :data:`RADIUS_PER_LENGTH` × the capsule's
  length and :data:`RADIUS_PER_REACH` × the arm's (the sum of the capsules' lengths). On the
  UR5 (published radii 40–75 mm) that gives 50–64 mm; on the Viper s650 37–46 mm (the
  shipped example estimates 37–70 mm).

Either way an estimate: the import says which links it came from, and a measured value
belongs in the robot file. Containing capsules about DH lines can be wide: the Viper s650's
public meshes give 217, 203 and 158 mm for links 1–3 (a wide shoulder housing, an upper arm off
the DH line), and ``plan`` then finds no wire path; the import warns when a radius from
geometry exceeds :data:`WIDE_RATIO` times the length rule's.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.formats.stl import stl_vertices
from wirecal.formats.urdf import check_reach, rpy_matrix
from wirecal.formats.urdf_model import UrdfChain
from wirecal.solver.dh_from_axes import dh_frames
from wirecal.solver.errors import WirecalError

RADIUS_PER_LENGTH = 0.15
"""A link's radius from its length: 15 % (the UR5's upper arm: 425 mm long, 54–60 mm radius)."""
RADIUS_PER_REACH = 0.05
"""The smallest radius from the arm's size: 5 % of its reach (the UR5's wrist: 45 mm of 1010)."""
WIDE_RATIO = 2.0
"""A radius from geometry this many times the length rule's is reported as wide."""
DISC_POINTS = 16
"""Points on each end disc of a cylinder (the capsule's radius is then within 2 % of exact)."""
ANCESTORS = 4
"""Folders above the URDF searched for a ``package://`` mesh's package."""


@dataclass(frozen=True)
class LinkRadii:
    """Capsule radii (mm) and, per capsule, the URDF links they were measured on."""

    radius_mm: np.ndarray  # (n-1,), whole mm rounded up
    measured: tuple[tuple[str, ...], ...]  # links whose geometry gave the radius; () by length
    notes: tuple[str, ...]  # why some radii come from lengths
    uncovered: str | None = None  # how much geometry lies beyond the capsules' ends
    only_beyond: tuple[int, ...] = ()  # links (1-based) whose own geometry is all beyond its ends
    by_length_mm: np.ndarray | None = None  # the length rule's radii, for comparison


def _origin(el: ET.Element) -> np.ndarray:
    """Return an element's ``<origin>`` as a 4×4 transform in mm (identity when absent)."""
    T = np.eye(4)
    o = el.find("origin")
    if o is not None:
        T[:3, :3] = rpy_matrix(np.array([float(v) for v in o.get("rpy", "0 0 0").split()]))
        T[:3, 3] = 1000.0 * np.array([float(v) for v in o.get("xyz", "0 0 0").split()])
    return T


def mesh_path(filename: str, urdf_path: Path) -> Path | None:
    """Return the file a mesh ``filename`` names, or None when it is not there.

    ``package://PKG/rest``: a folder named PKG among the URDF's folder and its
    :data:`ANCESTORS` parents, or beside one of them; ``file://`` an absolute path;
    anything else relative to the URDF's folder.
    """
    here = urdf_path.resolve().parent
    if filename.startswith("file://"):
        candidates = [Path(filename[len("file://") :])]
    elif filename.startswith("package://"):
        package, _, rest = filename[len("package://") :].partition("/")
        folders = [here, *list(here.parents)[:ANCESTORS]]
        candidates = [f / rest for f in folders if f.name == package]
        candidates += [f / package / rest for f in folders]
    else:
        candidates = [here / filename]
    return next((c for c in candidates if c.is_file()), None)


def _shape(geometry: ET.Element, urdf_path: Path) -> tuple[np.ndarray, float]:
    """Return points (k, 3) in mm, in the geometry's frame, and a padding radius (mm).

    The shape lies within the padding of the points. Raise :class:`WirecalError` saying why
    a mesh cannot be read.
    """
    shape = next(iter(geometry), None)
    if shape is None:
        raise WirecalError("an empty <geometry>")
    kind = shape.tag
    try:
        if kind == "box":
            half = 500.0 * np.array([float(v) for v in shape.get("size", "").split()])
            corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
            return corners * half, 0.0
        if kind == "sphere":
            return np.zeros((1, 3)), 1000.0 * float(shape.get("radius", ""))
        if kind == "cylinder":
            r = 1000.0 * float(shape.get("radius", ""))
            h = 500.0 * float(shape.get("length", ""))
            a = np.linspace(0, 2 * np.pi, DISC_POINTS, endpoint=False)
            rim = np.c_[r * np.cos(a), r * np.sin(a)]
            return np.r_[np.c_[rim, np.full(len(a), -h)], np.c_[rim, np.full(len(a), h)]], 0.0
    except ValueError:
        raise WirecalError(f"<{kind}> has a dimension that is not a number") from None
    if kind != "mesh":
        raise WirecalError(f"geometry <{kind}> is not one wirecal reads")
    name = shape.get("filename", "")
    path = mesh_path(name, urdf_path)
    if path is None:
        raise WirecalError(f"mesh {name} is not there")
    if path.suffix.lower() != ".stl":
        raise WirecalError(f"mesh {name} is not an STL file (the format wirecal reads)")
    scale = np.array([float(v) for v in shape.get("scale", "1 1 1").split()])
    return 1000.0 * stl_vertices(path) * scale, 0.0


def _check_shape_reach(points: np.ndarray, pad: float, where: str) -> None:
    """Refuse a shape (points in its link's frame, mm) reaching too far (:func:`check_reach`).

    Such a shape was written in millimetres; read as metres it would be dropped as lying
    beyond the links, leaving the link the length rule's thin capsule.
    """
    finite = np.nan_to_num(points, nan=np.inf)  # inf − inf of an overflowed shape: nan
    reach_m = (float(np.max(np.linalg.norm(finite, axis=1), initial=0.0)) + pad) / 1000.0
    check_reach(
        reach_m,
        f"{where}: its geometry reaches {reach_m:.4g} m from the link's origin,",
        ' (a mesh in mm: scale="0.001 0.001 0.001")',
    )


def _link_points(link: ET.Element, urdf_path: Path) -> list[tuple[np.ndarray, float]]:
    """Return a link's shapes as (points in the link frame (k, 3) mm, padding mm)."""
    elements = link.findall("collision") or link.findall("visual")
    out = []
    for el in elements:
        geometry = el.find("geometry")
        if geometry is None:
            continue
        points, pad = _shape(geometry, urdf_path)
        try:
            T = _origin(el)
        except ValueError:
            raise WirecalError("a geometry's <origin> is not numbers") from None
        out.append((points @ T[:3, :3].T + T[:3, 3], pad))
    return out


def _nearest_segment(
    points: np.ndarray, starts: np.ndarray, ends: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return, per point (k, 3), its nearest segment, the distance and whether it is beside it.

    "Beside": the point's foot on that segment lies between its ends (a zero-length
    segment counts as beside every point), not beyond one end.
    """
    d = ends - starts  # (m, 3)
    dd = np.einsum("mc,mc->m", d, d)
    rel = points[:, None, :] - starts[None]  # (k, m, 3)
    safe = np.where(dd > 0, dd, 1.0)
    t = np.where(dd > 0, np.einsum("kmc,mc->km", rel, d) / safe, 0.0)
    inside = (t >= -1e-9) & (t <= 1 + 1e-9)
    dist = np.linalg.norm(rel - np.clip(t, 0, 1)[..., None] * d[None], axis=2)
    nearest = np.argmin(dist, axis=1)
    rows = np.arange(len(points))
    return nearest, dist[rows, nearest], inside[rows, nearest]


def link_radii(ch: UrdfChain) -> LinkRadii:
    """Return the capsule radii of the chain ``ch`` (see the module doc)."""
    n = len(ch.moving)
    F = dh_frames(ch.dh.dh, np.zeros((1, n)))[0]  # frames at q = 0, in frame 0
    starts, ends = F[1:n, :3, 3], F[2 : n + 1, :3, 3]
    lengths = np.linalg.norm(ends - starts, axis=1)
    by_length = np.maximum(RADIUS_PER_LENGTH * lengths, RADIUS_PER_REACH * lengths.sum())
    points, pads, frames, unreadable = _chain_points(ch, F)
    own = np.bincount(frames, minlength=n + 1)  # geometry points of each DH frame's links
    found = np.full(n - 1, -np.inf)
    beyond = 0
    if len(points):
        nearest, dist, beside = _nearest_segment(points, starts, ends)
        np.maximum.at(found, nearest[beside], dist[beside] + pads[beside])
        beyond = int(np.count_nonzero(~beside))
    radii = by_length.copy()
    measured: list[tuple[str, ...]] = []
    notes: list[str] = []
    only_beyond = []
    for k in range(1, n):
        if k in unreadable or not np.isfinite(found[k - 1]):
            why = unreadable.get(k, "no collision or visual geometry beside it")
            if k not in unreadable and own[k]:
                only_beyond.append(k)
                why = (
                    f"its links' {own[k]} geometry point(s) lie beyond its ends, none beside "
                    "it (a housing past a joint, or a geometry <origin> off the link: check it)"
                )
            measured.append(())
            notes.append(f"link {k}: {why}")
            continue
        radii[k - 1] = found[k - 1]
        measured.append(tuple(x for x, (frame, _) in ch.link_offsets.items() if frame == k))
    uncovered = (
        f"{beyond} of {len(points)} geometry points lie beyond the links' ends (the base "
        "column, joint housings): the capsules do not cover them"
        if beyond
        else None
    )
    return LinkRadii(
        np.ceil(radii), tuple(measured), tuple(notes), uncovered, tuple(only_beyond), by_length
    )


def wide_links(radii: LinkRadii) -> list[int]:
    """Return the links (1-based) whose radius from geometry is :data:`WIDE_RATIO` × wide."""
    if radii.by_length_mm is None:
        return []
    return [
        k
        for k, (r, rule, links) in enumerate(
            zip(radii.radius_mm, radii.by_length_mm, radii.measured, strict=True), 1
        )
        if links and r > WIDE_RATIO * rule
    ]


def _chain_points(ch: UrdfChain, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """Return the moving links' geometry points (k, 3) in frame 0 at q = 0, pads, DH frames.

    Each point's pad (mm) and its link's DH frame; and, per DH frame whose links' geometry
    cannot be read, why. The base's own links (frame 0) are left out: no capsule models them.
    """
    elements = {el.get("name"): el for el in ch.urdf.root.findall("link")}
    points, pads, unreadable = [np.zeros((0, 3))], [np.zeros(0)], {}
    frames = [np.zeros(0, dtype=int)]
    for link, (k, D) in ch.link_offsets.items():
        if k == 0 or k in unreadable:
            continue
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # too large: refused below
                shapes = _link_points(elements[link], ch.urdf.path)
        except WirecalError as exc:
            unreadable[k] = f"{link}'s {exc}"
            continue
        T = F[k] @ D
        for p, pad in shapes:
            _check_shape_reach(p, pad, f"{ch.urdf.path}: link {link!r}")
            points.append(p @ T[:3, :3].T + T[:3, 3])
            pads.append(np.full(len(p), pad))
            frames.append(np.full(len(p), k))
    return np.concatenate(points), np.concatenate(pads), np.concatenate(frames), unreadable
