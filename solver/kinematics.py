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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from . import params as P
from .robot import Robot


@dataclass(frozen=True)
class Model:
    """A concrete kinematic model: the nominal DH table plus error offsets (radians, mm)."""

    dh: np.ndarray          # (n, 4): α_{i-1}, a_{i-1}, θ offset, d_i
    tool_point: np.ndarray  # (3,)

    @property
    def n_joints(self) -> int:
        return int(self.dh.shape[0])


_COL = {"al": 0, "a": 1, "th": 2, "d": 3}


def perturbed(robot: Robot | Model, errors: Mapping[str, float] | None = None,
              *, units: str = "deg") -> Model:
    """The model with error offsets added to the nominal parameters.

    ``errors`` maps parameter names to offsets in boundary units (deg, mm) when
    ``units == "deg"``, or in internal units (rad, mm) when ``units == "rad"``.
    """
    dh = np.array(robot.dh, dtype=float)
    tool = np.array(robot.tool_point, dtype=float)
    for name, value in (errors or {}).items():
        p = P.parse(name, dh.shape[0])
        v = float(value)
        if p.angular and units == "deg":
            v = np.radians(v)
        if p.kind == "tool":
            tool[p.row] += v
        else:
            dh[p.row, _COL[p.kind]] += v
    return Model(dh=dh, tool_point=tool)


def as_model(robot: Robot | Model) -> Model:
    return robot if isinstance(robot, Model) else perturbed(robot)


@dataclass(frozen=True)
class Frames:
    """Joint frames along the chain for a batch: frame k = 0 (base) … n (last link)."""

    x: np.ndarray  # (N, n+1, 3) x axes
    z: np.ndarray  # (N, n+1, 3) z axes
    o: np.ndarray  # (N, n+1, 3) origins
    R_last: np.ndarray  # (N, 3, 3) rotation of the last frame


def frames(model: Model, q: np.ndarray) -> Frames:
    """All frames of the chain for joint angles ``q`` (N, n) in radians."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    N, n = q.shape
    if n != model.n_joints:
        raise ValueError(f"configurations have {n} joints; the model has {model.n_joints}")
    alpha, a, off, d = model.dh.T
    x = np.empty((N, n + 1, 3))
    z = np.empty((N, n + 1, 3))
    o = np.empty((N, n + 1, 3))
    R = np.broadcast_to(np.eye(3), (N, 3, 3)).copy()
    pos = np.zeros((N, 3))
    x[:, 0], z[:, 0], o[:, 0] = R[:, :, 0], R[:, :, 2], pos
    th = q + off
    ct, st = np.cos(th), np.sin(th)
    for i in range(n):
        ca, sa = np.cos(alpha[i]), np.sin(alpha[i])
        # local rotation RotX(α)·RotZ(θ) and translation (a, −sα·d, cα·d)
        c, s = ct[:, i], st[:, i]
        L = np.empty((N, 3, 3))
        L[:, 0, 0], L[:, 0, 1], L[:, 0, 2] = c, -s, 0.0
        L[:, 1, 0], L[:, 1, 1], L[:, 1, 2] = ca * s, ca * c, -sa
        L[:, 2, 0], L[:, 2, 1], L[:, 2, 2] = sa * s, sa * c, ca
        t_local = np.array([a[i], -sa * d[i], ca * d[i]])
        pos = pos + R @ t_local
        R = R @ L
        x[:, i + 1], z[:, i + 1], o[:, i + 1] = R[:, :, 0], R[:, :, 2], pos
    return Frames(x=x, z=z, o=o, R_last=R)


def tool_position(model: Model, q: np.ndarray) -> np.ndarray:
    """Tool point (wire attachment) in the base frame, shape (N, 3)."""
    f = frames(model, q)
    return f.o[:, -1] + f.R_last @ model.tool_point


def tool_jacobian(model: Model, q: np.ndarray,
                  names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂e (N, 3, m) for the named parameters (mm/rad, mm/mm)."""
    f = frames(model, q)
    p = f.o[:, -1] + f.R_last @ model.tool_point
    n = model.n_joints
    J = np.empty((*p.shape, len(names)))
    for k, name in enumerate(names):
        par = P.parse(name, n)
        i = par.row
        if par.kind == "th":
            J[:, :, k] = np.cross(f.z[:, i + 1], p - f.o[:, i + 1])
        elif par.kind == "d":
            J[:, :, k] = f.z[:, i + 1]
        elif par.kind == "a":
            J[:, :, k] = f.x[:, i]
        elif par.kind == "al":
            J[:, :, k] = np.cross(f.x[:, i], p - f.o[:, i])
        else:  # tool point component
            J[:, :, k] = f.R_last[:, :, i]
    return p, J


def joint_jacobian(model: Model, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂q (N, 3, n): the positional geometric Jacobian."""
    return tool_jacobian(model, q, [f"th{i + 1}" for i in range(model.n_joints)])
