"""The cell: the arm's own body, the floor it stands on and the keep-out volumes around it.

Everything that produces motion (the planner, ``wirecal gen``, ``psi --strict``, the
twins) asks this module whether a configuration collides, vectorised over
configurations. The arm is a chain of capsules built from the DH table (Craig's modified
convention): chain step i contributes the segment along its common normal, o_{i−1} →
o_{i−1} + a_{i−1}·x_{i−1} (fixed in link i−1), and the segment along joint i's axis to
o_i (length d_i, fixed in links i−1 and i alike, since turning about an axis leaves a
segment on it in place); the tool fixture is the segment from the last origin to the
wire's attachment point. An offset wrist (the UR's d4, d5, d6) is thus modelled as the
L-shaped links it is, not as the diagonal between joint origins. Capsule radii are the
``[geometry] link_radius_mm`` of the wire clearance (:mod:`~wirecal.solver.cell.clearance`):
the chain step from frame k to k+1 takes radius k; the base column the first and the
tool fixture the last.

Checks, each a gap (mm) that must stay ≥ 0 after ``margin_mm``:

* **self-collision** between capsules with at least two joints between them
  (non-adjacent links). Pairs one joint apart are skipped: they meet at that joint by
  construction, and the body limits (``body_min_deg``/``body_max_deg``, e.g. the UR
  elbow's ±175°) keep them from folding into each other. Pairs joined by a chain shorter
  than their radii plus the margin are skipped too (a spherical wrist's links all meet at
  its centre): the capsule model cannot tell them apart from the joint housing;
* **floor** (``floor_z_mm``, the mounting plane in frame 0) and **half-spaces**: every
  capsule not fixed to the base (the base column turns in place) stays above them;
* **boxes** (axis-aligned in frame 0): points every ``BOX_STEP_MM`` along each capsule
  keep their radius, the margin and half the step from the box (a conservative test);
* the **encoder's housing** (optional): a capsule from the wire's exit (the tool point
  at θ0) along ``direction``; every capsule but the tool fixture (which sits at the exit
  at θ0 by design) keeps clear of it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from wirecal.solver.cell.clearance import dot, segment_distance
from wirecal.solver.kinematics import Frames, Model, frames

DEFAULT_MARGIN_MM = 10.0
"""The gap kept from the floor, boxes, half-spaces and between link capsules (mm)."""

BOX_STEP_MM = 20.0
"""Spacing of the points along a capsule tested against a box (mm)."""

SURE_GAP_MM = 10.0
"""A gap (mm) beyond every threshold a yes-or-no question about gaps asks (collides: 0,
touches: −margin, the validation's slack: 1 mm): such questions may take the gaps between
two capsules as exact only below it (``exact_below_mm`` of :func:`cell_gaps`)."""

_TINY_MM = 1e-6


@dataclass(frozen=True)
class Box:
    """A keep-out box, axis-aligned in frame 0 (mm)."""

    name: str
    min_mm: tuple[float, float, float]
    max_mm: tuple[float, float, float]


@dataclass(frozen=True)
class HalfSpace:
    """A keep-out half-space: ``normal`` (unit) points from ``point_mm`` into the free side."""

    name: str
    point_mm: tuple[float, float, float]
    normal: tuple[float, float, float]


@dataclass(frozen=True)
class Housing:
    """The encoder's housing: a capsule from the wire's exit along ``direction`` (frame 0)."""

    direction: tuple[float, float, float]
    length_mm: float
    radius_mm: float


@dataclass(frozen=True)
class CellModel:
    """The robot file's ``[cell]``: floor, margin, body limits, boxes, half-spaces, housing.

    ``body_min_deg``/``body_max_deg``: joint limits that keep the arm out of itself
    (None: the joint limits).
    """

    floor_z_mm: float = 0.0
    margin_mm: float = DEFAULT_MARGIN_MM
    body_min_deg: tuple[float, ...] | None = None
    body_max_deg: tuple[float, ...] | None = None
    boxes: tuple[Box, ...] = ()
    half_spaces: tuple[HalfSpace, ...] = ()
    housing: Housing | None = None


@dataclass(frozen=True)
class EndsAt:
    """Where :func:`capsule_ends` finds the capsules' ends among the points it computes.

    The points: the n+1 origins o_k, then o_{i−1} + a_{i−1}·x_{i−1} at the "a" capsules'
    frames i−1 (``a_frames``), then o_i − d_i·z_i at the "d" capsules' frames i
    (``d_frames``), then the tool point; ``index`` (2, S): each capsule's start and end.
    """

    index: np.ndarray
    a_frames: np.ndarray
    d_frames: np.ndarray


@dataclass(frozen=True)
class Capsules:
    """The arm's capsules and the checks between them (see the module docstring).

    Capsule s runs from the origin of frame ``start[s]`` along ``kind[s]`` ("a": the
    common normal a_{i−1}·x_{i−1}, "d": back from o_i by d_i·z_i, "tool": to the tool
    point); ``frames_fixed[s]`` is the (first, last) frame it is fixed in.
    """

    names: tuple[str, ...]
    radius_mm: np.ndarray
    step: np.ndarray  # chain step i (1…n) of each capsule; n+1 for the tool fixture
    kind: tuple[str, ...]
    frames_fixed: np.ndarray  # (S, 2)
    pairs: np.ndarray  # (P, 2) self-collision pairs checked
    skipped: tuple[tuple[str, str, str], ...]  # (name, name, why) of the pairs left out
    moving: np.ndarray  # capsules checked against floor, half-spaces and boxes
    ends_at: EndsAt  # where capsule_ends finds each capsule's ends

    @cached_property
    def checked(self) -> tuple[np.ndarray, np.ndarray]:
        """Return the moving capsules, and those checked against the encoder's housing.

        The housing's: all moving ones but the tool fixture (which sits at the exit at θ0).
        """
        return np.flatnonzero(self.moving), np.flatnonzero(
            self.moving & (np.array(self.kind) != "tool")
        )


def capsules(
    dh: np.ndarray, radii: np.ndarray, tool_point: np.ndarray, margin_mm: float
) -> Capsules:
    """Return the arm's :class:`Capsules` for a DH table (rad, mm) and link radii (mm)."""
    n = len(dh)
    # (name, radius, chain step, kind, first and last frame it is fixed in, length)
    rows: list[tuple[str, float, int, str, tuple[int, int], float]] = []
    for i in range(1, n + 1):
        r = float(radii[max(i - 2, 0)])
        a, d = float(dh[i - 1, 1]), float(dh[i - 1, 3])
        if abs(a) > _TINY_MM:
            rows.append((f"link {i - 1} (a{i - 1})", r, i, "a", (i - 1, i - 1), abs(a)))
        if abs(d) > _TINY_MM:
            rows.append((f"link {i} (d{i})", r, i, "d", (i - 1, i), abs(d)))
    tool = float(np.linalg.norm(tool_point))
    if tool > _TINY_MM:
        rows.append(("tool fixture", float(radii[-1]), n + 1, "tool", (n, n), tool))
    names = tuple(row[0] for row in rows)
    rad = np.array([row[1] for row in rows])
    fixed = np.array([row[4] for row in rows], int).reshape(-1, 2)
    length = np.array([row[5] for row in rows])
    pairs, skipped = _self_pairs(names, rad, fixed, length, margin_mm)
    step = np.array([row[2] for row in rows], int)
    kind = tuple(row[3] for row in rows)
    return Capsules(
        names, rad, step, kind, fixed, pairs, skipped, fixed[:, 0] >= 1, _ends_at(n, step, kind)
    )


def _ends_at(n: int, step: np.ndarray, kind: tuple[str, ...]) -> EndsAt:
    """Return where :func:`capsule_ends` finds each capsule's ends (:class:`EndsAt`)."""
    kinds = np.array(kind)
    a_frames, d_frames = step[kinds == "a"] - 1, step[kinds == "d"]
    a_row = iter(range(n + 1, n + 1 + len(a_frames)))
    d_row = iter(range(n + 1 + len(a_frames), n + 1 + len(a_frames) + len(d_frames)))
    at = {
        "a": lambda i: (i - 1, next(a_row)),  # o_{i−1} → o_{i−1} + a_{i−1}·x_{i−1}
        "d": lambda i: (next(d_row), i),  # o_i − d_i·z_i → o_i
        "tool": lambda i: (n, n + 1 + len(a_frames) + len(d_frames)),  # o_n → the tool point
    }
    ends = [at[k](int(i)) for i, k in zip(step, kind, strict=True)]
    return EndsAt(np.array(ends, int).reshape(-1, 2).T, a_frames, d_frames)


def _self_pairs(
    names: tuple[str, ...],
    rad: np.ndarray,
    fixed: np.ndarray,
    length: np.ndarray,
    margin_mm: float,
) -> tuple[np.ndarray, tuple[tuple[str, str, str], ...]]:
    """Return the self-collision pairs checked, and those skipped with why."""
    pairs: list[tuple[int, int]] = []
    skipped: list[tuple[str, str, str]] = []
    for s in range(len(names)):
        for t in range(s + 1, len(names)):
            joints = fixed[t, 0] - fixed[s, 1]
            chain = float(length[s + 1 : t].sum())
            if joints < 2:
                skipped.append((names[s], names[t], "adjacent: they meet at a joint"))
            elif chain < rad[s] + rad[t] + margin_mm:
                skipped.append(
                    (names[s], names[t], f"joined by {chain:g} mm of links, less than their radii")
                )
            else:
                pairs.append((s, t))
    return np.array(pairs, int).reshape(-1, 2), tuple(skipped)


def capsule_ends(model: Model, caps: Capsules, f: Frames) -> tuple[np.ndarray, np.ndarray]:
    """Return the capsules' ends, each (3, S, N) component-first, from q's frames ``f``.

    Each kind's computed ends at once, then each capsule's taken (:class:`EndsAt`): the
    same numbers as one capsule at a time.
    """
    dh = np.asarray(model.dh)
    dh = dh if dh.ndim == 2 else dh[0]
    at = caps.ends_at
    o = f.o.transpose(2, 1, 0)  # (3, n+1, N)
    i, k = at.a_frames, at.d_frames
    along_a = o[:, i] + dh[i, 1, None] * f.x.transpose(2, 1, 0)[:, i]
    back_d = o[:, k] - dh[k - 1, 3, None] * f.z.transpose(2, 1, 0)[:, k]
    R = f.R_last.transpose(1, 2, 0)  # (3, 3, N)
    t = model.tool_point
    tool = o[:, -1] + R[:, 0] * t[0] + R[:, 1] * t[1] + R[:, 2] * t[2]
    points = np.concatenate([o, along_a, back_d, tool[:, None]], axis=1)
    return points[:, at.index[0]], points[:, at.index[1]]


@dataclass
class Gaps:
    """Every check's gap (mm, after the margin) per configuration, and what each check is.

    A gap of a capsule to a box beyond its sampling, or between two capsules of
    ``exact_below_mm`` or more (:func:`cell_gaps`), may be a lower bound of it.
    """

    gap: np.ndarray  # (K, N)
    cell: CellModel
    caps: Capsules

    @property
    def margin_mm(self) -> float:
        """Return the cell's margin (mm), which every gap is after."""
        return self.cell.margin_mm

    @cached_property
    def labels(self) -> list[str]:
        """Return what each check (row of ``gap``) is, in words (:func:`cell_gaps`'s order)."""
        caps, cell = self.caps, self.cell
        labels = [f"{caps.names[i]} and {caps.names[j]}" for i, j in caps.pairs]
        mv, housed = caps.checked
        for name in ["floor", *(h.name for h in cell.half_spaces)]:
            labels += [f"{caps.names[i]} and the {name}" for i in mv]
        for box in cell.boxes:
            labels += [f"{caps.names[i]} and box {box.name!r}" for i in mv]
        if cell.housing is not None:
            labels += [f"{caps.names[i]} and the encoder's housing" for i in housed]
        return labels

    def smallest(self) -> np.ndarray:
        """Return each configuration's smallest gap (mm): negative where it collides."""
        return np.min(self.gap, axis=0) if len(self.gap) else np.full(self.gap.shape[1], np.inf)

    def cause(self, k: int) -> str:
        """Return configuration k's worst check in words (the colliding pair)."""
        worst = int(np.argmin(self.gap[:, k]))
        apart = self.gap[worst, k] + self.margin_mm
        how = f"{apart:.0f} mm apart" if apart >= 0 else f"{-apart:.0f} mm into each other"
        return f"{self.labels[worst]}: {how}, margin {self.margin_mm:g} mm"


def cell_gaps(
    cell: CellModel,
    caps: Capsules,
    model: Model,
    q_rad: np.ndarray,
    p0: np.ndarray,
    f: Frames | None = None,
    exact_below_mm: float = np.inf,
) -> Gaps:
    """Return the gaps of configurations ``q_rad`` (N, n) to the body and the cell.

    ``p0`` is the wire's exit (the housing's start), (3,) or (N, 3); ``f``: q's frames
    when known. Gaps between two capsules are exact below ``exact_below_mm`` and may be
    lower bounds above it (:func:`_pair_gaps`): a question of whether configurations
    collide gives the same answers with :data:`SURE_GAP_MM` as with all exact, at a
    fraction of the cost.
    """
    f = frames(model, q_rad) if f is None else f
    a, b = capsule_ends(model, caps, f)
    r, m = caps.radius_mm, cell.margin_mm
    rows = []  # in the order of Gaps.labels
    if len(caps.pairs):
        s, t = caps.pairs.T
        rows.append(_pair_gaps(a, b, s, t, r[s] + r[t] + m, exact_below_mm))
    mv = caps.checked[0]
    am, bm = a[:, mv], b[:, mv]
    planes = [((0.0, 0.0, cell.floor_z_mm), (0.0, 0.0, 1.0))]  # the floor, the half-spaces
    planes += [(h.point_mm, h.normal) for h in cell.half_spaces]
    for point, normal in planes:
        nrm, pt = np.asarray(normal)[:, None, None], np.asarray(point)[:, None, None]
        height = np.minimum(dot(am - pt, nrm), dot(bm - pt, nrm))
        rows.append(height - (r[mv] + m)[:, None])
    for box in cell.boxes:
        keep = r[mv] + m + BOX_STEP_MM / 2
        rows.append(_box_gaps(box, am, bm, keep) - keep[:, None])
    if cell.housing is not None:
        rows.append(_housing_gaps(cell.housing, m, caps, a, b, p0))
    gap = np.concatenate(rows) if rows else np.zeros((0, len(q_rad)))
    return Gaps(gap, cell, caps)


def _pair_gaps(
    a: np.ndarray,
    b: np.ndarray,
    s: np.ndarray,
    t: np.ndarray,
    reach_mm: np.ndarray,
    exact_below_mm: float,
) -> np.ndarray:
    """Return the gaps (mm) of capsule pairs (s, t), axes a → b (3, S, N), (P, N).

    A gap is the distance of the two axes less ``reach_mm`` (P,), the radii and the margin.
    With ``exact_below_mm`` finite, the distance of the axes' bounding boxes bounds it from
    below; where that bound leaves a gap under ``exact_below_mm`` the axes' distance is
    computed, elsewhere the bound stands for it (most pairs of most configurations are far
    apart, and a bound costs a third of a distance).
    """
    if np.isinf(exact_below_mm):
        return segment_distance(a[:, s], b[:, s], a[:, t], b[:, t]) - reach_mm[:, None]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    # the boxes' distance a component at a time, in place: dot's sum in its order, on
    # (P, N) arrays instead of (3, P, N) ones (fewer and smaller, kept in the cache)
    gap = np.zeros(s.shape + a.shape[2:])
    for c in range(3):
        apart = lo[c, s] - hi[c, t]
        np.maximum(apart, lo[c, t] - hi[c, s], out=apart)
        gap += np.square(np.maximum(apart, 0.0, out=apart), out=apart)
    gap = np.sqrt(gap, out=gap) - reach_mm[:, None]
    k, n = np.nonzero(gap < exact_below_mm)
    if len(k):
        sk, tk = s[k], t[k]
        d = segment_distance(a[:, sk, n], b[:, sk, n], a[:, tk, n], b[:, tk, n])
        gap[k, n] = d - reach_mm[k]
    return gap


def _to_box(lo: np.ndarray, hi: np.ndarray, p_lo: np.ndarray, p_hi: np.ndarray) -> np.ndarray:
    """Return the distance (mm) from boxes [p_lo, p_hi] (component-first) to box [lo, hi]."""
    shape = (3,) + (1,) * (p_lo.ndim - 1)
    lo, hi = lo.reshape(shape), hi.reshape(shape)
    out = np.maximum(np.maximum(lo - p_hi, p_lo - hi), 0.0)
    return np.sqrt(dot(out, out))


@lru_cache(maxsize=64)
def _fractions(count: int) -> np.ndarray:
    """Return ``np.linspace(0, 1, count)``, kept (read-only): a box asks the same few again."""
    out = np.linspace(0.0, 1.0, count)
    out.flags.writeable = False
    return out


def _box_gaps(box: Box, a: np.ndarray, b: np.ndarray, near_mm: np.ndarray) -> np.ndarray:
    """Return a distance (mm) from each capsule axis a → b, (3, S, N), to ``box``.

    The distance from the box to the segment's own bounding box bounds it from below;
    where that is under ``near_mm`` (S,), the smallest distance of points every
    :data:`BOX_STEP_MM` or closer along the segment is returned instead (the segment's
    own points: a gap does not depend on which other configurations are asked about).
    """
    lo, hi = np.array(box.min_mm, float), np.array(box.max_mm, float)
    best = _to_box(lo, hi, np.minimum(a, b), np.maximum(a, b))
    s, k = np.nonzero(best < near_mm[:, None])
    if not len(s):
        return best
    a, d = a[:, s, k], b[:, s, k] - a[:, s, k]
    count = np.ceil(np.sqrt(dot(d, d)) / BOX_STEP_MM).astype(int) + 1
    near = np.empty(len(s))
    for c in sorted(set(count.tolist())):  # np.unique's counts, without its sort of arrays
        m = count == c
        p = a[:, None, m] + _fractions(c)[:, None] * d[:, None, m]
        near[m] = np.min(_to_box(lo, hi, p, p), axis=0)
    best[s, k] = near
    return best


def _housing_gaps(
    h: Housing, margin_mm: float, caps: Capsules, a: np.ndarray, b: np.ndarray, p0: np.ndarray
) -> np.ndarray:
    """Return the gaps (mm) of the capsules to the encoder's housing at exit ``p0``."""
    idx = caps.checked[1]
    start = np.asarray(p0, float).T.reshape(3, 1, -1)  # (3,) or one exit per configuration
    end = start + h.length_mm * np.asarray(h.direction)[:, None, None]
    d = segment_distance(a[:, idx], b[:, idx], start, end)
    return d - (caps.radius_mm[idx] + h.radius_mm + margin_mm)[:, None]


def body_limits(
    joint_min_deg: np.ndarray, joint_max_deg: np.ndarray, cell: CellModel
) -> tuple[np.ndarray, np.ndarray]:
    """Return the joint limits narrowed by the cell's body limits (deg)."""
    lo = np.asarray(joint_min_deg, float)
    hi = np.asarray(joint_max_deg, float)
    if cell.body_min_deg is not None:
        lo = np.maximum(lo, cell.body_min_deg)
    if cell.body_max_deg is not None:
        hi = np.minimum(hi, cell.body_max_deg)
    return lo, hi
