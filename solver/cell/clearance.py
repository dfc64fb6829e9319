"""Wire clearance: the wire against the links, modelled as capsules.

Wire clearance: the straight wire from the encoder's exit point to the attachment point
must stay clear of the robot's links, each modelled as a capsule (a segment between
consecutive joint-frame origins, with a radius from the robot file).
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.kinematics import Frames, Model, frames


def dot(u, v) -> np.ndarray:
    """Return u · v for vectors held component-first (3, ...).

    Summed x + y + z in place: the numbers of ``u[0] * v[0] + u[1] * v[1] + u[2] * v[2]``
    with two arrays fewer (the cell's checks and the wire's clearance share it).
    """
    out = u[0] * v[0]
    out += u[1] * v[1]
    out += u[2] * v[2]
    return out


def _unit(x: np.ndarray) -> np.ndarray:
    """Return x clamped to [0, 1] (``np.clip``'s numbers without its per-call overhead)."""
    return np.minimum(np.maximum(x, 0.0), 1.0)


def segment_distance(p1, q1, p2, q2) -> np.ndarray:
    """Return the shortest distance between segments p1–q1 and p2–q2.

    The points are held component-first, (3, ...), and broadcast over the other axes
    (the clamped closest-point construction).
    """
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = dot(d1, d1)
    e = dot(d2, d2)
    f = dot(d2, r)
    c = dot(d1, r)
    b = dot(d1, d2)
    denom = a * e - b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(denom > 1e-12, _unit((b * f - c * e) / denom), 0.0)
        t = np.where(e > 1e-12, (b * s + f) / e, 0.0)
        a_or_1 = np.where(a > 1e-12, a, 1)
        s = np.where(t < 0, _unit(-c / a_or_1), s)
        s = np.where(t > 1, _unit((b - c) / a_or_1), s)
    t = _unit(t)
    gap = (p1 + s * d1) - (p2 + t * d2)
    return np.sqrt(dot(gap, gap))


def wire_trim_mm(robot) -> float:
    """Return the wire's end left out of the clearance check (mm).

    The wire's end at the attachment point left out of the clearance check: the fixture
    sits there (tool point offset, last link radius and 15 mm).
    """
    return float(np.linalg.norm(robot.tool_point)) + float(robot.link_radius_mm[-1]) + 15.0


def wire_clearance(
    model: Model,
    q: np.ndarray,
    encoder: np.ndarray,
    radii: np.ndarray,
    trim_mm: float,
    f: Frames | None = None,
) -> np.ndarray:
    """Return the smallest gap (mm) between the wire and the link capsules.

    The smallest gap (mm) between the wire and the link capsules for configurations q
    (N, n) in radians; the wire's last ``trim_mm`` at the attachment point are not checked
    (the fixture is there). ``f``: q's frames, when the caller has them.
    """
    f = frames(model, q) if f is None else f
    o = f.o.transpose(1, 2, 0)  # (n+1, 3, N): component-first, contiguous per row
    R = f.R_last.transpose(1, 2, 0)  # (3, 3, N)
    t = model.tool_point
    p = o[-1] + R[:, 0] * t[0] + R[:, 1] * t[1] + R[:, 2] * t[2]
    enc = np.asarray(encoder, dtype=float)[:, None]
    length = np.sqrt(dot(p - enc, p - enc))
    keep = _unit(1 - trim_mm / np.maximum(length, 1e-9))
    wire_end = enc + keep * (p - enc)
    starts = o[1:-1].transpose(1, 0, 2)  # (3, caps, N); capsule k: frame k origin → k+1
    ends = o[2:].transpose(1, 0, 2)
    n_caps = starts.shape[1]
    dist = segment_distance(enc[:, :, None], wire_end[:, None], starts, ends)
    return np.min(dist - np.asarray(radii)[:n_caps, None], axis=0)
