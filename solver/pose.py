"""Poses as a robot controller writes them (Z-Y-Z Euler angles).

Poses as a robot controller writes them: x, y, z (mm) and Z-Y-Z Euler angles yaw,
pitch, roll (deg), R = RotZ(yaw)·RotY(pitch)·RotZ(roll) — the convention of Adept's V+
transformations (from third-party sources; unconfirmed against the manual).
"""

from __future__ import annotations

import numpy as np


def matrix(x, y, z, yaw, pitch, roll) -> tuple[np.ndarray, np.ndarray]:
    """Rotation and position of a pose given as x, y, z, yaw, pitch, roll."""
    a, b, c = np.radians([yaw, pitch, roll])
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    R = np.array(
        [
            [ca * cb * cc - sa * sc, -ca * cb * sc - sa * cc, ca * sb],
            [sa * cb * cc + ca * sc, -sa * cb * sc + ca * cc, sa * sb],
            [-sb * cc, sb * sc, cb],
        ]
    )
    return R, np.array([x, y, z], dtype=float)


def values(R: np.ndarray, p: np.ndarray) -> tuple[float, ...]:
    """x, y, z, yaw, pitch, roll of a rotation and position (pitch in [0, 180])."""
    sb = float(np.hypot(R[0, 2], R[1, 2]))
    pitch = np.arctan2(sb, R[2, 2])
    if sb > 1e-12:
        yaw, roll = np.arctan2(R[1, 2], R[0, 2]), np.arctan2(R[2, 1], -R[2, 0])
    else:  # pitch 0 or 180: only yaw ± roll is defined; keep yaw = 0
        yaw, roll = 0.0, np.arctan2(R[1, 0], R[0, 0]) * (1 if R[2, 2] > 0 else -1)
    return (*(float(v) for v in p), *(float(v) for v in np.degrees([yaw, pitch, roll])))
