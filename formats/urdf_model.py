"""A URDF's serial chain as a wirecal robot, and a calibrated model back as URDF joint origins.

Import: the chain's joint frames at q = 0 give each revolute axis as a line in the base
link's frame; :func:`wirecal.solver.dh_from_axes.dh_from_axes` writes them in Craig's
modified DH. Fixed joints are folded in (they only move the next axis or the tip). Every link
on the chain keeps a constant transform D from the DH frame of the joint before it, so

    T_base,link(q) = F0 · DH frames(q)[k] · D_link       (k = moving joints before the link)

holds for every q, and for a calibrated model the new link frames are the same product with
the new DH table: each chain joint's new origin is T_parent⁻¹ · T_child at q = 0. Nothing
off the chain changes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.formats.urdf import MOVING, Joint, Urdf, chain, inertial, origin_mm
from wirecal.solver.dh_from_axes import (
    PARALLEL_TOL,
    ChainError,
    DhChain,
    dh_frames,
    dh_from_axes,
)
from wirecal.solver.errors import WirecalError
from wirecal.solver.gravity import MassModel
from wirecal.solver.kinematics import Model


@dataclass(frozen=True)
class UrdfChain:
    """A URDF's serial chain from base to tip and its modified-DH model."""

    urdf: Urdf
    joints: tuple[Joint, ...]  # the path from base to tip, fixed joints included
    moving: tuple[Joint, ...]  # its revolute joints, in order
    dh: DhChain
    link_offsets: dict[str, tuple[int, np.ndarray]]  # link → (k, D): frame k → link
    wire_point_mm: np.ndarray  # the wire attachment point in the tip link's frame

    @property
    def tool_point(self) -> np.ndarray:
        """Return the wire attachment point in DH frame n (the robot file's tool point)."""
        D = self.dh.tip_offset
        return D[:3, :3] @ self.wire_point_mm + D[:3, 3]

    @property
    def base_link(self) -> str:
        """Return the chain's base link."""
        return self.joints[0].parent

    @property
    def tip_link(self) -> str:
        """Return the chain's tip link."""
        return self.joints[-1].child


def _inv(T: np.ndarray) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def read_chain(
    urdf: Urdf,
    base: str | None,
    tip: str,
    parallel_tol: float = PARALLEL_TOL,
    wire_point_mm: np.ndarray | None = None,
) -> UrdfChain:
    """Return the serial chain from ``base`` to ``tip`` in modified DH (see the module doc).

    ``wire_point_mm``: the wire's attachment in the tip link's frame (default its origin).
    The last DH frame is placed from the tip link's origin either way.
    """
    path = chain(urdf, base, tip)
    if not path:
        raise WirecalError(f"{urdf.path}: --base and --tip are the same link {tip!r}")
    T = np.eye(4)
    link_frames = {path[0].parent: (0, T)}
    moving, points, axes, joint_frames = [], [], [], []
    for j in path:
        T = T @ origin_mm(j)
        if j.type in MOVING:
            moving.append(j)
            points.append(T[:3, 3])
            axes.append(T[:3, :3] @ j.axis)
            joint_frames.append(T)
        link_frames[j.child] = (len(moving), T)
    if len(moving) < 2:
        raise WirecalError(
            f"{urdf.path}: the chain from {path[0].parent!r} to {tip!r} has {len(moving)} "
            "revolute joint(s); a serial arm needs at least 2"
        )
    names = [j.name for j in moving]
    try:
        dh = dh_from_axes(
            np.array(points), np.array(axes), T, np.array(joint_frames), names, parallel_tol
        )
    except ChainError as exc:
        raise WirecalError(f"{urdf.path}: {exc}") from None
    F = dh.frame0 @ dh_frames(dh.dh, np.zeros((1, len(moving))))[0]
    offsets = {link: (k, _inv(F[k]) @ L) for link, (k, L) in link_frames.items()}
    wire = np.zeros(3) if wire_point_mm is None else np.asarray(wire_point_mm, dtype=float)
    return UrdfChain(urdf, tuple(path), tuple(moving), dh, offsets, wire)


def chain_masses(ch: UrdfChain) -> MassModel | None:
    """Return the chain's links' masses from their ``<inertial>`` (None: no link has one).

    Link k of the robot file (the body joint k turns) gathers every chain link after moving
    joint k (fixed joints fold links together): their masses add, their centres (each the
    ``<inertial>`` origin in its link's frame, moved into DH frame k by the link's constant
    offset) average by mass. Links off the chain (a gripper's fingers) are left out; the
    base's links (k = 0) hold no torque.
    """
    n = len(ch.moving)
    mass, moment = np.zeros(n), np.zeros((n, 3))
    found = False
    for link, (k, D) in ch.link_offsets.items():
        data = inertial(ch.urdf, link)
        if data is None or k == 0:
            continue
        m_kg, com_mm = data
        found = True
        mass[k - 1] += m_kg
        moment[k - 1] += m_kg * (D[:3, :3] @ com_mm + D[:3, 3])
    if not found:
        return None
    com = np.divide(moment, mass[:, None], out=np.zeros((n, 3)), where=mass[:, None] > 0)
    return MassModel(mass, com, source=f"URDF <inertial> of {ch.urdf.path.name}")


def calibrated_origins(ch: UrdfChain, model: Model) -> dict[str, np.ndarray]:
    """Return new origins (4×4, mm) of the chain's joints for the model ``model`` (same joints)."""
    n = len(ch.moving)
    F = ch.dh.frame0 @ dh_frames(model.dh, np.zeros((1, n)))[0]
    tool_moved = not np.allclose(model.tool_point, ch.tool_point, rtol=0, atol=1e-12)
    frames_ = {}
    for link, (k, D) in ch.link_offsets.items():
        D = D.copy()
        if link == ch.tip_link and tool_moved:
            last = ch.joints[-1]
            if last.type in MOVING:
                raise WirecalError(
                    f"{ch.urdf.path}: the tool point changed but the tip link {link!r} is the "
                    f"child of revolute joint {last.name!r}: its origin must stay on the axis. "
                    "Add a fixed joint to a tool link and import with that tip"
                )
            D[:3, 3] = model.tool_point - D[:3, :3] @ ch.wire_point_mm
        frames_[link] = F[k] @ D
    return {j.name: _inv(frames_[j.parent]) @ frames_[j.child] for j in ch.joints}


def _axis_angle(k: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Rotations (N, 3, 3) by angles q (N,) about the unit axis k (Rodrigues)."""
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    s, c = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
    return np.eye(3) + s * K + (1 - c) * (K @ K)


def urdf_tip_mm(ch: UrdfChain, q: np.ndarray) -> np.ndarray:
    """Return the wire point in the base link (N, 3) straight from the URDF's joints, q (N, n)."""
    q = np.atleast_2d(q)
    T = np.broadcast_to(np.eye(4), (len(q), 4, 4)).copy()
    k = 0
    for j in ch.joints:
        T = T @ origin_mm(j)
        if j.type in MOVING:
            M = np.broadcast_to(np.eye(4), (len(q), 4, 4)).copy()
            M[:, :3, :3] = _axis_angle(j.axis, q[:, k])
            T = T @ M
            k += 1
    return T[:, :3, :3] @ ch.wire_point_mm + T[:, :3, 3]


def fk_difference_mm(ch: UrdfChain, q: np.ndarray) -> float:
    """Return the largest tip distance between the URDF and the DH model.

    The largest distance between the URDF's tip and the DH model's over configurations
    q (N, n) in radians: the import's check of itself.
    """
    F = ch.dh.frame0 @ dh_frames(ch.dh.dh, q)
    tip = F[:, -1, :3, :3] @ ch.tool_point + F[:, -1, :3, 3]
    return float(np.max(np.linalg.norm(tip - urdf_tip_mm(ch, q), axis=1)))
