"""Kinematic corrections in Universal Robots' terms.

Kinematic corrections in Universal Robots' terms: the standard-DH deltas of a
calibrated model, in the layout of the controller's ``calibration.conf``.

The deltas are ``delta_theta``, ``delta_a``, ``delta_d``, ``delta_alpha`` per joint, in
metres and radians, of the calibrated model's standard-DH table
(:mod:`wirecal.solver.standard_dh`) minus the nominal one. With that exact conversion the
wirecal parameters map one to one: ``th<i>`` → delta_theta[i-1], ``d<i>`` → delta_d[i-1],
``a<i>`` → delta_a[i-1], ``al<i>`` → delta_alpha[i-1] (i ≥ 1). ``a0``/``al0`` move the
base frame and the ``tool_*`` components the tool point: neither has a place in these
deltas, so they are refused rather than dropped.

UNCONFIRMED: the names delta_theta/delta_a/delta_d/delta_alpha and their units come from
the ROS driver's documentation, not from a Universal Robots manual; the ``[mounting]``
section name is an assumption. (UR's controller reports its own factory calibration as
full dh_theta/dh_a/dh_d/dh_alpha values, per the ROS driver's ur_calibration docs.) The
file is for reading and for ROS users' URDF tools; do not copy it onto a controller.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import Outputs, read_toml
from wirecal.solver.formats.toml_fields import document
from wirecal.solver.kinematics import Model, with_errors
from wirecal.solver.robot import Robot
from wirecal.solver.standard_dh import from_modified

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
    """Return the deltas as text in calibration.conf's layout, with the tables they come from."""
    deltas = ur_deltas(robot, offsets)
    nominal = from_modified(robot).table
    calibrated = from_modified(robot.model(offsets)).table
    lines = [
        f"# wirecal: standard-DH deltas of the calibrated {robot.name} (metres, radians).",
        "# UNCONFIRMED layout: key names from the ROS driver docs, not a Universal Robots",
        "# manual. For reading and ROS/URDF tools; do not copy onto a controller.",
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


def ur_calibration_path(path: str | Path) -> Path:
    """Where the deltas of the patch ``path`` go: ``<name>.ur_calibration.conf`` beside it."""
    path = Path(path)
    return path.with_name(path.stem + ".ur_calibration.conf")


def read_ur_calibration(path: str | Path, n_joints: int = 6) -> dict[str, np.ndarray]:
    """Read the deltas back (m, rad): the ``[mounting]`` table of :func:`calibration_text`.

    Each key a list of ``n_joints`` finite numbers; any other key or table is refused.
    """
    doc = document(
        read_toml(path, "UR calibration file"), str(path), "UR calibration file", ("mounting",)
    )
    table = doc.table("mounting", KEYS)
    values = {key: table.vector(key, length=n_joints, labels="(one per joint)") for key in KEYS}
    doc.raise_if_any()
    return {key: np.asarray(v) for key, v in values.items()}


def put_ur_calibration(
    out: Outputs, path: str | Path, robot: Robot, offsets: Mapping[str, float]
) -> None:
    """Queue the calibration.conf-style file on an :class:`Outputs` set."""
    out.put(path, calibration_text(robot, offsets))
