"""Static gravity torques at the joints of a serial arm, for its joint compliance.

Joint j yields under the static gravity torque it holds: δθ_j = c_j · τ_j(q), with c_j
its compliance (rad/(N·m); the robot file's ``compliance_urad_per_nm``) and

    τ_j(q) = z_j · Σ_{k ≥ j} (r_k − o_j) × m_k g ĝ        (N·m; lengths mm / 1000)

over the links k carried by joint j (link k is the body moved by joint k, its centre of
mass ``link_com_mm[k]`` in DH frame k, Craig's modified convention) and the payload (its
centre in the last frame). ĝ is the direction of gravity in the base frame. A positive c_j
makes the joint give way in the direction gravity pulls it.

First-order approximation: τ is evaluated at the commanded configuration, not at the
deflected one; the difference, c·(∂τ/∂q)·c·τ, is of order (c·τ)² (10⁻¹⁰ rad for the
compliances of industrial arms, 1–10 µrad/(N·m) under tens of N·m).

Nothing here imports the kinematics: the torques are computed from the frames' axes and
origins, arrays (N, n+1, 3) of :class:`~wirecal.solver.kinematics.Frames`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from wirecal.solver.rows import ROW_BLOCK, row_blocks

STANDARD_GRAVITY_M_S2 = 9.80665
"""Standard acceleration of gravity (m/s²)."""

DEFAULT_LINK_KG_PER_M = 10.0
"""A link's mass per metre of its length (a_{k} and d_{k+1}) when the robot file gives no
masses: an assumption (a hollow cast-aluminium link of industrial arms of 5–20 kg payload
weighs 5–20 kg/m), stated so that the torques' shape over the workspace is plausible; the
identified compliance absorbs the masses' overall scale of each joint only when the
masses' distribution is right."""

DOWN = (0.0, 0.0, -1.0)
"""Gravity's direction in the base frame when the robot file gives none (floor-mounted)."""


@dataclass(frozen=True)
class MassModel:
    """Masses and centres of mass of an arm's links and payload, and gravity's direction.

    ``link_com_mm[k]`` is link k+1's centre of mass in DH frame k+1 (the frame joint k+1
    turns); ``payload_com_mm`` is in the last frame (the flange). ``assumed`` says the
    masses are :func:`default_masses`' (no data sheet or URDF), ``source`` where they come
    from. ``load_kg`` (one per configuration the model is evaluated at, or None) is a
    mass the operator mounts at the flange for some of them, its centre ``load_com_mm``
    in the last frame (the plan's payload step, :func:`with_load`).
    """

    link_mass_kg: np.ndarray  # (n,)
    link_com_mm: np.ndarray  # (n, 3)
    payload_mass_kg: float = 0.0
    payload_com_mm: np.ndarray = field(default_factory=lambda: np.zeros(3))
    direction: np.ndarray = field(default_factory=lambda: np.array(DOWN))
    assumed: bool = False
    source: str = ""
    load_kg: np.ndarray | None = None  # (N,): a mass mounted for some configurations
    load_com_mm: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def n_joints(self) -> int:
        """Return the number of links (one per joint)."""
        return int(np.shape(self.link_mass_kg)[0])


def default_masses(dh: np.ndarray) -> MassModel:
    """Assumed masses when the robot file gives none (:data:`DEFAULT_LINK_KG_PER_M`).

    Link k (frame k) reaches frame k+1's origin, (a_k, −sin α_k·d_{k+1}, cos α_k·d_{k+1})
    in frame k (Craig's T_{k,k+1}); its mass is its length × 10 kg/m, its centre half-way.
    The last link reaches nothing: it gets the mass and centre of no length (0 kg).
    """
    dh = np.asarray(dh, dtype=float)
    n = dh.shape[0]
    reach = np.zeros((n, 3))
    alpha, a, d = dh[1:, 0], dh[1:, 1], dh[1:, 3]
    reach[:-1] = np.stack([a, -np.sin(alpha) * d, np.cos(alpha) * d], axis=1)
    mass = np.linalg.norm(reach, axis=1) / 1000.0 * DEFAULT_LINK_KG_PER_M
    return MassModel(mass, reach / 2.0, assumed=True, source="assumed: 10 kg/m of link")


@lru_cache(maxsize=8)
def wrist_weight(n_joints: int) -> MassModel:
    """Return a weight of 1 N at the wrist centre (frame 4's origin) and no other mass.

    The mass model of the robot file's ``gravity_sag_deg_per_m``: with it, c_2 = c_3 = the
    sag (deg/(N·m)) turns joints 2 and 3 by the sag per metre of lever arm from their axis
    to the wrist centre, in the direction gravity pulls
    (:class:`~wirecal.solver.simulate.Unmodelled`). One per number of joints, shared (the
    twin's sag at every move asks for it): its arrays are read-only.
    """
    mass = np.zeros(n_joints)
    mass[3] = 1.0 / STANDARD_GRAVITY_M_S2  # link 4: the wrist, its centre at frame 4's origin
    com = np.zeros((n_joints, 3))
    for a in (mass, com):
        a.setflags(write=False)
    return MassModel(mass, com, source="the assumed sag: 1 N at the wrist")


def with_load(masses: MassModel, load_kg: np.ndarray, com_mm: np.ndarray) -> MassModel:
    """Return ``masses`` with a mass ``load_kg[i]`` (kg) at the flange for configuration i.

    The calibration payload (the plan's payload step) beside the tool's own
    ``payload_mass_kg``; ``com_mm`` is its centre in the last frame.
    """
    kg = np.asarray(load_kg, dtype=float)
    return replace(masses, load_kg=kg, load_com_mm=np.asarray(com_mm, dtype=float))


def unloaded(masses: MassModel | None) -> MassModel | None:
    """Return ``masses`` without a per-configuration load (as at θ0, where none is mounted)."""
    return masses if masses is None or masses.load_kg is None else replace(masses, load_kg=None)


def cross3(a: tuple, b: tuple) -> tuple[float, float, float]:
    """Return a × b of two 3-tuples: numpy's cross's products and differences, in its order."""
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def cross(
    a: np.ndarray, b: np.ndarray, axis: int = -1, out: np.ndarray | None = None
) -> np.ndarray:
    """Return a × b of stacks of 3-vectors along ``axis`` (−1 or −2): numpy's cross's operations.

    ``a`` and ``b`` broadcast against each other as arrays, their components along
    ``axis``. The same products and differences, in the same order, as ``np.cross`` (the
    same numbers), without its checks and moved axes, which cost more than the arithmetic
    on small stacks. ``out``: where to write it (a C-ordered new array by default).
    """
    a0, a1, a2 = (_component(a, i, axis) for i in range(3))
    b0, b1, b2 = (_component(b, i, axis) for i in range(3))
    first = a1 * b2
    if out is None:
        at = first.ndim + axis + 1  # where the components go in the broadcast shape
        out = np.empty((*first.shape[:at], 3, *first.shape[at:]))
    np.subtract(first, a2 * b1, out=_component(out, 0, axis))
    np.subtract(a2 * b0, a0 * b2, out=_component(out, 1, axis))
    np.subtract(a0 * b1, a1 * b0, out=_component(out, 2, axis))
    return out


def _component(v: np.ndarray, i: int, axis: int) -> np.ndarray:
    """Return component ``i`` of the vectors along ``axis`` (−1 or −2) of ``v``, a view."""
    if axis == -1:
        return v[..., i]
    if axis == -2:
        return v[..., i, :]
    raise ValueError(f"vectors along axis {axis}: only -1 or -2")


def gravity_torques_floats(
    masses: MassModel, x: list[tuple], z: list[tuple], o: list[tuple]
) -> list[float] | None:
    """Return :func:`gravity_torques_nm` of one configuration from its frames' 3-tuples.

    ``x``, ``z``, ``o``: per frame 0…n; the same numbers as the vectorised form (the same
    operations in its order: numpy's einsum adds three products as (0 + 2) + 1), without
    the cost of arrays for a single configuration (the twin's sag at every move). None
    with a payload or a mounted load (its matrix product): use the array form.
    """
    if masses.payload_mass_kg or masses.load_kg is not None:
        return None
    weight = (STANDARD_GRAVITY_M_S2 * np.asarray(masses.direction, dtype=float)).tolist()
    com = np.asarray(masses.link_com_mm, dtype=float).tolist()
    mass = np.asarray(masses.link_mass_kg, dtype=float).tolist()
    n = len(mass)
    S1: tuple[float, ...] = (0.0, 0.0, 0.0)
    S0: tuple[float, ...] = S1
    tau = [0.0] * n
    w0, w1, w2 = weight
    for k in range(n - 1, -1, -1):  # the reverse cumulative sums, from the last link
        xk, zk, ok, (c0, c1, c2) = x[k + 1], z[k + 1], o[k + 1], com[k]
        y0, y1, y2 = cross3(zk, xk)
        r = (  # written out per component: a generator per sum costs more than the sum
            ok[0] + (xk[0] * c0 + zk[0] * c2 + y0 * c1),
            ok[1] + (xk[1] * c0 + zk[1] * c2 + y1 * c1),
            ok[2] + (xk[2] * c0 + zk[2] * c2 + y2 * c1),
        )
        F = (mass[k] * w0, mass[k] * w1, mass[k] * w2)
        moment = cross3(r, F)
        if k == n - 1:
            S1, S0 = moment, F
        else:
            S1 = (S1[0] + moment[0], S1[1] + moment[1], S1[2] + moment[2])
            S0 = (S0[0] + F[0], S0[1] + F[1], S0[2] + F[2])
        a0, a1, a2 = cross3(ok, S0)
        M0, M1, M2 = S1[0] - a0, S1[1] - a1, S1[2] - a2
        tau[k] = (zk[0] * M0 + zk[2] * M2 + zk[1] * M1) / 1000.0
    return tau


def gravity_torques_nm(
    masses: MassModel, x: np.ndarray, z: np.ndarray, o: np.ndarray
) -> np.ndarray:
    """Return the static gravity torque τ_j (N·m) about each joint axis, (N, n).

    ``x``, ``z``, ``o``: the frames' x and z axes and origins, (N, n+1, 3), frame 0 the base.
    Vectorised: the moments of the links beyond each joint are reverse cumulative sums,
    M_j = Σ_{k≥j} r_k × F_k − o_j × Σ_{k≥j} F_k. Over
    :data:`~wirecal.solver.rows.ROW_BLOCK` configurations, a block of them at a time (the
    same numbers).
    """
    kg = masses.load_kg
    if len(x) > ROW_BLOCK and (kg is None or np.shape(kg) == (len(x),)):
        return np.concatenate(
            [
                _torques(masses if kg is None else replace(masses, load_kg=kg[r]), x[r], z[r], o[r])
                for r in row_blocks(len(x))
            ]
        )
    return _torques(masses, x, z, o)


def _torques(masses: MassModel, x: np.ndarray, z: np.ndarray, o: np.ndarray) -> np.ndarray:
    """Return :func:`gravity_torques_nm` of one batch.

    The centres of mass r = o + R·com of frames 1…n are summed as ``einsum`` sums its
    three products, (x·c₀ + z·c₂) + y·c₁ (:func:`gravity_torques_floats`; the same numbers
    on a C-ordered ``link_com_mm``), without the (N, n, 3, 3) rotations.
    """
    x1, z1, o1 = x[:, 1:], z[:, 1:], o[:, 1:]
    y1 = cross(z1, x1)
    c0, c1, c2 = np.asarray(masses.link_com_mm, dtype=float).T[:, :, None]  # each (n, 1)
    r = o1 + ((x1 * c0 + z1 * c2) + y1 * c1)  # (N, n, 3)
    R_last = np.stack([x[:, -1], y1[:, -1], z[:, -1]], axis=-1)  # (N, 3, 3): columns x, y, z
    weight = STANDARD_GRAVITY_M_S2 * np.asarray(masses.direction, dtype=float)
    F = np.asarray(masses.link_mass_kg, dtype=float)[:, None] * weight  # (n, 3)
    moment = cross(r, F)  # (N, n, 3), N·mm
    if masses.payload_mass_kg:
        r_pay = o[:, -1] + R_last @ np.asarray(masses.payload_com_mm, dtype=float)
        F_pay = masses.payload_mass_kg * weight
        moment[:, -1] += cross(r_pay, F_pay)
        F = F.copy()
        F[-1] += F_pay
    if masses.load_kg is not None:
        moment, F = _with_load_moment(masses, moment, F, o[:, -1], R_last, weight)
    S1 = np.cumsum(moment[:, ::-1], axis=1)[:, ::-1]
    S0 = np.cumsum(F[..., ::-1, :], axis=-2)[..., ::-1, :]  # (n, 3), or (N, n, 3) with a load
    M = S1 - cross(o1, S0)
    return np.einsum("nkc,nkc->nk", z1, M) / 1000.0


def _with_load_moment(
    masses: MassModel,
    moment: np.ndarray,
    F: np.ndarray,
    o_last: np.ndarray,
    R_last: np.ndarray,
    weight: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Add the per-configuration load's moment and force to the last link's (N, n, 3)."""
    kg = np.asarray(masses.load_kg, dtype=float)
    if kg.shape != (len(o_last),):
        raise ValueError(
            f"the mounted load is given for {kg.size} configurations; the model is "
            f"evaluated at {len(o_last)}"
        )
    F_load = kg[:, None] * weight  # (N, 3)
    r_load = o_last + R_last @ masses.load_com_mm
    moment, F = moment.copy(), np.array(np.broadcast_to(F, moment.shape))
    moment[:, -1] += cross(r_load, F_load)
    F[:, -1] += F_load
    return moment, F
