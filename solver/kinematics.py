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
* c_j        — compliance of joint j (:mod:`~wirecal.solver.gravity`): the joint turns by
  c_j·τ_j(q), so                                          ∂p/∂c_j = τ_j · z_j × (p − o_j)

A model with masses (``Model.masses``) and compliances bends under gravity: its frames are
those of the commanded joints plus δθ_j = c_j·τ_j(q), τ evaluated at the commanded
configuration on the model's own (rigid) frames (:mod:`~wirecal.solver.gravity`, first
order). Every derivative is then taken at the deflected frames; the geometric parameters'
columns leave out their effect on τ (c·∂τ/∂e, relative size c·|∂τ/∂θ| ≈ 10⁻⁴–10⁻³).

Angular derivatives are in mm/rad here; callers convert at the boundary.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace
from functools import cache, lru_cache
from typing import Any, NamedTuple

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.exit_geometry import Pulley
from wirecal.solver.gravity import MassModel, cross, gravity_torques_nm, with_load
from wirecal.solver.rows import ROW_BLOCK, row_blocks


@dataclass(frozen=True)
class Model:
    """A concrete kinematic model: the nominal DH table plus error offsets (radians, mm).

    ``dh`` is (n, 4) for one model, or (N, n, 4) with ``tool_point`` (N, 3) for one model
    per configuration of a batch (Monte Carlo trials evaluated in one call). ``pulley`` is
    the encoder's guide pulley when the wire's path over it is modelled (None: the wire
    leaves from a point, paper eq. 7); see :mod:`~wirecal.solver.exit_geometry`.
    ``masses`` and ``compliance`` (rad/(N·m), (n,) or (N, n)) make the arm bend under
    gravity (module docstring); without masses it is rigid, as without compliance.
    """

    dh: np.ndarray  # (n, 4) or (N, n, 4): α_{i-1}, a_{i-1}, θ offset, d_i
    tool_point: np.ndarray  # (3,) or (N, 3)
    pulley: Pulley | None = None
    masses: MassModel | None = None
    compliance: np.ndarray | None = None  # (n,) or (N, n), rad/(N·m)

    @property
    def n_joints(self) -> int:
        """Return the number of joints."""
        return int(self.dh.shape[-2])

    @property
    def batched(self) -> bool:
        """Return whether the model holds a batch of DH tables."""
        return self.dh.ndim == 3


def table_property(check: Callable[[np.ndarray], bool]) -> Callable[[Model], bool]:
    """Make ``check`` of a single (n, 4) DH table a cached question about a model.

    A batched model answers False. The inverse kinematics asks at every move of the twin
    which closed form a model's table allows; the answer is kept per table (its bytes).
    """

    @lru_cache(maxsize=16)
    def on_table(raw: bytes, n: int) -> bool:
        return check(np.frombuffer(raw).reshape(n, 4))

    def of_model(model: Model) -> bool:
        dh = np.asarray(model.dh, dtype=float)
        return dh.ndim == 2 and on_table(dh.tobytes(), dh.shape[0])

    of_model.__doc__ = check.__doc__
    return of_model


def with_errors(base: Model, names: Sequence[str], values: np.ndarray) -> Model:
    """Return the model with offsets ``values`` (m,) or (T, m), internal units, added to ``base``.

    With a (T, m) array the result holds T models (dh (T, n, 4)). A robot's offsets in
    boundary units (deg, mm) give a model through :meth:`~wirecal.solver.robot.Robot.model`.
    """
    values = np.asarray(values, dtype=float)
    lead = values.shape[:-1]
    n = base.n_joints
    places = _offset_places(tuple(names), n)
    dh, tool = _filled((*lead, n, 4), base.dh), _filled((*lead, 3), base.tool_point)
    targets = {"dh": dh, "tool": tool}
    compliance = base.compliance
    if any(key == "c" for key, _, _ in places):
        compliance = _filled((*lead, n), np.zeros(n) if compliance is None else compliance)
        targets["c"] = compliance
    for key, index, k in places:  # one sum per name, in their order
        targets[key][index] += values[..., k]
    return Model(dh, tool, base.pulley, base.masses, compliance)


def _filled(shape: tuple[int, ...], start: np.ndarray) -> np.ndarray:
    """Return a new array of ``shape`` holding ``start`` (broadcast) in every row.

    Its memory keeps the broadcast's order (a batch's rows innermost), which the sums of
    the products taken from it follow (``einsum``).
    """
    if np.shape(start) == shape:
        return np.array(start, dtype=float)  # its order, as the broadcast's
    return np.array(np.broadcast_to(start, shape), dtype=float)


@cache
def _offset_places(names: tuple[str, ...], n: int) -> tuple[tuple[str, tuple[Any, ...], int], ...]:
    """Where :func:`with_errors` adds each named offset: (array, index in it, column of values).

    The array is "dh" (the index a row and column of the table), "tool" or "c".
    """
    places: list[tuple[str, tuple[Any, ...], int]] = []
    for k, name in enumerate(names):
        p = P.parse(name, n)
        if p.kind in ("tool", "c"):
            places.append((p.kind, (..., p.row), k))
        else:
            places.append(("dh", (..., p.row, P.DH_COLUMN[p.kind]), k))
    return tuple(places)


def loaded(
    model: Model, kg: Sequence[float] | np.ndarray, com_mm: Sequence[float] | np.ndarray
) -> Model:
    """Return ``model`` with ``kg[i]`` (kg) at the flange at configuration i, centre ``com_mm``.

    The mass the operator mounts for a plan's payload step
    (:func:`~wirecal.solver.gravity.with_load`); a model without masses cannot carry it.
    """
    if model.masses is None:
        raise ValueError("a mounted mass needs the arm's masses ([gravity])")
    return replace(
        model,
        masses=with_load(
            model.masses, np.asarray(kg, dtype=float), np.asarray(com_mm, dtype=float)
        ),
    )


def repeat(model: Model, counts: int) -> Model:
    """Each model of a batch repeated ``counts`` times in a row (for T trials × k points)."""
    c = model.compliance
    return Model(
        np.repeat(model.dh, counts, axis=0),
        np.repeat(model.tool_point, counts, axis=0),
        model.pulley,
        model.masses,
        c if c is None or c.ndim == 1 else np.repeat(c, counts, axis=0),
    )


@dataclass(frozen=True)
class Frames:
    """Joint frames along the chain for a batch: frame k = 0 (base) … n (last link)."""

    x: np.ndarray  # (N, n+1, 3) x axes
    z: np.ndarray  # (N, n+1, 3) z axes
    o: np.ndarray  # (N, n+1, 3) origins
    R_last: np.ndarray  # (N, 3, 3) rotation of the last frame
    torque_nm: np.ndarray | None = None  # (N, n) gravity torques of a bent arm's frames


def _rotate(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R_k · v_k for a stack of rotations (N, 3, 3) and one vector (3,) or one per row."""
    if v.ndim == 1:
        return R @ v
    return np.einsum("nij,nj->ni", R, v)


_BASE_AXES = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))


@lru_cache(maxsize=16)
def _table_floats(raw: bytes, n: int) -> tuple[list, list, list, list, np.ndarray]:
    """Return a DH table's cos α, sin α, a, d as floats and its θ offsets (n,), kept per table.

    The twin and the inverse kinematics evaluate one model's chain tens of thousands of
    times; its constant terms are taken once (the same numbers).
    """
    dh = np.frombuffer(raw).reshape(n, 4)
    ca, sa = np.cos(dh[:, 0]), np.sin(dh[:, 0])
    return ca.tolist(), sa.tolist(), dh[:, 1].tolist(), dh[:, 3].tolist(), dh[:, 2].copy()


@lru_cache(maxsize=16)
def _table_factors(raw: bytes, n: int) -> tuple[list, np.ndarray, np.ndarray]:
    """Return a DH table's factors of :func:`_array_terms`, kept per table (its floats)."""
    ca, sa, a, d, _ = _table_floats(raw, n)
    sa_pairs = np.array([[s, -s] for s in sa]).reshape(n, 2, 1, 1)
    ad_pairs = np.array([a, d]).T.reshape(n, 2, 1, 1)
    for kept in (sa_pairs, ad_pairs):
        kept.setflags(write=False)
    return ca, sa_pairs, ad_pairs


def _array_terms(dh: np.ndarray, q: np.ndarray) -> Iterator[tuple]:
    """Per joint the factors of :func:`_recurrence` for a batch ``q`` (N, n).

    Per joint cos α, (sin α, −sin α), (a, d), cos θ and (sin θ, −sin θ), each pair stacked
    (2, 1, 1) for ``dh``'s one table (n, 4), (2, 1, N) for one per configuration
    (N, n, 4); cos θ is (N,), cos α a float or (N,).
    """
    th = np.ascontiguousarray((q + dh[..., 2]).T)  # (n, N): a row per joint
    ct, st = np.cos(th), np.sin(th)
    st_pairs = np.empty((len(th), 2, 1, q.shape[0]))
    st_pairs[:, 0, 0] = st
    np.negative(st, out=st_pairs[:, 1, 0])
    if dh.ndim == 2:
        ca, sa_pairs, ad_pairs = _table_factors(np.asarray(dh, float).tobytes(), dh.shape[0])
        return zip(ca, sa_pairs, ad_pairs, ct, st_pairs, strict=True)
    ca, sa = np.cos(dh[..., 0]).T, np.sin(dh[..., 0]).T  # (n, N)
    sa_pairs = np.stack([sa, -sa], axis=1)[:, :, None]
    ad_pairs = np.stack([dh[..., 1].T, dh[..., 3].T], axis=1)[:, :, None]
    return zip(ca, sa_pairs, ad_pairs, ct, st_pairs, strict=True)


def _one_terms(raw: bytes, n: int, q: np.ndarray) -> Iterator[tuple]:
    """Per joint (cos α, sin α, a, d, cos θ, sin θ), floats: the table ``raw``, joints ``q``."""
    *table, offset = _table_floats(raw, n)
    th = q + offset
    return zip(*table, np.cos(th).tolist(), np.sin(th).tolist(), strict=True)


def _turn(
    c, s_pair: np.ndarray, UV: np.ndarray, VU: np.ndarray, T: np.ndarray, S: np.ndarray
) -> None:
    """Rotate the pair of axes UV = (U, V) in place by the angle of cosine c, sine s.

    (cU + sV, cV − sU), as cV + (−s)U (the same number); ``s_pair`` is (s, −s), VU the
    pair's rows in reverse, T and S scratch of UV's shape.
    """
    np.multiply(c, UV, out=T)
    np.multiply(s_pair, VU, out=S)
    np.add(T, S, out=UV)


def _recurrence_floats(terms: Iterator[tuple]) -> tuple[list[tuple], tuple]:
    """:func:`_recurrence` of one configuration on Python floats, written out.

    The same products and sums in the same order as :func:`_recurrence`'s (the same
    numbers), without arrays.
    """
    (x0, x1, x2), (y0, y1, y2), (z0, z1, z2) = _BASE_AXES
    p0 = p1 = p2 = 0.0
    stored = [((x0, x1, x2), (z0, z1, z2), (p0, p1, p2))]
    for ca, sa, a, d, c, s in terms:
        y0, y1, y2, z0, z1, z2 = (  # RotX(α_{i-1})
            ca * y0 + sa * z0,
            ca * y1 + sa * z1,
            ca * y2 + sa * z2,
            ca * z0 - sa * y0,
            ca * z1 - sa * y1,
            ca * z2 - sa * y2,
        )
        p0, p1, p2 = p0 + a * x0 + d * z0, p1 + a * x1 + d * z1, p2 + a * x2 + d * z2
        x0, x1, x2, y0, y1, y2 = (  # RotZ(θ_i + offset_i)
            c * x0 + s * y0,
            c * x1 + s * y1,
            c * x2 + s * y2,
            c * y0 - s * x0,
            c * y1 - s * x1,
            c * y2 - s * x2,
        )
        stored.append(((x0, x1, x2), (z0, z1, z2), (p0, p1, p2)))
    return stored, ((x0, x1, x2), (y0, y1, y2), (z0, z1, z2))


def bends(model: Model) -> bool:
    """Whether ``model`` bends under gravity: it has masses and a nonzero compliance."""
    return (
        model.masses is not None and model.compliance is not None and bool(np.any(model.compliance))
    )


def frames(model: Model, q: np.ndarray) -> Frames:
    """All frames of the chain for commanded joint angles ``q`` (N, n) in radians.

    A model with masses and compliance: the frames of the arm bent under gravity, with the
    gravity torques at ``q`` (module docstring); otherwise :func:`rigid_frames`.
    """
    if not bends(model):
        return rigid_frames(model, q)
    masses, c = model.masses, model.compliance
    assert masses is not None  # bends(model)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    rigid = rigid_frames(model, q)
    torque = gravity_torques_nm(masses, rigid.x, rigid.z, rigid.o)
    return replace(rigid_frames(model, q + c * torque), torque_nm=torque)


def gravity_torques(model: Model, f: Frames) -> np.ndarray:
    """Return the gravity torques (N·m, (N, n)) at the commanded joints of frames ``f``.

    Bent frames carry them; rigid frames are the commanded ones, so they give them.
    """
    if f.torque_nm is not None:
        return f.torque_nm
    if model.masses is None:
        raise ValueError("compliance parameters need the arm's masses ([gravity])")
    return gravity_torques_nm(model.masses, f.x, f.z, f.o)


def rigid_frames(model: Model, q: np.ndarray) -> Frames:
    """All frames of the rigid chain for joint angles ``q`` (N, n) in radians.

    A batched model (dh (N, n, 4)) gives configuration k its own model k. The rotation
    is carried as its three columns X, Y, Z; per joint, RotX(α) turns (Y, Z) by α, the
    origin moves by a·X + d·Z, and RotZ(θ) turns (X, Y) by θ. Vectors are floats for one
    configuration of one model, (3, N) arrays otherwise (:func:`_recurrence`), so every
    product of a batch runs over contiguous rows; the arrays returned are (N, …, 3) views of one
    (n+1, 3, 3, N) storage, read-only: up to :data:`KEPT_ROWS` configurations, the frames
    of the last :data:`KEPT_FRAMES` tables and joints asked for are kept and given again.
    Over :data:`~wirecal.solver.rows.ROW_BLOCK` configurations, a block of them at a time
    (the same numbers).
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    n = q.shape[1]
    if n != model.n_joints:
        raise ValueError(f"configurations have {n} joints; the model has {model.n_joints}")
    dh = np.asarray(model.dh, dtype=float)
    if len(q) <= KEPT_ROWS:
        return _kept_frames(dh.tobytes(), dh.shape, q.tobytes(), q.shape)
    if len(q) > ROW_BLOCK and (dh.ndim == 2 or len(dh) == len(q)):
        chain, last = np.empty((n + 1, 3, 3, len(q))), np.empty((len(q), 3, 3))
        for rows in row_blocks(len(q)):  # the same numbers (rows.py)
            last[rows] = _chain(dh if dh.ndim == 2 else dh[rows], q[rows], chain[..., rows])[1]
    else:
        chain, last = _chain(dh, q)
    return _frames_of(chain, last)


KEPT_ROWS = 128
"""Frames of at most this many configurations are kept (:func:`rigid_frames`): kept frames of
1,024 made ``wirecal plan`` of the Viper 5 % slower (the memory of 32 large batches kept
instead of reused), of 128 none."""

KEPT_FRAMES = 32
"""How many tables and joints the kept frames are of: the solvers, the planner and the twin
ask for the frames of the same model at the same joints again and again (a solve's steps,
each move's clearance, the run's timing)."""


@lru_cache(maxsize=KEPT_FRAMES)
def _kept_frames(raw_dh: bytes, dh_shape: tuple, raw_q: bytes, q_shape: tuple) -> Frames:
    """:func:`rigid_frames` of a table and joints given by their bytes and shapes."""
    dh, q = np.frombuffer(raw_dh).reshape(dh_shape), np.frombuffer(raw_q).reshape(q_shape)
    return _frames_of(*_chain(dh, q))


def _frames_of(chain: np.ndarray, last: np.ndarray) -> Frames:
    """Return the frames, read-only views of the storage ``chain`` and ``last``."""
    chain.setflags(write=False)
    last.setflags(write=False)
    chain = chain.transpose(3, 0, 1, 2)
    return Frames(x=chain[:, :, 0], z=chain[:, :, 1], o=chain[:, :, 2], R_last=last)


def _chain(
    dh: np.ndarray, q: np.ndarray, out: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Return the frames' storage (n+1, 3, 3, N) and the last rotation (N, 3, 3) of ``q``.

    ``out``: the storage to fill (a batch of more than one configuration), else a new one.
    """
    N, n = q.shape
    if dh.ndim == 2 and N == 1:  # one configuration: Python floats
        stored, axes = _recurrence_floats(_one_terms(np.asarray(dh, float).tobytes(), n, q[0]))
        last = np.array(axes).reshape(3, 3, 1).transpose(2, 1, 0)  # columns X, Y, Z
        return np.array(stored).reshape(n + 1, 3, 3, 1), np.ascontiguousarray(last)
    chain = np.empty((n + 1, 3, 3, N)) if out is None else out
    return chain, _recurrence(_array_terms(dh, q), chain)


def _recurrence(terms: Iterator[tuple], chain: np.ndarray) -> np.ndarray:
    """Fill ``chain`` (:func:`_chain`) from a batch's ``terms``; return the last rotation.

    ``terms``: the joints' factors (:func:`_array_terms`). The frame being built is one
    array W of rows x, z, o, y (each (3, N)), turned and moved in place: each rotation's
    pair of axes, either way round, and the pair (x, z) the origin moves along are views
    of it, and no step allocates; each frame's x, z, o are copied out.
    """
    N = chain.shape[-1]
    W = np.zeros((4, 3, N))
    W[0, 0] = W[1, 2] = W[3, 1] = 1.0  # the base frame: x, z, o = 0, y
    chain[0] = W[:3]
    T, S = np.empty((2, 3, N)), np.empty((2, 3, N))
    XY, YX, YZ, ZY, XZ, P = W[0::3], W[3::-3], W[3:0:-2], W[1::2], W[0:2], W[2]
    for i, (ca, sa_pair, ad_pair, c, s_pair) in enumerate(terms, 1):
        _turn(ca, sa_pair, YZ, ZY, T, S)  # RotX(α_{i-1})
        np.multiply(ad_pair, XZ, out=T)  # TransX(a_{i-1}), then TransZ(d_i) along the new z
        P += T[0]
        P += T[1]
        _turn(c, s_pair, XY, YX, T, S)  # RotZ(θ_i + offset_i)
        chain[i] = W[:3]
    return np.ascontiguousarray(W[[0, 3, 1]].transpose(2, 1, 0))  # columns X, Y, Z


def one_chain(model: Model, q: np.ndarray) -> tuple[list[tuple], tuple] | None:
    """Return one configuration's rigid frames as Python floats, or None where it cannot.

    ``q`` (n,) rad; per frame its (x, z, o) 3-tuples and the last frame's axes (X, Y, Z),
    the very numbers of :func:`frames` without building its arrays (a Newton step of the
    inverse kinematics needs a handful of them). None for a model that bends under
    gravity, one model per configuration or ``q`` not one configuration: use
    :func:`frames`.
    """
    q = np.asarray(q, dtype=float)
    if bends(model) or np.ndim(model.dh) != 2 or q.shape != (model.n_joints,):
        return None
    return _kept_chain(np.asarray(model.dh, float).tobytes(), q.tobytes())


@lru_cache(maxsize=4)
def _kept_chain(raw_dh: bytes, raw_q: bytes) -> tuple[list[tuple], tuple]:
    """:func:`one_chain` of a table and joints given by their bytes; the last few kept.

    The controller's inverse kinematics asks for a configuration's chain again and again
    (its names, then a Newton step from it; the step's result, then its names). The
    callers only read what it returns.
    """
    q = np.frombuffer(raw_q)
    return _recurrence_floats(_one_terms(raw_dh, q.size, q))


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
        frame = par.row + 1 if par.kind in ("th", "d", "c") else par.row
        cols, frames_ = groups.setdefault(par.kind, ([], []))
        cols.append(k)
        frames_.append(frame)
    return {kind: (np.array(c), np.array(f)) for kind, (c, f) in groups.items()}


class _Groups(NamedTuple):
    """A Jacobian's columns gathered by what they take from the frames (:func:`_groups`)."""

    turns: tuple[np.ndarray, np.ndarray, np.ndarray]  # columns; z frames, then x frames
    bent: slice  # which of the turns are compliances' (after the θ offsets)
    bent_joints: np.ndarray  # their joints (0-based)
    moves: tuple[np.ndarray, np.ndarray, np.ndarray]  # columns; z frames, then x frames
    tool: tuple[np.ndarray, np.ndarray]  # columns; rows of the last frame


@cache
def _groups(names: tuple[str, ...], n: int) -> _Groups:
    """Group the columns of :func:`_layout` by what they take from the frames.

    Rotations: θ and c about z, α about x; translations: d along z, a along x; the tool
    point's.
    """
    layout = _layout(names, n)
    none = (np.zeros(0, dtype=int), np.zeros(0, dtype=int))

    def group(
        along_z: tuple[str, ...], along_x: tuple[str, ...]
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        z, x = ([layout.get(k, none) for k in kinds] for kinds in (along_z, along_x))
        cols = np.concatenate([c for c, _ in z + x])
        return cols, np.concatenate([f for _, f in z]), np.concatenate([f for _, f in x])

    turns = group(("th", "c"), ("al",))
    n_th, bent_frames = len(layout.get("th", none)[0]), layout.get("c", none)[1]
    return _Groups(
        turns,
        slice(n_th, n_th + len(bent_frames)),
        bent_frames - 1,
        group(("d",), ("a",)),
        layout.get("tool", none),
    )


def tool_jacobian(
    model: Model, q: np.ndarray, names: Sequence[str], f: Frames | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂e (N, 3, m) for the named parameters (mm/rad, mm/mm).

    ``f``: the frames of ``q`` when the caller has them already (they do not depend on
    the tool point). The columns of a kind of derivative (module docstring) are taken
    together: the rotations about z_i (θ_i; c_i, times τ_i) and x_{i-1} (α_{i-1}) through
    their frames' origins, the translations along z_i (d_i) and x_{i-1} (a_{i-1}), the
    tool point's (columns of the last frame).
    """
    f = frames(model, q) if f is None else f
    p = f.o[:, -1] + _rotate(f.R_last, model.tool_point)
    J = np.empty((*p.shape, len(names)))
    g = _groups(tuple(names), model.n_joints)
    cols, fz, fx = g.turns
    if len(cols):
        axes = _gathered(f, fz, fx)
        lever = np.subtract(p[:, None], f.o[:, np.concatenate([fz, fx])], out=np.empty_like(axes))
        turn = cross(axes, lever, out=np.empty_like(axes))
        if len(g.bent_joints):  # the joint's turn c_j·τ_j: τ_j times the θ_j column
            turn[:, g.bent] *= gravity_torques(model, f)[:, g.bent_joints, None]
        J[:, :, cols] = turn.transpose(0, 2, 1)
    cols, fz, fx = g.moves
    if len(cols):
        J[:, :, cols] = _gathered(f, fz, fx).transpose(0, 2, 1)
    cols, rows = g.tool
    if len(cols):
        J[:, :, cols] = f.R_last[:, :, rows]
    return p, J


def _gathered(f: Frames, z_frames: np.ndarray, x_frames: np.ndarray) -> np.ndarray:
    """Return the z axes of ``z_frames`` then the x axes of ``x_frames``, (N, k, 3).

    Stored as the frames are, the configurations innermost (copies and products over them
    run along contiguous memory).
    """
    axes = np.empty((len(z_frames) + len(x_frames), 3, len(f.z))).transpose(2, 0, 1)
    axes[:, : len(z_frames)] = f.z[:, z_frames]
    axes[:, len(z_frames) :] = f.x[:, x_frames]
    return axes


def tool_gradient(
    model: Model, f: Frames, p: np.ndarray, u: np.ndarray, names: Sequence[str]
) -> np.ndarray:
    """Return uᵀ·∂p/∂e (N, m): the tool point's derivatives along one direction per row.

    The same columns as ``einsum("nc,ncm->nm", u, tool_jacobian(…)[1])`` (module
    docstring), without the (N, 3, m) Jacobian: a rotation's column
    uᵀ(z × (p − o)) = z·(p × u − o × u) shares p × u, and every product runs over the
    rows of one frame at a time (the frames' storage is contiguous along the rows).
    ``f``: the frames of the configurations, ``p`` (N, 3) their tool points, ``u`` (N, 3)
    the directions.
    """
    ut = np.ascontiguousarray(u.T)  # (3, N)
    pu = cross(np.ascontiguousarray(p.T), ut, axis=-2)
    out = np.empty((len(p), len(names)))
    for kind, (cols, fr) in _layout(tuple(names), model.n_joints).items():
        if kind == "tool":  # a column of the last frame
            out[:, cols] = np.einsum("nc,nck->nk", u, f.R_last[:, :, fr])
            continue
        axes = (f.z if kind in ("th", "d", "c") else f.x).transpose(1, 2, 0)[fr]  # (k, 3, N)
        if kind in ("d", "a"):  # translation along the axis
            along = np.einsum("kcn,cn->kn", axes, ut)
        else:  # rotation about the axis through the frame's origin
            o = f.o.transpose(1, 2, 0)[fr]
            lever = pu - cross(o, ut, axis=-2)
            along = np.einsum("kcn,kcn->kn", axes, lever)
        if kind == "c":  # the joint's turn c_j·τ_j: τ_j times the θ_j column
            along *= gravity_torques(model, f)[:, fr - 1].T
        out[:, cols] = along.T
    return out


def joint_jacobian(
    model: Model, q: np.ndarray, f: Frames | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Tool point p (N, 3) and ∂p/∂q (N, 3, n): the positional geometric Jacobian."""
    return tool_jacobian(model, q, [f"th{i + 1}" for i in range(model.n_joints)], f)


def flange_jacobian(model: Model, q: np.ndarray, f: Frames) -> np.ndarray:
    """Geometric Jacobian (6, n) of the flange at one configuration q (rad) from its frames.

    Rows: the flange origin's velocity (mm/rad), then the angular velocity × 1000 (1 rad of
    orientation weighs as 1 m).
    """
    _, Jp = joint_jacobian(Model(model.dh, np.zeros(3)), q[None], f)
    return np.vstack([Jp[0], f.z[0, 1:].T * 1000.0])
