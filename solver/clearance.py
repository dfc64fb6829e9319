"""Wire clearance: the wire against the links, modelled as capsules.

Wire clearance: the straight wire from the encoder's exit point to the attachment point
must stay clear of the robot's links, each modelled as a capsule (a segment between
consecutive joint-frame origins, with a radius from the robot file).
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.kinematics import Model, frames


def segment_distance(p1, q1, p2, q2) -> np.ndarray:
    """Return the shortest distance between segments p1–q1 and p2–q2.

    Broadcast over leading axes (the clamped closest-point construction).
    """
    d1, d2, r = q1 - p1, q2 - p2, p1 - p2
    a = np.einsum("...i,...i", d1, d1)
    e = np.einsum("...i,...i", d2, d2)
    f = np.einsum("...i,...i", d2, r)
    c = np.einsum("...i,...i", d1, r)
    b = np.einsum("...i,...i", d1, d2)
    denom = a * e - b * b
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.where(denom > 1e-12, np.clip((b * f - c * e) / denom, 0, 1), 0.0)
        t = np.where(e > 1e-12, (b * s + f) / e, 0.0)
        s = np.where(t < 0, np.clip(-c / np.where(a > 1e-12, a, 1), 0, 1), s)
        s = np.where(t > 1, np.clip((b - c) / np.where(a > 1e-12, a, 1), 0, 1), s)
    t = np.clip(t, 0, 1)
    gap = (p1 + s[..., None] * d1) - (p2 + t[..., None] * d2)
    return np.linalg.norm(gap, axis=-1)


def wire_trim_mm(robot) -> float:
    """Return the wire's end left out of the clearance check (mm).

    The wire's end at the attachment point left out of the clearance check: the fixture
    sits there (tool point offset, last link radius and 15 mm).
    """
    return float(np.linalg.norm(robot.tool_point)) + float(robot.link_radius_mm[-1]) + 15.0


def wire_clearance(
    model: Model, q: np.ndarray, encoder: np.ndarray, radii: np.ndarray, trim_mm: float
) -> np.ndarray:
    """Return the smallest gap (mm) between the wire and the link capsules.

    The smallest gap (mm) between the wire and the link capsules for configurations q
    (N, n) in radians; the wire's last ``trim_mm`` at the attachment point are not checked
    (the fixture is there).
    """
    f = frames(model, q)
    p = f.o[:, -1] + np.einsum("nij,j->ni", f.R_last, model.tool_point)
    length = np.linalg.norm(p - encoder, axis=1, keepdims=True)
    keep = np.clip(1 - trim_mm / np.maximum(length, 1e-9), 0, 1)
    wire_end = encoder + keep * (p - encoder)
    starts = f.o[:, 1:-1]  # capsule k: frame k origin → frame k+1
    ends = f.o[:, 2:]
    n_caps = starts.shape[1]
    enc = np.broadcast_to(encoder, (len(q), n_caps, 3))
    dist = segment_distance(enc, np.repeat(wire_end[:, None], n_caps, axis=1), starts, ends)
    return np.min(dist - radii[:n_caps], axis=1)
