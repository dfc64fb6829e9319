"""Robot description files (TOML): read and validate them into a :class:`Robot`.

Format (angles in degrees, lengths in mm)::

    name = "Adept Viper s650"
    [kinematics]
    convention = "craig"                  # modified DH, row i = α_{i-1}, a_{i-1}, θ_i offset, d_i
    dh = [[0, 0, 0, 0], [-90, 75, 0, 0], ...]
    joint_min_deg = [...]; joint_max_deg = [...]; joint_speed_deg_s = [...]
    [tool]
    point_mm = [-60, 0, 50]               # wire attachment point in the last joint's frame
    [encoder]
    mm_per_count = 0.025488; range_mm = 1250; counter_bits = 24
    max_wire_speed_mm_s = 1000; max_wire_accel_mm_s2 = 49000   # optional: the wire's limits
    scale_tolerance_ppm = 500             # the datasheet's scale figure (default 500)
    reference_length_mm = 500.0           # optional: a gauge's certified nest distance,
    reference_uncertainty_mm = 0.002      #   its standard uncertainty (default 0),
    reference_repeats = 3                 #   nest A/B seatings asked for (default 3)
    temperature_coefficient_ppm_per_k = 23  # the drum's expansion (default 23, aluminium)
    [calibration]
    parameters = ["th2", "th3", ...]      # names from wirecal.solver.params
    gravity_sag_deg_per_m = 0.01          # optional: joints 2, 3 sag per m of lever (budget)
    compliances = ["c2", "c3"]            # optional: compliances to identify (needs [gravity])
    repeatability_mm = 0.02               # optional: the arm's pose repeatability (zero_reading)
    rated_payload_kg = 5.0                # optional: the arm's rated payload (data sheet)
    payload_kg = 5.0                      # optional: a mass for plan's payload step (needs
    payload_com_mm = [0, 0, 50]           #   compliances, rated_payload_kg); its centre (flange)
    [controller]                          # optional
    language = "vplus"                    # or "urscript" (Universal Robots)
    software = "5.20"                     # the controller's software version (optional)
    host = "192.168.1.10"; port = 50000   # URScript: where 'wirecal receive' listens
    key = "…"                             # URScript: the run token's secret (16+ characters)
    [gravity]                             # optional: masses and compliances (robot_gravity)
    link_mass_kg = [...]; link_com_mm = [[x, y, z], ...]; compliance_urad_per_nm = [...]
    [geometry]                            # optional
    link_radius_mm = [70, 70, 55, 45, 37] # capsule radius per chain step 1-2 … 5-6 (docs/cell.md)
    [cell]                                # optional (wirecal.solver.cell.model)
    floor_z_mm = -335.0                   # the mounting plane in frame 0 (default 0)
    margin_mm = 10.0                      # gap kept from floor, volumes, the arm itself
    body_min_deg = [...]; body_max_deg = [...]  # optional: limits keeping the arm out of itself
    [[cell.box]]                          # keep-out boxes, axis-aligned in frame 0
    name = "table"; min_mm = [x, y, z]; max_mm = [x, y, z]
    [[cell.half_space]]                   # keep-out half-spaces
    name = "wall"; point_mm = [x, y, z]; normal = [nx, ny, nz]  # normal into the free side
    [cell.encoder_housing]                # optional: a capsule from the wire's exit
    direction = [0, 0, -1]; length_mm = 120; radius_mm = 40


Every problem is reported as ``file: key: problem``, all at once, with the field rules of
:mod:`wirecal.formats.toml_fields`. Beyond types, the file must describe an arm a draw
wire can calibrate (each rule says what to do when it fails):

* plausible sizes: |α|, |θ offset| ≤ 360°; |a|, |d|, tool point, link radii ≤ 10 m; joint
  limits within ±3600° (ten turns); speeds in (0, 10 000] °/s; |mm_per_count| ≤ 10 mm;
  range_mm in (0, 100 m]. Larger values are typing slips, and would only fail later;
* degrees, not radians: twists α and θ offsets whose non-zero values are all within ±π with
  one at ±π/2 or ±π; a joint whose limits both lie within ±2π;
* millimetres, not metres: the arm's links (Σ|a| + Σ|d|) add up to less than 1 % of the
  encoder's range or less than its widest link radius; a range_mm under 10 mm
  (:data:`~wirecal.formats.robot_values.MIN_RANGE_MM`: 1.25 for a 1250 mm wire);
* each joint's range wider than 10° (:data:`MIN_JOINT_RANGE_DEG`): plan design and the
  generated programs keep every point 5° inside each limit;
* a counter wide enough for the wire: 2^(bits−1)·|mm_per_count| must exceed range_mm, or two
  wire lengths a counter turn apart give the same count;
* an encoder interface the controller language reads: "belt" or "device" for V+, "pulse"
  (the URScript pulse decoder, ``pulse_inputs`` two digital inputs 8–11) for URScript.

The readers are split by table: :mod:`.robot_kinematics`, :mod:`.robot_encoder` (with
``[controller]``), :mod:`.robot_cell`; the bounds are in :mod:`.robot_values`, the unit and
size rules in :mod:`.robot_sanity`, the writer in :mod:`.robot_writer`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from wirecal.formats.fileio import read_toml
from wirecal.formats.robot_cell import CELL_KEYS, read_cell
from wirecal.formats.robot_encoder import (
    CONTROLLER_KEYS,
    ENCODER_KEYS,
    read_controller,
    read_encoder,
    read_language_and_interface,
)
from wirecal.formats.robot_gravity import GRAVITY_KEYS, MAX_MASS_KG, read_com, read_gravity
from wirecal.formats.robot_kinematics import (
    KINEMATICS_KEYS,
    dh_radians,
    read_dh,
    read_limits,
)
from wirecal.formats.robot_sanity import check_units
from wirecal.formats.robot_values import (
    MAX_DH_ANGLE_DEG,
    MAX_GRAVITY_SAG_DEG_PER_M,
    MAX_LENGTH_MM,
    MAX_RANGE_MM,
    MAX_REPEATABILITY_MM,
    MAX_SCALE_PPM,
    MAX_SPEED_DEG_S,
    not_metres,
)
from wirecal.formats.robot_writer import robot_file_text
from wirecal.formats.toml_fields import Table, document, duplicates, valid
from wirecal.solver import params as P
from wirecal.solver.gravity import MassModel
from wirecal.solver.robot import (
    DEFAULT_GRAVITY_SAG_DEG_PER_M,
    DEFAULT_LINK_RADIUS_MM,
    Robot,
    UrdfSource,
)

__all__ = [
    "MAX_DH_ANGLE_DEG",
    "MAX_LENGTH_MM",
    "MAX_RANGE_MM",
    "MAX_SCALE_PPM",
    "load_robot",
    "robot_file_text",
    "robot_from_dict",
]
"""The reader, the writer (:mod:`.robot_writer`) and the bounds callers check against
(:mod:`.robot_values`), importable from here as before the split."""

_TOP_KEYS = (
    "name",
    "description",
    "source",
    "kinematics",
    "tool",
    "encoder",
    "calibration",
    "geometry",
    "urdf",
    "controller",
    "cell",
    "gravity",
)
_KEYS = {
    "tool": ("point_mm",),
    "calibration": (
        "parameters",
        "gravity_sag_deg_per_m",
        "compliances",
        "repeatability_mm",
        "rated_payload_kg",
        "payload_kg",
        "payload_com_mm",
    ),
    "geometry": ("link_radius_mm",),
    "urdf": ("source", "base_link", "tip_link", "parallel_tol_deg", "wire_point_mm"),
}
"""The keys of the tables read here; the other tables' are beside their readers."""


def load_robot(path: str | Path) -> Robot:
    """Read and validate a robot file; raise :class:`WirecalError` listing every problem."""
    data = read_toml(path, "robot file")
    return robot_from_dict(data, str(path))


def robot_from_dict(data: dict[str, Any], source: str = "<robot>") -> Robot:
    """Validate a parsed robot description (see module docstring)."""
    doc = document(data, source, "robot file", _TOP_KEYS)
    name = doc.string("name")
    doc.string("description", None)
    doc.string("source", None)
    kin = doc.table("kinematics", KINEMATICS_KEYS)
    dh = read_dh(kin)
    n = None if dh is None else dh.shape[0]
    lo, hi = read_limits(kin, n)
    speed, speed_confirmed = _speeds(kin, n)
    point = _tool_point(doc.table("tool", _KEYS["tool"]))
    controller_table = doc.table("controller", CONTROLLER_KEYS, required=False)
    encoder_table = doc.table("encoder", ENCODER_KEYS)
    language, interface = read_language_and_interface(controller_table, encoder_table)
    controller = read_controller(controller_table, language)
    encoder = read_encoder(encoder_table, interface)
    calibration = doc.table("calibration", _KEYS["calibration"])
    parameters = _parameters(calibration, n)
    radii = _link_radii(doc.table("geometry", _KEYS["geometry"], required=False), n)
    urdf = _urdf(doc.table("urdf", _KEYS["urdf"], required=False), source)
    cell = read_cell(doc.table("cell", CELL_KEYS, required=False), n)
    dh_rad = dh_radians(dh)
    masses, compliance = read_gravity(doc.table("gravity", GRAVITY_KEYS, required=False), dh_rad)
    compliances = _compliances(calibration, n, masses is not None)
    sag = _sag(calibration, bool(compliances))
    repeatability = calibration.number(
        "repeatability_mm", None, above=0, hi=MAX_REPEATABILITY_MM, unit="mm"
    )
    payload = _payload(calibration, bool(compliances), masses)
    check_units(doc, dh, lo, hi, encoder, radii)
    doc.raise_if_any()
    return Robot(
        name=valid(name).strip(),
        dh=valid(dh_rad),
        joint_min_deg=valid(lo),
        joint_max_deg=valid(hi),
        joint_speed_deg_s=valid(speed),
        tool_point=valid(point),
        encoder=valid(encoder),
        parameters=tuple(valid(parameters)),
        source=source,
        link_radius_mm=radii,
        urdf=urdf,
        controller=valid(controller),
        joint_speed_confirmed=speed_confirmed,  # None: not stated
        gravity_sag_deg_per_m=valid(sag),
        cell=valid(cell),
        masses=masses,
        compliance_urad_per_nm=compliance,
        compliances=tuple(compliances),
        repeatability_mm=repeatability,
        **payload,
    )


def _speeds(kin: Table, n: int | None) -> tuple[np.ndarray | None, bool | None]:
    """Read ``joint_speed_deg_s`` (one per joint) and ``joint_speed_confirmed``."""
    speed = kin.vector(
        "joint_speed_deg_s",
        length=n,
        labels="(one per joint)",
        above=0,
        hi=MAX_SPEED_DEG_S,
        unit="deg/s",
    )
    return speed, kin.boolean("joint_speed_confirmed", None)


def _tool_point(tool: Table) -> np.ndarray | None:
    """Read ``[tool] point_mm``, refusing a point in metres."""
    point = tool.vector(
        "point_mm", length=3, labels="(x, y, z)", lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM, unit="mm"
    )
    return not_metres(tool, "point_mm", point, " (e.g. [-60, 0, 50])")


def _link_radii(geometry: Table, n: int | None) -> np.ndarray | None:
    """Read ``[geometry] link_radius_mm``, one per link; the default radius when not given."""
    radii = geometry.vector(
        "link_radius_mm",
        None,
        length=None if n is None else n - 1,
        labels="(one per link)",
        lo=0,
        hi=MAX_LENGTH_MM,
        unit="mm",
    )
    if radii is not None:  # in metres: a problem; the units check reads them as given
        not_metres(geometry, "link_radius_mm", radii)
    if n is not None and radii is None:
        radii = np.full(n - 1, DEFAULT_LINK_RADIUS_MM)
    return radii


def _parameters(cal: Table, n: int | None) -> list[str] | None:
    """Read ``[calibration] parameters``: names of :mod:`wirecal.solver.params`, each once."""
    names = cal.strings("parameters", what="parameter names")
    if names is None:
        return None
    if not names:
        cal.add("parameters", "is empty; name at least one parameter")
    for x in duplicates(names):
        cal.add("parameters", f"{x!r} is listed twice")
    for x in names if n is not None else ():
        try:
            P.parse(x, n)
        except ValueError as exc:
            cal.add("parameters", str(exc))
    return names


def _sag(cal: Table, compliances: bool) -> float | None:
    """Read ``gravity_sag_deg_per_m``: the assumed sag, none when compliances are identified.

    The assumed sag is one instance of the compliance model (a weight at the wrist centre,
    c2 = c3); a file that identifies compliances measures the sag instead of assuming it.
    """
    if compliances and "gravity_sag_deg_per_m" in cal.keys():
        cal.add(
            "gravity_sag_deg_per_m",
            "is the assumed sag that [calibration] compliances measure instead; remove it",
        )
    return cal.number(
        "gravity_sag_deg_per_m",
        0.0 if compliances else DEFAULT_GRAVITY_SAG_DEG_PER_M,
        lo=0,
        hi=MAX_GRAVITY_SAG_DEG_PER_M,
        unit="deg/m",
    )


def _compliances(cal: Table, n: int | None, masses: bool) -> list[str]:
    """Read ``[calibration] compliances``: c1..cn, each once; they need ``[gravity]``."""
    names = cal.strings("compliances", [], what="compliance names (c2, c3, …)") or []
    for x in duplicates(names):
        cal.add("compliances", f"{x!r} is listed twice")
    for x in names:
        if n is not None and not (x.startswith("c") and x[1:].isdigit() and 1 <= int(x[1:]) <= n):
            cal.add("compliances", f"{x!r} is not a compliance; use c1..c{n}")
    if names and not masses:
        cal.add(
            "compliances",
            "needs the arm's masses: add a [gravity] table (without link_mass_kg the masses "
            "are assumed, 10 kg per metre of link)",
        )
    return names


def _payload(cal: Table, compliances: bool, masses: MassModel | None) -> dict:
    """Read the payload step's mass, its centre and the arm's rated payload.

    ``payload_kg`` needs ``compliances`` (the step is for them) and ``rated_payload_kg``;
    with the tool's own mass (``[gravity] payload_mass_kg``) it may not exceed the rating.
    """
    rated = cal.number("rated_payload_kg", None, above=0, hi=MAX_MASS_KG, unit="kg")
    kg = cal.number("payload_kg", None, above=0, hi=MAX_MASS_KG, unit="kg")
    com = read_com(cal, "payload_com_mm")
    if kg is not None and not compliances:
        cal.add(
            "payload_kg", "is the payload step's mass, for [calibration] compliances; list them"
        )
    if kg is not None and rated is None:
        cal.add(
            "payload_kg",
            "needs the arm's rated payload: add rated_payload_kg (the data sheet's), so that "
            "the mass is checked against it",
        )
    tool = masses.payload_mass_kg if masses is not None else 0.0
    if rated is not None and tool > rated:
        cal.add(
            "rated_payload_kg",
            f"is {rated:g} kg, less than the tool's own {tool:g} kg ([gravity] "
            "payload_mass_kg): the arm cannot carry its tool; give both in kg (the tool in "
            "grams?)",
        )
    elif kg is not None and rated is not None and kg + tool > rated:
        cal.add(
            "payload_kg",
            f"{kg:g} kg with the tool's {tool:g} kg ([gravity] payload_mass_kg) exceeds the "
            f"rated payload {rated:g} kg; use a lighter mass",
        )
    return {"rated_payload_kg": rated, "payload_kg": kg, "payload_com_mm": com}


def _urdf(table: Table, source: str) -> UrdfSource | None:
    """Read the optional ``[urdf]`` table.

    The optional ``[urdf]`` table: the URDF a robot file was imported from (``wirecal
    import-urdf``), its base and tip links, and the parallel-axis tolerance used; the
    source path is relative to the robot file.
    """
    if not table.present:
        return None
    path = table.string("source")
    base = table.string("base_link")
    tip = table.string("tip_link")
    tol = table.number("parallel_tol_deg", None, above=0, hi=0.05, unit="deg")
    wire = table.vector(
        "wire_point_mm",
        None,
        length=3,
        labels="(x, y, z)",
        lo=-MAX_LENGTH_MM,
        hi=MAX_LENGTH_MM,
        unit="mm",
    )
    if path is None or base is None or tip is None:
        return None
    here = Path() if source.startswith("<") else Path(source).parent
    point = None if wire is None else (float(wire[0]), float(wire[1]), float(wire[2]))
    return UrdfSource(str(here / path), base, tip, tol, point)
