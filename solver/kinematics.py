"""Forward kinematics in Craig's modified DH convention, with analytic derivatives.

T_{i-1,i} = RotX(α_{i-1}) · TransX(a_{i-1}) · RotZ(θ_i + offset_i) · TransZ(d_i)
(DESIGN.md; paper Table 1). Everything is vectorised over a batch of N configurations:
joint angles ``q`` have shape (N, n) in radians; there is no Python loop per point.

Derivatives of the tool point p with respect to the error parameters (paper §2.2, Φ):

* θ_i offset — rotation about z_i through o_i:           ∂p/∂θ_i = z_i × (p − o_i)
* d_i        — translation along z_i:                     ∂p/∂d_i = z_i
* a_{i-1}    — translation along x_{i-1}:                 ∂p/∂a_{i-1} = x_{i-1}
* α_{i-1}    — rotation about x_{i-1} through o_{i-1}:    ∂p/∂α_{i-1} = x_{i-1} × (p − o_{i-1})
* tool point — ∂p/∂t = R_n (columns of the last frame)

Angular derivatives are in mm/rad here; callers convert at the boundary.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.exit_geometry import Pulley


@dataclass(frozen=True)
class Model:
    """A concrete kinematic model: the nominal DH table plus error offsets (radians, mm).

    ``dh`` is (n, 4) for one model, or (N, n, 4) with ``tool_point`` (N, 3) for one model
    per configuration of a batch (Monte Carlo trials evaluated in one call). ``pulley`` is
    the encoder's guide pulley when the wire's path over it is modelled (None: the wire
    leaves from a point, paper eq. 7); see :mod:`~wirecal.solver.exit_geometry`.
    """

    dh: np.ndarray  # (n, 4) or (N, n, 4): α_{i-1}, a_{i-1}, θ offset, d_i
    tool_point: np.ndarray  # (3,) or (N, 3)
    pulley: Pulley | None = None

    @property
    def n_joints(self) -> int:
        """Return the number of joints."""
        return int(self.dh.shape[-2])

    @property
    def batched(self) -> bool:
        """Return whether the model holds a batch of DH tables."""
        return self.dh.ndim == 3


def with_errors(base: Model, names: Sequence[str], values: np.ndarray) -> Model:
    """Return the model with offsets ``values`` (m,) or (T, m), internal units, added to ``base``.

    With a (T, m) array the result holds T models (dh (T, n, 4)). A robot's offsets in
    boundary units (deg, mm) give a model through :meth:`~wirecal.solver.robot.Robot.model`.
    """
    values = np.asarray(values, dtype=float)
    lead = values.shape[:-1]
    dh = np.array(np.broadcast_to(base.dh, lead + np.shape(base.dh)[-2:]), dtype=float)
    tool = np.array(np.broadcast_to(base.tool_point, (*lead, 3)), dtype=float)
    for k, name in enumerate(names):
        p = P.parse(name, dh.shape[-2])
        if p.kind == "tool":
            tool[..., p.row] += values[..., k]
        else:
            dh[..., p.row, P.DH_COLUMN[p.kind]] += values[..., k]
    return Model(dh=dh, tool_point=tool, pulley=base.pulley)


def repeat(model: Model, counts: int) -> Model:
    """Each model of a batch repeated ``counts`` times in a row (for T trials × k points)."""
    return Model(
        np.repeat(model.dh, counts, axis=0),
        np.repeat(model.tool_point, counts, axis=0),
        model.pulley,
    )


@dataclass(frozen=True)
class Frames:
    """Joint frames along the chain for a batch: frame k = 0 (base) … n (last link)."""

    x: np.ndarray  # (N, n+1, 3) x axes
    z: np.ndarray  # (N, n+1, 3) z axes
    o: np.ndarray  # (N, n+1, 3) origins
    R_last: np.ndarray  # (N, 3, 3) rotation of the last frame


def _rotate(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R_k · v_k for a stack of rotations (N, 3, 3) and one vector (3,) or one per row."""
    if v.ndim == 1:
        return R @ v
    return np.einsum("nij,nj->ni", R, v)


def frames(model: Model, q: np.ndarray) -> Frames:
    """All frames of the chain for joint angles ``q`` (N, n) in radians.

    A batched model (dh (N, n, 4)) gives configuration k its own model k. The rotation
    is carried as its three columns X, Y, Z; per joint, RotX(α) gives
    Y' = cα·Y + sα·Z, Z' = −sα·Y + cα·Z, the origin moves by a·X + d·Z', and RotZ(θ)
    gives X'' = cθ·X + sθ·Y', Y'' = −sθ·X + cθ·Y'. The vectors are held component-major
    (3, N), so every product runs over contiguous memory; the arrays returned are
    (N, …, 3) views of that storage.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    N, n = q.shape
    if n != model.n_joints:
        raise ValueError(f"configurations have {n} joints; the model has {model.n_joints}")
    dh = model.dh
    batched = dh.ndim == 3
    th = (q + dh[..., 2]).T
    ct, st = np.cos(th), np.sin(th)
    ca_all, sa_all = np.cos(dh[..., 0]), np.sin(dh[..., 0])
    x = np.empty((n + 1, 3, N))
    z = np.empty((n + 1, 3, N))
    o = np.empty((n + 1, 3, N))
    basis = np.zeros((3, 3, N))
    basis[0, 0] = basis[1, 1] = basis[2, 2] = 1.0
    X, Y, Z = basis[:, 0], basis[:, 1], basis[:, 2]
    pos = np.zeros((3, N))
    x[0], z[0], o[0] = X, Z, pos
    for i in range(n):
        if batched:
            ca, sa = ca_all[:, i], sa_all[:, i]
            a, d = dh[:, i, 1], dh[:, i, 3]
        else:
            ca, sa, a, d = ca_all[i], sa_all[i], dh[i, 1], dh[i, 3]
        Y, Z = ca * Y + sa * Z, ca * Z - sa * Y
        pos = pos + a * X + d * Z
        c, s = ct[i], st[i]
        X, Y = c * X + s * Y, c * Y - s * X
        x[i + 1], z[i + 1], o[i + 1] = X, Z, pos
    return Frames(
        x=x.transpose(2, 0, 1),
        z=z.transpose(2, 0, 1),
        o=o.transpose(2, 0, 1),
        R_last=np.ascontiguousarray(np.stack([X, Y, Z], axis=1).transpose(2, 0, 1)),
    )


def tool_position(model: Model, q: np.ndarray, f: Frames | None = None) -> np.ndarray:
    """Tool point (wire attachment) in the base frame, shape (N, 3); ``f``: q's frames."""
    f = frames(model, q) if f is None else f
    return f.o[:, -1] + _rotate(f.R_last, model.tool_point)


@cache
def _layout(names: tuple[str, ...], n: int) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Column indices and frame numbers of each kind of derivative, for gathering."""
    groups: dict[str, tuple[list[int], list[int]]] = {}
    for k, name in enumerate(names):
        par = P.parse(name, n)
        frame = par.row + 1 if par.kind in ("th", "d") else par.row
        cols, frames_ = groups.setdefault(par.kind, ([], []))
        cols.append(k)
        frames_.append(frame)
    return {kind: (np.array(c), np.array(f)) for kind, (c, f) in groups.items()}


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Return a × b over the last axis (faster than np.cross for stacks of 3-vectors)."""
    return np.stack(
        [
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ],
        axis=-1,
    )


def tool_jacobian(
    model: Model, q: np.ndarray, names: Sequence[str], f: Frames | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂e (N, 3, m) for the named parameters (mm/rad, mm/mm).

    ``f``: the frames of ``q`` when the caller has them already (they do not depend on
    the tool point).
    """
    f = frames(model, q) if f is None else f
    p = f.o[:, -1] + _rotate(f.R_last, model.tool_point)
    J = np.empty((*p.shape, len(names)))
    for kind, (cols, fr) in _layout(tuple(names), model.n_joints).items():
        if kind == "th":  # rotation about z_i through o_i
            J[:, :, cols] = _cross(f.z[:, fr], p[:, None] - f.o[:, fr]).transpose(0, 2, 1)
        elif kind == "al":  # rotation about x_{i-1} through o_{i-1}
            J[:, :, cols] = _cross(f.x[:, fr], p[:, None] - f.o[:, fr]).transpose(0, 2, 1)
        elif kind == "d":  # translation along z_i
            J[:, :, cols] = f.z[:, fr].transpose(0, 2, 1)
        elif kind == "a":  # translation along x_{i-1}
            J[:, :, cols] = f.x[:, fr].transpose(0, 2, 1)
        else:  # tool point component: a column of the last frame
            J[:, :, cols] = f.R_last[:, :, fr]
    return p, J


def joint_jacobian(
    model: Model, q: np.ndarray, f: Frames | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂q (N, 3, n): the positional geometric Jacobian."""
    return tool_jacobian(model, q, [f"th{i + 1}" for i in range(model.n_joints)], f)
