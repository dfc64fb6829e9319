"""The robot file's optional ``[gravity]`` table: masses, centres of mass, compliances.

The model is :mod:`wirecal.solver.gravity`. Format (masses kg, lengths mm in each link's
DH frame, compliances µrad/(N·m))::

    [gravity]
    source = "UR's DH parameters page (masses, centres of mass)"   # where the masses come from
    link_mass_kg = [3.761, 8.058, 2.846, 1.37, 1.3, 0.365]   # link k: the body joint k turns
    link_com_mm = [[0, -25.6, 1.9], ...]   # link k's centre of mass in DH frame k (Craig)
    payload_mass_kg = 0.0                  # optional: the tool's mass (default 0)
    payload_com_mm = [0, 0, 0]             # optional: its centre in the last frame
    direction = [0, 0, -1]                 # optional: gravity in frame 0 (default down)
    compliance_urad_per_nm = [0, 5, 5, 5, 0, 0]  # optional: c_j (default 0, a rigid arm)

Without ``link_mass_kg`` (the masses unknown) the links get
:func:`~wirecal.solver.gravity.default_masses` (10 kg per metre of link, centre half-way:
an assumption the file's ``source`` should say). Without the table the arm is rigid and
every output is what it was before compliance existed.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from wirecal.formats.robot_values import MAX_LENGTH_MM, not_metres, unit_vector
from wirecal.formats.toml_fields import Table
from wirecal.solver.gravity import DOWN, MassModel, default_masses

GRAVITY_KEYS = (
    "source",
    "link_mass_kg",
    "link_com_mm",
    "payload_mass_kg",
    "payload_com_mm",
    "direction",
    "compliance_urad_per_nm",
)
"""The keys of ``[gravity]``."""

MAX_MASS_KG = 10_000.0
"""Largest link or payload mass (kg): heavier than the heaviest industrial arm's link."""
MAX_KG_PER_M = 5000.0
"""Heaviest links per metre of DH lengths (kg/m): 5 t a metre is beyond any arm's links (an
estimate: the heaviest industrial arms weigh some 10 t over metres of links); grams read as
kg make a 20 kg arm of 1.3 m 13 t a metre."""
MAX_COMPLIANCE_URAD_PER_NM = 10_000.0
"""Largest compliance (µrad/(N·m)): 0.01 rad per N·m; harmonic drives of light arms are
about 10–100 µrad/(N·m), heavy arms' gearboxes 0.1–10."""


def read_gravity(
    table: Table, dh_rad: np.ndarray | None
) -> tuple[MassModel | None, np.ndarray | None]:
    """Read ``[gravity]``: the mass model and the compliances (None, None when absent).

    ``dh_rad`` is the DH table, its angles in radians (None when it has problems).
    """
    if not table.present:
        return None, None
    n = None if dh_rad is None else dh_rad.shape[0]
    source = table.string("source", "")
    mass, com = _links(table, n)
    if mass is not None and dh_rad is not None and _in_grams(mass, dh_rad):
        table.add(
            "link_mass_kg",
            f"the links weigh {mass.sum():g} kg in all, more than {MAX_KG_PER_M:g} kg per "
            "metre of the DH table's lengths: that looks like grams; give kg",
        )
        mass = None
    payload = table.number("payload_mass_kg", 0.0, lo=0, hi=MAX_MASS_KG, unit="kg")
    pay_com = read_com(table, "payload_com_mm")
    direction: tuple[float, float, float] | None = DOWN
    if "direction" in table.keys():
        direction = unit_vector(table, "direction", "gravity's direction", ", e.g. [0, 0, -1]")
    c = table.vector(
        "compliance_urad_per_nm",
        None,
        length=n,
        labels="(one per joint)",
        lo=0,
        hi=MAX_COMPLIANCE_URAD_PER_NM,
        unit="µrad/(N·m)",
    )
    if dh_rad is None or payload is None or pay_com is None or direction is None:
        return None, c
    if mass is None or com is None or com.shape[0] != n:
        assumed = default_masses(dh_rad)
        return replace(
            assumed,
            source=source or assumed.source,
            payload_mass_kg=payload,
            payload_com_mm=pay_com,
            direction=np.array(direction),
        ), c
    return MassModel(mass, com, payload, pay_com, np.array(direction), False, source or ""), c


def _in_grams(mass_kg: np.ndarray, dh_rad: np.ndarray) -> bool:
    """Whether link masses meant in kg are in grams: over :data:`MAX_KG_PER_M` of links."""
    length_m = float(np.abs(dh_rad[:, [1, 3]]).sum()) / 1000.0
    return float(mass_kg.sum()) > MAX_KG_PER_M * length_m


def read_com(table: Table, key: str) -> np.ndarray | None:
    """Read a mass's centre (mm, default the origin) in the last frame: x, y, z in range.

    None, with a problem, when it is in metres (:func:`~.robot_values.not_metres`).
    """
    com = table.vector(
        key,
        [0.0, 0.0, 0.0],
        length=3,
        labels="(x, y, z)",
        lo=-MAX_LENGTH_MM,
        hi=MAX_LENGTH_MM,
        unit="mm",
    )
    return not_metres(table, key, com)


def _links(table: Table, n: int | None) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Read ``link_mass_kg`` and ``link_com_mm``: both or neither, one per link."""
    mass = table.vector(
        "link_mass_kg", None, length=n, labels="(one per link)", lo=0, hi=MAX_MASS_KG, unit="kg"
    )
    com = table.matrix(
        "link_com_mm",
        None,
        cols=3,
        labels="(x, y, z)",
        lo=-MAX_LENGTH_MM,
        hi=MAX_LENGTH_MM,
        unit="mm",
    )
    if (mass is None) != (com is None):
        table.add(
            "link_com_mm" if com is None else "link_mass_kg",
            "give link_mass_kg and link_com_mm together, or neither (assumed masses)",
        )
    if com is not None and n is not None and com.shape[0] != n:
        table.add("link_com_mm", f"has {com.shape[0]} rows; expected {n} (one per link)")
    if com is not None and not_metres(table, "link_com_mm", com.ravel()) is None:
        com = None
    return mass, com
