"""The cable-length model of ``wirecal fit``: the paper's eq. 7 with the fixed end anywhere.

The wire runs from an anchor **a** fixed in the base frame (the encoder's exit, anywhere in
the cell) to the attachment point t in the flange frame; the sensor reads an absolute
length with an offset c_s that changes when the sensor is re-mounted (session s) and,
optionally, a scale error κ of its mm per count:

    L_i = (1 + κ)·‖p(q_i; e) − a‖ + c_{s(i)}

p is the robot model's tool point (:func:`~wirecal.solver.kinematics.tool_jacobian`, with
the attachment as its tool point and the DH error parameters e). The paper's eq. 7 is the
case a = p(θ0), c = 0. Derivatives with u = (p − a)/‖p − a‖ the wire direction:

    ∂L/∂e = (1 + κ)·uᵀ ∂p/∂e,   ∂L/∂a = −(1 + κ)·u,   ∂L/∂κ = ‖p − a‖,   ∂L/∂c_s = 1.

Values are internal units (rad, mm, dimensionless κ) inside, deg/mm/ppm at the boundary.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.kinematics import (
    Model,
    frames,
    tool_gradient,
    tool_position,
    with_errors,
)
from wirecal.solver.rows import row_blocks
from wirecal.solver.scale import PPM

ANCHOR_NAMES = ("anchor_x", "anchor_y", "anchor_z")
SCALE_NAME = "scale"


def session_of(starts: np.ndarray | list[int] | tuple[int, ...], n_rows: int) -> np.ndarray:
    """Return the 0-based session of each of ``n_rows`` rows, sessions starting at ``starts``."""
    return np.searchsorted(np.asarray(starts), np.arange(n_rows), side="right") - 1


@dataclass(frozen=True)
class Layout:
    """The fit's parameter vector: geometry (DH errors, attachment), anchor, scale, offsets."""

    geometry: tuple[str, ...]  # error-parameter names (params.parse), tool_x… the attachment
    n_joints: int
    n_sessions: int
    scale: bool

    @property
    def names(self) -> tuple[str, ...]:
        """Every parameter's name, in vector order."""
        offsets = tuple(f"offset_{s + 1}" for s in range(self.n_sessions))
        return (*self.geometry, *ANCHOR_NAMES, *((SCALE_NAME,) if self.scale else ()), *offsets)

    @property
    def units(self) -> tuple[str, ...]:
        """Each parameter's boundary unit: deg, mm or ppm."""
        geo = P.ErrorSet(self.geometry, self.n_joints).units
        return (
            *geo,
            "mm",
            "mm",
            "mm",
            *(("ppm",) if self.scale else ()),
            *["mm"] * self.n_sessions,
        )

    @property
    def boundary_per_internal(self) -> np.ndarray:
        """Boundary units per internal unit of each parameter (180/π for angles, 1e6 for κ)."""
        per = {**P.BOUNDARY_PER_INTERNAL, "ppm": 1.0 / PPM}
        return np.array([per[u] for u in self.units])

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        """Return (geometry, anchor, κ, offsets) of a parameter vector."""
        g = len(self.geometry)
        k = g + 3 + int(self.scale)
        kappa = float(x[g + 3]) if self.scale else 0.0
        return x[:g], x[g : g + 3], kappa, x[k:]


def model_of(base: Model, layout: Layout, x: np.ndarray) -> Model:
    """Return the robot model at the geometry of ``x`` (attachment as its tool point)."""
    return with_errors(base, layout.geometry, layout.split(x)[0])


def lengths(
    base: Model, layout: Layout, x: np.ndarray, q_rad: np.ndarray, session: np.ndarray
) -> np.ndarray:
    """Return the model's lengths L (N,) in mm, without the Jacobian (module docstring)."""
    _, anchor, kappa, offsets = layout.split(x)
    model = model_of(base, layout, x)
    p = np.concatenate([tool_position(model, q_rad[c]) for c in row_blocks(len(q_rad))])
    return (1 + kappa) * np.linalg.norm(p - anchor, axis=1) + offsets[session]


def _along_wire(
    model: Model, q_rad: np.ndarray, anchor: np.ndarray, names: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return ‖p − a‖ (N,), the wire's direction u (N, 3) and uᵀ·∂p/∂e (N, m)."""
    dist, u, along = _spans(model, q_rad, anchor, names)
    return dist, u, along()


def _spans(
    model: Model, q_rad: np.ndarray, anchor: np.ndarray, names: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray, Callable[[], np.ndarray]]:
    """Return ‖p − a‖ (N,), the wire's direction u (N, 3) and a function giving uᵀ·∂p/∂e.

    A block of rows at a time (:func:`~wirecal.solver.rows.row_blocks`), the derivatives
    along the wire (N, m) from :func:`~wirecal.solver.kinematics.tool_gradient` (no
    (N, 3, m) Jacobian). Rows of one block keep their frames until the derivatives are
    asked for (a solver asks only at the points it accepts); a longer table's are taken
    block by block at once, while each block's frames are in the processor's cache.
    """
    dist, u = np.empty(len(q_rad)), np.empty((len(q_rad), 3))
    along = np.empty((len(q_rad), len(names)))
    blocks = row_blocks(len(q_rad))
    for c in blocks:
        f = frames(model, q_rad[c])
        p = tool_position(model, q_rad[c], f)
        span = p - anchor
        dist[c] = np.linalg.norm(span, axis=1)
        u[c] = span / dist[c, None]
        if len(blocks) > 1:
            along[c] = tool_gradient(model, f, p, u[c], names)
    if len(blocks) != 1:
        return dist, u, lambda: along

    def deferred() -> np.ndarray:
        along[c] = tool_gradient(model, f, p, u[c], names)
        return along

    return dist, u, deferred


def lengths_and_jacobian(
    base: Model, layout: Layout, x: np.ndarray, q_rad: np.ndarray, session: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return the model's lengths L (N,) and ∂L/∂x (N, k), internal units (module docstring)."""
    L, jacobian = lengths_then_jacobian(base, layout, x, q_rad, session)
    return L, jacobian()


def lengths_then_jacobian(
    base: Model, layout: Layout, x: np.ndarray, q_rad: np.ndarray, session: np.ndarray
) -> tuple[np.ndarray, Callable[[], np.ndarray]]:
    """Return :func:`lengths_and_jacobian`'s L and a function giving its ∂L/∂x.

    ∂L/∂x is taken from the frames of L when asked for (a solver asks only at the points
    it accepts), the very numbers of :func:`lengths_and_jacobian`.
    """
    _, anchor, kappa, offsets = layout.split(x)
    dist, u, along = _spans(model_of(base, layout, x), q_rad, anchor, layout.geometry)

    def jacobian() -> np.ndarray:
        J = np.zeros((len(q_rad), len(layout.names)))
        g = len(layout.geometry)
        J[:, :g] = (1 + kappa) * along()
        J[:, g : g + 3] = -(1 + kappa) * u
        if layout.scale:
            J[:, g + 3] = dist
        k = g + 3 + int(layout.scale)
        J[np.arange(len(q_rad)), k + session] = 1.0
        return J

    return (1 + kappa) * dist + offsets[session], jacobian


def geometry_jacobian(J: np.ndarray, g: int) -> np.ndarray:
    """Return ∂L/∂(the geometry's ``g`` parameters) with the other columns' span projected out.

    ``J`` is :func:`lengths_and_jacobian`'s (the geometry's columns first): what the lengths
    tell of the geometry once the anchor, the scale and the offsets are fitted beside it.
    """
    nuisance = J[:, g:]
    return J[:, :g] - nuisance @ np.linalg.lstsq(nuisance, J[:, :g], rcond=None)[0]


def length_joint_gradient(
    base: Model, layout: Layout, x: np.ndarray, q_rad: np.ndarray
) -> np.ndarray:
    """Return ∂L/∂q (N, n) in mm/rad: how a joint's error moves the modelled length."""
    _, anchor, kappa, _ = layout.split(x)
    joints = tuple(f"th{i + 1}" for i in range(base.n_joints))  # ∂p/∂q_j = ∂p/∂θ_j
    return (1 + kappa) * _along_wire(model_of(base, layout, x), q_rad, anchor, joints)[2]


def quantisation_floor(
    gradient_mm_per_rad: np.ndarray,
    joint_resolution_deg: float,
    length_resolution_mm: float,
    joint_cov_rad2: np.ndarray | None = None,
) -> np.ndarray:
    """Return each row's σ of the length from rounding (N,), mm.

    Each joint rounded to its resolution Δq is off by a uniform error of σ Δq/√12, each
    length by ΔL/√12; through the row's ∂L/∂q: σ_i² = Σ_j (∂L/∂q_j·Δq/√12)² + ΔL²/12.
    ``joint_cov_rad2`` (N, n, n) replaces the joints' (Δq/√12)²·I where they were refined.
    """
    g = gradient_mm_per_rad
    if joint_cov_rad2 is None:
        dq = np.radians(joint_resolution_deg) / np.sqrt(12)
        var = np.sum((g * dq) ** 2, axis=1)
    else:
        var = np.einsum("ni,nij,nj->n", g, joint_cov_rad2, g)
    return np.sqrt(var + length_resolution_mm**2 / 12)


def multilaterate(
    p: np.ndarray, length: np.ndarray, session: np.ndarray, n_sessions: int
) -> np.ndarray:
    """Return a starting anchor (3,) and offsets (S,) from tool points and lengths, linearly.

    With L − c_s = ‖p − a‖ squared: ‖p‖² − L² = 2pᵀa − 2c_s·L + (c_s² − ‖a‖²), linear in a,
    c_s and k_s = c_s² − ‖a‖² (one least-squares solve; noise makes it a start, not a fit).
    """
    n = len(p)
    onehot = np.zeros((n, n_sessions))
    onehot[np.arange(n), session] = 1.0
    A = np.hstack([2 * p, -2 * length[:, None] * onehot, onehot])
    b = np.sum(p * p, axis=1) - length**2
    sol = np.linalg.lstsq(A, b, rcond=None)[0]
    return np.concatenate([sol[:3], sol[3 : 3 + n_sessions]])
