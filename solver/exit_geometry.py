"""Where the wire leaves the encoder: an ideal point, an eyelet, or a swivel guide pulley.

The paper's model (eq. 7) lets the wire leave the encoder at one point, the exit A, which
is where the tool point is at θ0, so the reading at θ_i is ‖p_i − p_0‖. A real encoder
guides the wire out through an eyelet or over a guide pulley, and both bend it over a
circle of radius r that touches the encoder's axis a at A:

* **pulley** (``exit = "pulley"``): a guide pulley of radius r swivels about the axis
  through A (cable-robot pulley kinematics), so it always lies in the plane of a and the
  tool point P. The wire comes out along a, wraps the pulley by ψ and leaves it
  tangentially towards P: its length is the arc plus the free span, L = r·ψ + t. wirecal
  models it (:func:`wire_path`), in every use of the wire length.
* **eyelet** (``exit = "eyelet"``): the same bend over the eyelet's rounded edge (radius
  ρ, the torus round the hole seen in the plane of a and P), but the sensor maker allows
  only a small exit angle φ (``max_exit_deg``), so wirecal keeps the point model and the
  planner keeps the wire within the cone. The bend is then unmodelled: the wire is longer
  than ‖p_i − p_0‖ by :func:`edge_wrap_mm`, ≈ ρ(φ − sin φ) far from the exit (0.024 mm at
  ρ = 1 mm and 30°). Simulations add it, so its effect is measured.

Geometry, in the plane of a and P with A at the origin: w = v·a along the axis,
s = ‖v − w·a‖ across it, u the unit vector across it towards P. The circle's centre is
C = r·u. With c² = ‖P − C‖² = (s − r)² + w², the free span is t = √(c² − r²) =
√(‖v‖² − 2·r·s) and the wrap ψ = atan2(t, −r) − atan2(w, s − r) (mod 2π): the tangent
point T = C + r·(−cos ψ·u + sin ψ·a) sees P along the tangent. The gradient of L with
respect to P is the unit direction of the free span, û = (P − T)/t (the swivel moves P
only to second order), which without trigonometry is
û = [(t(s − r) + r·w)·u + (t·w − r(s − r))·a] / c². With r = 0 all of it reduces to the
point model: L = ‖v‖, û = v/‖v‖.

As in the paper, the exit is where the tool point is at θ0 (so no encoder position is
identified): for a pulley, the point where the wire meets it, A = p(θ0), the wire's tip
resting there when the encoder is mounted (paper §2.1); for an eyelet, the start of its
rounded edge, the hole taken as wide as the wire, so the wire bears on the edge as soon as
it leaves the axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Eyelet:
    """The wire leaves through an eyelet: a point exit, within a cone about the axis."""

    axis: tuple[float, float, float]  # unit, base frame: the wire's ideal direction
    max_exit_deg: float  # cone half-angle the sensor maker allows
    edge_radius_mm: float  # the eyelet edge's radius, which the wire wraps (unmodelled)

    kind = "eyelet"


@dataclass(frozen=True)
class Pulley:
    """The wire leaves over a guide pulley swivelling about the axis through the exit."""

    axis: tuple[float, float, float]  # unit, base frame: the swivel axis
    radius_mm: float

    kind = "pulley"


Exit = Eyelet | Pulley
"""The encoder's exit as the robot file declares it; ``None`` is the ideal point exit
(``exit = "point"``, the default)."""


def _plane(v: np.ndarray, axis: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (w, s, u): v's component along the axis, its distance from it, and u."""
    w = v @ axis
    perp = v - w[..., None] * axis
    s = np.linalg.norm(perp, axis=-1)
    # on the axis the bend is nil and u does not matter; any unit vector across the axis
    across = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    across /= np.linalg.norm(across)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where(s[..., None] > 0, perp / s[..., None], across)
    return w, s, u


def bend_coordinates(
    v: np.ndarray, axis: np.ndarray | tuple[float, ...], radius_mm: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Return (w, s, u, t) of tool points v (…, 3) relative to the exit (module docstring).

    w along the axis, s across it, u the unit vector across it towards v, t the free span
    (NaN within the circle, where no wire reaches).
    """
    a = np.asarray(axis, dtype=float)
    v = np.asarray(v, dtype=float)
    w, s, u = _plane(v, a)
    with np.errstate(invalid="ignore"):
        t = np.sqrt(np.einsum("...k,...k->...", v, v) - 2 * radius_mm * s)
    return w, s, u, t


def wrap(
    v: np.ndarray, axis: np.ndarray | tuple[float, ...], radius_mm: float
) -> tuple[np.ndarray, np.ndarray]:
    """Return the wire's length L = r·ψ + t and its gradient û, for tool points v (…, 3).

    ``v`` is the tool point relative to the exit A (mm, base frame); the wire comes out
    along ``axis`` and bends over a circle of ``radius_mm`` touching the axis at A (module
    docstring). A point inside that circle, where no wire can reach, gives NaN.
    """
    a = np.asarray(axis, dtype=float)
    r = float(radius_mm)
    w, s, u, t = bend_coordinates(v, a, r)
    psi = np.mod(np.arctan2(t, -r) - np.arctan2(w, s - r), 2 * np.pi)
    c2 = (s - r) ** 2 + w**2
    with np.errstate(invalid="ignore", divide="ignore"):
        along_u = (t * (s - r) + r * w) / c2
        along_a = (t * w - r * (s - r)) / c2
    direction = along_u[..., None] * u + along_a[..., None] * a
    return r * psi + t, direction


def wire_path(pulley: Pulley | None, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the modelled wire length (…,) and its gradient (…, 3) for tool points v.

    ``v`` is p_i − p_0 (the tool point relative to the exit). The ideal point exit
    (``None``, also used for an eyelet) gives ‖v‖ and v/‖v‖ (paper eq. 7, 12); a pulley,
    arc plus free span (:func:`wrap`).
    """
    if pulley is None:
        d = np.linalg.norm(v, axis=-1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return d, v / d[..., None]
    return wrap(v, pulley.axis, pulley.radius_mm)


def physical_wire_mm(exit_: Exit | None, v: np.ndarray) -> np.ndarray:
    """Return the wire's true length (mm) to tool points v (…, 3) relative to the exit.

    Over the pulley, or over the eyelet's rounded edge (which the model leaves out), or
    straight from an ideal point exit (``None``): what a simulated encoder reads.
    """
    if exit_ is None:
        return np.linalg.norm(v, axis=-1)
    radius = exit_.radius_mm if isinstance(exit_, Pulley) else exit_.edge_radius_mm
    if radius == 0:  # a sharp edge adds nothing: the point exit, computed as one
        return np.linalg.norm(v, axis=-1)
    return wrap(v, exit_.axis, radius)[0]


def exit_angle_deg(v: np.ndarray, axis: np.ndarray | tuple[float, ...]) -> np.ndarray:
    """Return the angle (deg) between the wire from the exit to v (…, 3) and the axis."""
    a = np.asarray(axis, dtype=float)
    v = np.asarray(v, dtype=float)
    cross = np.linalg.norm(np.cross(v, a), axis=-1)
    return np.degrees(np.arctan2(cross, v @ a))


def edge_wrap_mm(v: np.ndarray, eyelet: Eyelet) -> np.ndarray:
    """Return the wire length an eyelet's edge adds to ‖v‖ (mm): the unmodelled exit length.

    Exact (module docstring); far from the exit it tends to ρ(φ − sin φ), φ the exit
    angle: 0.024 mm at ρ = 1 mm and 30°, 0.078 mm at 45°.
    """
    return physical_wire_mm(eyelet, v) - np.linalg.norm(v, axis=-1)


def far_field_edge_wrap_mm(exit_deg: np.ndarray, edge_radius_mm: float) -> np.ndarray:
    """Return ρ(φ − sin φ): :func:`edge_wrap_mm` for a tool point far from the exit."""
    phi = np.radians(exit_deg)
    return edge_radius_mm * (phi - np.sin(phi))


def within_cone(exit_: Exit | None, v: np.ndarray) -> np.ndarray:
    """Return whether the wire to each tool point v (…, 3) leaves an eyelet within its cone.

    Always true for a point exit or a pulley.
    """
    if not isinstance(exit_, Eyelet):
        return np.ones(np.shape(v)[:-1], bool)
    return exit_angle_deg(v, exit_.axis) <= exit_.max_exit_deg


def off_the_wire(exit_: Exit, v: np.ndarray) -> str:
    """Return, in words, where a tool point v (3,) lies that no wire reaches (:func:`wrap`).

    For the error messages of the computations that meet one.
    """
    return (
        f"{np.linalg.norm(v):.3g} mm from the exit, {float(exit_angle_deg(v, exit_.axis)):.0f} "
        f"deg off its axis, inside the circle the wire bends over ({describe(exit_)}), where "
        "no wire reaches"
    )


def describe(exit_: Exit | None) -> str:
    """Return the exit in words, for the outputs of plan and solve."""
    if exit_ is None:
        return "ideal point exit (the paper's model: any direction, no cone, no pulley)"
    axis = ", ".join(f"{x:.3g}" for x in exit_.axis)
    if isinstance(exit_, Pulley):
        return f"swivel guide pulley, radius {exit_.radius_mm:g} mm, axis ({axis}) (modelled)"
    return (
        f"eyelet, axis ({axis}), cone ±{exit_.max_exit_deg:g} deg, edge radius "
        f"{exit_.edge_radius_mm:g} mm (edge wrap unmodelled)"
    )
