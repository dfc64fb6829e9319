"""Kinematic corrections in Universal Robots' terms: the patch's companion for a UR.

The standard-DH deltas of a calibrated model, in the layout of the controller's
``calibration.conf``.

The deltas are ``delta_theta``, ``delta_a``, ``delta_d``, ``delta_alpha`` per joint, in
metres and radians, of the calibrated model's standard-DH table
(:mod:`wirecal.solver.standard_dh`) minus the nominal one. With that exact conversion the
wirecal parameters map one to one: ``th<i>`` → delta_theta[i-1], ``d<i>`` → delta_d[i-1],
``a<i>`` → delta_a[i-1], ``al<i>`` → delta_alpha[i-1] (i ≥ 1). ``a0``/``al0`` move the
base frame and the ``tool_*`` components the tool point: neither has a place in these
deltas, so :func:`ur_deltas` refuses them rather than dropping them. The companion
(:func:`calibration_text`) names the tool point's components in a comment as not carried
(the fit of a plan from a pool estimates the wire's attachment beside the geometry: the
installation's TCP holds it, not these deltas); a0/al0 it refuses.

UNCONFIRMED: the names delta_theta/delta_a/delta_d/delta_alpha and their units come from
the ROS driver's documentation, not from a Universal Robots manual; the ``[mounting]``
section name is an assumption. (UR's controller reports its own factory calibration as
full dh_theta/dh_a/dh_d/dh_alpha values, per the ROS driver's ur_calibration docs.) The
file is for reading and for ROS users' URDF tools; do not copy it onto a controller.
The file is read back by :func:`wirecal.formats.patch_companion.read_companion`.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.errors import WirecalError
from wirecal.solver.kinematics import Model, with_errors
from wirecal.solver.robot import Robot
from wirecal.solver.standard_dh import from_modified

SUFFIX = ".ur_calibration.conf"
"""The file beside a patch ``<name>.toml``: ``<name>.ur_calibration.conf``."""

KEYS = ("delta_theta", "delta_a", "delta_d", "delta_alpha")
_COLUMN = {"delta_theta": 0, "delta_d": 1, "delta_a": 2, "delta_alpha": 3}
_SI = {"delta_theta": 1.0, "delta_d": 1e-3, "delta_a": 1e-3, "delta_alpha": 1.0}


def ur_deltas(robot: Robot, offsets: Mapping[str, float]) -> dict[str, np.ndarray]:
    """Standard-DH deltas (m, rad) of ``robot`` with ``offsets`` (name → deg or mm).

    Raises :class:`WirecalError` for a parameter outside UR's deltas (a0, al0, tool point)
    or an unknown name.
    """
    problems = []
    for name in offsets:
        try:
            p = P.parse(name, robot.n_joints)
        except ValueError as exc:
            problems.append(f"{name}: {exc}")
            continue
        if p.kind == "tool" or (p.kind in ("a", "al") and p.row == 0):
            problems.append(
                f"{name}: moves the {'tool point' if p.kind == 'tool' else 'base frame'}, "
                "which UR's calibration deltas cannot hold; set it in the installation "
                "(TCP or base mounting) instead"
            )
    if problems:
        raise WirecalError(problems)
    # The conversion moves entries without arithmetic, so the standard table of the offsets
    # alone is the difference of the calibrated and nominal tables, free of rounding.
    zero = Model(dh=np.zeros_like(robot.dh), tool_point=np.zeros(3))
    es = robot.errors(list(offsets))
    delta = from_modified(
        with_errors(zero, es.names, es.to_internal([offsets[n] for n in es.names]))
    ).table
    return {key: delta[:, _COLUMN[key]] * _SI[key] for key in KEYS}


def _vector(values: np.ndarray) -> str:
    return "[" + ", ".join(repr(float(v)) for v in values) + "]"


def calibration_text(robot: Robot, offsets: Mapping[str, float]) -> str:
    """Return the deltas as text in calibration.conf's layout, with the tables they come from.

    The tool point's components are named in a comment as not carried (module docstring).
    """
    tool = {n: v for n, v in offsets.items() if n.startswith("tool_")}
    offsets = {n: v for n, v in offsets.items() if n not in tool}
    deltas = ur_deltas(robot, offsets)
    nominal = from_modified(robot).table
    calibrated = from_modified(robot.model(offsets)).table
    lines = [
        f"# wirecal: standard-DH deltas of the calibrated {robot.name} (metres, radians).",
        "# UNCONFIRMED layout: key names from the ROS driver docs, not a Universal Robots",
        "# manual. For reading and ROS/URDF tools; do not copy onto a controller.",
    ]
    if tool:
        moved = ", ".join(f"{n} {v:+.4f} mm" for n, v in tool.items())
        lines += [
            "# Not carried: the tool point's offsets (flange frame), which these deltas cannot",
            "# hold; set them in the installation's TCP where the wire's point is the tool's:",
            f"#   {moved}",
        ]
    for title, table in (("Nominal", nominal), ("Calibrated", calibrated)):
        lines.append(
            f"# {title} standard DH per joint: theta_offset [rad], d [m], a [m], alpha [rad]"
        )
        for i, (th, d, a, al) in enumerate(table, start=1):
            cells = (float(th), float(d) * 1e-3, float(a) * 1e-3, float(al))
            lines.append(f"#   joint {i}: " + ", ".join(repr(c) for c in cells))
    lines += ["", "[mounting]"]
    lines += [f"{key} = {_vector(deltas[key])}" for key in KEYS]
    return "\n".join(lines) + "\n"
