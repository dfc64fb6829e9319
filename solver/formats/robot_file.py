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
    [controller]                          # optional
    language = "vplus"                    # or "urscript" (Universal Robots)
    software = "5.20"                     # the controller's software version (optional)
    host = "192.168.1.10"; port = 50000   # URScript: where 'wirecal receive' listens
    key = "…"                             # URScript: the run token's secret (16+ characters)
    [geometry]                            # optional
    link_radius_mm = [70, 55, 45, 40, 35] # capsule radius of each link (wire clearance)
    [cell]                                # optional (wirecal.solver.cell)
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
:mod:`wirecal.solver.formats.toml_fields`. Beyond types, the file must describe an arm a draw
wire can calibrate (each rule says what to do when it fails):

* plausible sizes: |α|, |θ offset| ≤ 360°; |a|, |d|, tool point, link radii ≤ 10 m; joint
  limits within ±3600° (ten turns); speeds in (0, 10 000] °/s; |mm_per_count| ≤ 10 mm;
  range_mm in (0, 100 m]. Larger values are typing slips, and would only fail later;
* degrees, not radians: twists α and θ offsets whose non-zero values are all within ±π with
  one at ±π/2 or ±π; a joint whose limits both lie within ±2π;
* millimetres, not metres: the arm's links (Σ|a| + Σ|d|) add up to less than 1 % of the
  encoder's range or less than its widest link radius;
* each joint's range wider than 10° (:data:`MIN_JOINT_RANGE_DEG`): plan design and the
  generated programs keep every point 5° inside each limit;
* a counter wide enough for the wire: 2^(bits−1)·|mm_per_count| must exceed range_mm, or two
  wire lengths a counter turn apart give the same count;
* an encoder interface the controller language reads: "belt" or "device" for V+, "pulse"
  (the URScript pulse decoder, ``pulse_inputs`` two digital inputs 8–11) for URScript.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.cell import DEFAULT_MARGIN_MM, Box, CellModel, HalfSpace, Housing
from wirecal.solver.exit_geometry import Exit, Eyelet, Pulley
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.formats.run_token import MIN_KEY_CHARS
from wirecal.solver.formats.toml_fields import Table, document, duplicates, valid
from wirecal.solver.robot import (
    DEFAULT_CHANNEL,
    DEFAULT_DRUM_PPM_PER_K,
    DEFAULT_GRAVITY_SAG_DEG_PER_M,
    DEFAULT_LINK_RADIUS_MM,
    DEFAULT_SCALE_TOLERANCE_PPM,
    INTERFACES,
    LANGUAGES,
    SOFTWARE_LINES,
    SOFTWARE_PATTERN,
    Controller,
    Encoder,
    Robot,
    UrdfSource,
)

MAX_LENGTH_MM = 10_000.0
"""Largest |a|, |d|, tool coordinate or link radius (mm): no arm a draw wire spans is 10 m."""
MAX_DH_ANGLE_DEG = 360.0
"""Largest |α| or |θ offset| in the DH table (deg)."""
MAX_JOINT_DEG = 3600.0
"""Largest |joint limit| (deg): ten turns."""
MAX_SPEED_DEG_S = 10_000.0
MAX_MM_PER_COUNT = 10.0
MAX_RANGE_MM = 100_000.0
MAX_WIRE_SPEED_MM_S = 20_000.0
"""Largest wire speed limit (mm/s): catalogue draw-wire sensors allow 1–10 m/s."""
MAX_WIRE_ACCEL_MM_S2 = 1_000_000.0
"""Largest wire acceleration limit (mm/s²): about 100 g; catalogues give 5–20 g."""
MAX_CELL_MARGIN_MM = 500.0
"""Largest ``[cell] margin_mm``: a gap wider than half a metre leaves no arm room to move."""
MIN_JOINT_RANGE_DEG = 10.0
"""A joint's range (deg) must exceed this: plan points stay 5° (the planner's and the
generator's default margin) inside each limit."""
MAX_SCALE_PPM = 100_000.0
"""Largest scale tolerance (ppm): 10 %; a draw-wire sensor is far better than that."""
MAX_REFERENCE_U_MM = 1.0
"""Largest certified uncertainty of a reference gauge (mm)."""
MAX_TEMPCO_PPM_PER_K = 1000.0
"""Largest |temperature coefficient| (ppm/K): metals and plastics are below 200."""
MAX_GRAVITY_SAG_DEG_PER_M = 1.0
"""Largest gravity sag (deg per metre of lever): 1 deg/m bends a 0.6 m arm by 10 mm."""
METRES_RATIO = 0.01
"""Links adding up to less than this fraction of the encoder's range are in metres."""

MAX_EXIT_DEG = 90.0
"""Largest eyelet cone half-angle (deg): beyond 90° the wire would leave backwards."""
MAX_EXIT_RADIUS_MM = 100.0
"""Largest eyelet edge or guide pulley radius (mm): draw-wire sensors' are a few mm."""
AXIS_TOLERANCE = 0.01
"""An exit axis must be a unit vector to within this (it is then normalised exactly)."""
EXIT_KEYS = ("exit", "axis", "max_exit_deg", "exit_edge_radius_mm", "pulley_radius_mm")
"""The ``[encoder]`` keys of the wire exit (:mod:`wirecal.solver.exit_geometry`)."""
_EXIT_OWN: dict[str, tuple[str, ...]] = {
    "eyelet": ("axis", "max_exit_deg", "exit_edge_radius_mm"),
    "pulley": ("axis", "pulley_radius_mm"),
}

_DH_COLUMNS = "[alpha_deg, a_mm, theta_offset_deg, d_mm]"
_DH_BOUND = (MAX_DH_ANGLE_DEG, MAX_LENGTH_MM, MAX_DH_ANGLE_DEG, MAX_LENGTH_MM)

_KEYS = {
    "": (
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
    ),
    "kinematics": (
        "convention",
        "dh",
        "joint_min_deg",
        "joint_max_deg",
        "joint_speed_deg_s",
        "joint_speed_confirmed",
    ),
    "tool": ("point_mm",),
    "encoder": (
        "mm_per_count",
        "range_mm",
        "counter_bits",
        "interface",
        "channel",
        "belt_mode",
        "pulse_inputs",
        *EXIT_KEYS,
        "max_wire_speed_mm_s",
        "max_wire_accel_mm_s2",
        "scale_tolerance_ppm",
        "reference_length_mm",
        "reference_uncertainty_mm",
        "reference_repeats",
        "temperature_coefficient_ppm_per_k",
    ),
    "calibration": ("parameters", "gravity_sag_deg_per_m"),
    "geometry": ("link_radius_mm",),
    "urdf": ("source", "base_link", "tip_link", "parallel_tol_deg", "wire_point_mm"),
    "controller": ("language", "software", "host", "port", "key"),
    "cell": (
        "floor_z_mm",
        "margin_mm",
        "body_min_deg",
        "body_max_deg",
        "box",
        "half_space",
        "encoder_housing",
    ),
    "cell.box": ("name", "min_mm", "max_mm"),
    "cell.half_space": ("name", "point_mm", "normal"),
    "cell.encoder_housing": ("direction", "length_mm", "radius_mm"),
}

PULSE_INPUTS = (8, 11)
"""Digital inputs the URScript pulse decoder takes for signals A and B ("Must be 8-11":
UR e-Series Script Directory §14.2, encoder_enable_pulse_decode, p. 26)."""


def load_robot(path: str | Path) -> Robot:
    """Read and validate a robot file; raise :class:`WirecalError` listing every problem."""
    data = read_toml(path, "robot file")
    return robot_from_dict(data, str(path))


def robot_from_dict(data: dict[str, Any], source: str = "<robot>") -> Robot:
    """Validate a parsed robot description (see module docstring)."""
    doc = document(data, source, "robot file", _KEYS[""])
    name = doc.string("name")
    doc.string("description", None)
    doc.string("source", None)
    kin = doc.table("kinematics", _KEYS["kinematics"])
    dh = _dh(kin)
    n = None if dh is None else dh.shape[0]
    lo, hi = _limits(kin, n)
    speed = kin.vector(
        "joint_speed_deg_s",
        length=n,
        labels="(one per joint)",
        above=0,
        hi=MAX_SPEED_DEG_S,
        unit="deg/s",
    )
    speed_confirmed = kin.boolean("joint_speed_confirmed", True)
    tool = doc.table("tool", _KEYS["tool"])
    point = tool.vector(
        "point_mm", length=3, labels="(x, y, z)", lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM, unit="mm"
    )
    controller = _controller(doc.table("controller", _KEYS["controller"], required=False))
    encoder = _encoder(doc.table("encoder", _KEYS["encoder"]), controller)
    calibration = doc.table("calibration", _KEYS["calibration"])
    parameters = _parameters(calibration, n)
    sag = calibration.number(
        "gravity_sag_deg_per_m",
        DEFAULT_GRAVITY_SAG_DEG_PER_M,
        lo=0,
        hi=MAX_GRAVITY_SAG_DEG_PER_M,
        unit="deg/m",
    )
    radii = doc.table("geometry", _KEYS["geometry"], required=False).vector(
        "link_radius_mm",
        None,
        length=None if n is None else n - 1,
        labels="(one per link)",
        lo=0,
        hi=MAX_LENGTH_MM,
        unit="mm",
    )
    if dh is not None and radii is None:
        radii = np.full(dh.shape[0] - 1, DEFAULT_LINK_RADIUS_MM)
    urdf = _urdf(doc.table("urdf", _KEYS["urdf"], required=False), source)
    cell = _cell(doc.table("cell", _KEYS["cell"], required=False), n)
    _sanity(doc, dh, lo, hi, encoder, radii)
    doc.raise_if_any()
    dh_rad = valid(dh).copy()
    dh_rad[:, [0, 2]] = np.radians(dh_rad[:, [0, 2]])
    return Robot(
        name=valid(name).strip(),
        dh=dh_rad,
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
        joint_speed_confirmed=valid(speed_confirmed),
        gravity_sag_deg_per_m=valid(sag),
        cell=valid(cell),
    )


def _cell(table: Table, n: int | None) -> CellModel | None:
    """Read the optional ``[cell]`` table (a floor at z = 0 of frame 0 when absent)."""
    floor = table.number("floor_z_mm", 0.0, lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM, unit="mm")
    margin = table.number("margin_mm", DEFAULT_MARGIN_MM, lo=0, hi=MAX_CELL_MARGIN_MM, unit="mm")
    body = [
        table.vector(
            key, None, length=n, labels="(one per joint)", lo=-MAX_JOINT_DEG, hi=MAX_JOINT_DEG
        )
        for key in ("body_min_deg", "body_max_deg")
    ]
    if body[0] is not None and body[1] is not None:
        for j in np.flatnonzero(body[0] >= body[1]):
            table.add("body_max_deg", f"joint {j + 1}: {body[1][j]:g} is not above body_min_deg")
    boxes = [_box(t) for t in table.tables("box", _KEYS["cell.box"], required=False)]
    spaces = [
        _half_space(t) for t in table.tables("half_space", _KEYS["cell.half_space"], required=False)
    ]
    housing = _housing(
        table.table("encoder_housing", _KEYS["cell.encoder_housing"], required=False)
    )
    if floor is None or margin is None or None in boxes or None in spaces or housing is False:
        return None
    return CellModel(
        floor,
        margin,
        None if body[0] is None else tuple(body[0]),
        None if body[1] is None else tuple(body[1]),
        tuple(b for b in boxes if b is not None),
        tuple(h for h in spaces if h is not None),
        housing if isinstance(housing, Housing) else None,
    )


def _point(table: Table, key: str) -> tuple[float, float, float] | None:
    v = table.vector(key, length=3, labels="(x, y, z)", lo=-MAX_LENGTH_MM, hi=MAX_LENGTH_MM)
    return None if v is None else (float(v[0]), float(v[1]), float(v[2]))


def _box(table: Table) -> Box | None:
    """Read one ``[[cell.box]]``: its name and opposite corners (frame 0, mm)."""
    name, lo, hi = table.string("name"), _point(table, "min_mm"), _point(table, "max_mm")
    if name is None or lo is None or hi is None:
        return None
    if not all(a < b for a, b in zip(lo, hi, strict=True)):
        table.add("max_mm", f"{list(hi)} is not above min_mm {list(lo)} in every coordinate")
        return None
    return Box(name, lo, hi)


def _unit(table: Table, key: str) -> tuple[float, float, float] | None:
    """Read a unit vector (normalised exactly; its length must be 1 within 1 %)."""
    v = table.vector(key, length=3, labels="(x, y, z)", lo=-1, hi=1)
    if v is None:
        return None
    norm = float(np.linalg.norm(v))
    if abs(norm - 1) > AXIS_TOLERANCE:
        table.add(key, f"has length {norm:.4g}; give a unit vector (length 1 within 1 %)")
        return None
    x, y, z = (float(c) for c in v / norm)
    return (x, y, z)


def _half_space(table: Table) -> HalfSpace | None:
    """Read one ``[[cell.half_space]]``: a point on its plane and the free side's normal."""
    name, point, normal = table.string("name"), _point(table, "point_mm"), _unit(table, "normal")
    if name is None or point is None or normal is None:
        return None
    return HalfSpace(name, point, normal)


def _housing(table: Table) -> Housing | bool | None:
    """Read ``[cell.encoder_housing]``: None when absent, False when it has problems."""
    if not table.present:
        return None
    direction = _unit(table, "direction")
    length = table.number("length_mm", above=0, hi=MAX_LENGTH_MM, unit="mm")
    radius = table.number("radius_mm", above=0, hi=MAX_LENGTH_MM, unit="mm")
    if direction is None or length is None or radius is None:
        return False
    return Housing(direction, length, radius)


def _controller(table: Table) -> Controller | None:
    """Read the optional ``[controller]`` table (V+ when absent)."""
    language = table.string("language", "vplus", choices=LANGUAGES)
    host = table.string("host", None)
    if host is not None and not all(33 <= ord(c) <= 126 and c != '"' for c in host):
        table.add("host", f"is {host!r}; give an address or host name (printable, no spaces)")
        host = None
    port = table.integer("port", None, lo=1, hi=65535)
    software = _software(table, language)
    key = table.string("key", None)
    if key is not None and (len(key) < MIN_KEY_CHARS or not all(33 <= ord(c) <= 126 for c in key)):
        table.add(
            "key",
            f"has {len(key)} characters; give {MIN_KEY_CHARS} or more printable ones, no "
            "spaces (the secret the run token is derived from)",
        )
        key = None
    keys = table.keys()
    read = {"host": host, "port": port, "key": key, "software": software}
    bad = [k for k, v in read.items() if k in keys and v is None]
    if language is None or bad:
        return None
    return Controller(language, host, port, key, software)


def _software(table: Table, language: str | None) -> str | None:
    """Read ``software``: "major.minor[.patch]", of a line wirecal knows for the language."""
    software = table.string("software", None)
    if software is None:
        return None
    if not SOFTWARE_PATTERN.fullmatch(software):
        table.add("software", f'is {software!r}; give the version as numbers, e.g. "5.20"')
        return None
    lines = SOFTWARE_LINES.get(language or "", {})
    major = int(software.split(".")[0])
    if lines and major not in lines:
        known = ", ".join(f"{name} {m}.x" for m, name in lines.items())
        table.add("software", f"is {software!r}; wirecal knows {known}")
        return None
    return software


MAX_JOINTS = 12
"""Most rows of ``dh``: serial arms have 6 or 7 joints; wirecal's bound, not a controller's."""


def _dh(kin: Table) -> np.ndarray | None:
    kin.string("convention", choices={"craig": "modified DH, the one supported"})
    dh = kin.matrix(
        "dh",
        cols=4,
        labels=_DH_COLUMNS,
        lo=[-b for b in _DH_BOUND],
        hi=_DH_BOUND,
        unit=("deg", "mm", "deg", "mm"),
        max_rows=MAX_JOINTS,
    )
    if dh is not None and dh.shape[0] < 2:
        kin.add("dh", f"has {dh.shape[0]} row(s); a serial arm needs at least 2")
        return None
    return dh


def _limits(kin: Table, n: int | None) -> tuple[np.ndarray | None, np.ndarray | None]:
    lo, hi = (
        kin.vector(
            key,
            length=n,
            labels="(one per joint)",
            lo=-MAX_JOINT_DEG,
            hi=MAX_JOINT_DEG,
            unit="deg",
        )
        for key in ("joint_min_deg", "joint_max_deg")
    )
    if lo is None or hi is None or lo.shape != hi.shape:
        return lo, hi
    for j in np.flatnonzero(lo >= hi):
        kin.add("joint_min_deg", f"joint {j + 1}: min {lo[j]:g} is not below max {hi[j]:g}")
    return lo, hi


def _encoder(enc: Table, controller: Controller | None) -> Encoder | None:
    mpc = enc.number("mm_per_count", lo=-MAX_MM_PER_COUNT, hi=MAX_MM_PER_COUNT, unit="mm")
    if mpc == 0:
        enc.add("mm_per_count", "must not be zero")
        mpc = None
    rng = enc.number("range_mm", above=0, hi=MAX_RANGE_MM, unit="mm")
    bits = enc.integer("counter_bits", lo=8, hi=64)
    language = "vplus" if controller is None else controller.language
    interface = enc.string(
        "interface",
        INTERFACES[language][0],
        choices={
            "belt": "V+: DEFBELT/BELT",
            "device": "V+: DEVICE",
            "pulse": "URScript: the controller's pulse decoder",
            "group": "RAPID: a counter's group input, GInputDnum",
        },
    )
    if controller is not None and interface is not None and interface not in INTERFACES[language]:
        enc.add(
            "interface",
            f"is {interface!r}, which the {LANGUAGES[language]} programs cannot read; give "
            + " or ".join(repr(i) for i in INTERFACES[language])
            + " (or change [controller] language)",
        )
        interface = None
    pulse = interface == "pulse"
    channel = enc.integer(
        "channel", DEFAULT_CHANNEL.get(interface or "", 0), lo=0, hi=1 if pulse else 16
    )
    mode = enc.integer("belt_mode", 0, lo=0, hi=16)
    inputs = enc.vector(
        "pulse_inputs",
        [8, 9],
        length=2,
        labels="(A, B)",
        lo=PULSE_INPUTS[0],
        hi=PULSE_INPUTS[1],
        integer=True,
    )
    if inputs is not None and inputs[0] == inputs[1]:
        enc.add("pulse_inputs", f"A and B are both input {inputs[0]:g}; give two inputs")
        inputs = None
    if "pulse_inputs" in enc.keys() and not pulse:
        enc.add("pulse_inputs", 'is for interface = "pulse" (URScript) only; remove it')
    tol = enc.number(
        "scale_tolerance_ppm", DEFAULT_SCALE_TOLERANCE_PPM, lo=0, hi=MAX_SCALE_PPM, unit="ppm"
    )
    ref = enc.number("reference_length_mm", None, above=0, hi=MAX_RANGE_MM, unit="mm")
    ref_u = enc.number("reference_uncertainty_mm", 0.0, lo=0, hi=MAX_REFERENCE_U_MM, unit="mm")
    repeats = enc.integer("reference_repeats", 3, lo=1, hi=20)
    tempco = enc.number(
        "temperature_coefficient_ppm_per_k",
        DEFAULT_DRUM_PPM_PER_K,
        lo=-MAX_TEMPCO_PPM_PER_K,
        hi=MAX_TEMPCO_PPM_PER_K,
        unit="ppm/K",
    )
    if ref is not None and rng is not None and ref > rng:
        enc.add(
            "reference_length_mm",
            f"is {ref:g} mm, beyond range_mm {rng:g}: the wire cannot reach nest B; "
            "use a shorter gauge",
        )
        ref = None
    scale = (tol, ref_u, repeats, tempco)
    exit_ok, exit_ = _exit(enc)
    wire_speed = enc.number(
        "max_wire_speed_mm_s", None, above=0, hi=MAX_WIRE_SPEED_MM_S, unit="mm/s"
    )
    wire_accel = enc.number(
        "max_wire_accel_mm_s2", None, above=0, hi=MAX_WIRE_ACCEL_MM_S2, unit="mm/s²"
    )
    if mpc is None or rng is None or bits is None or interface is None:
        return None
    if channel is None or mode is None or inputs is None or not exit_ok:
        return None
    if any(x is None for x in scale):
        return None
    return Encoder(
        mpc,
        rng,
        bits,
        interface,
        channel,
        mode,
        (int(inputs[0]), int(inputs[1])),
        exit_,
        wire_speed,
        wire_accel,
        scale_tolerance_ppm=valid(tol),
        reference_length_mm=ref,
        reference_uncertainty_mm=valid(ref_u),
        reference_repeats=valid(repeats),
        temperature_coefficient_ppm_per_k=valid(tempco),
    )


def _exit(enc: Table) -> tuple[bool, Exit | None]:
    """Read the wire exit keys: (whether they passed, the exit or None for a point exit).

    ``exit = "point"`` (the default: the paper's model) takes no other key;
    ``exit = "eyelet"`` needs ``axis``, ``max_exit_deg`` and ``exit_edge_radius_mm``;
    ``exit = "pulley"`` needs ``axis`` and ``pulley_radius_mm``.
    """
    kind = enc.string(
        "exit",
        "point",
        choices={
            "point": "the paper's ideal point exit, any direction",
            "eyelet": "point exit within a cone about axis",
            "pulley": "swivel guide pulley about axis",
        },
    )
    if kind is None:  # reported: the other keys cannot be judged
        return False, None
    own = _EXIT_OWN.get(kind, ())
    for key in EXIT_KEYS[1:]:
        if key in enc.keys() and key not in own:
            enc.add(
                key,
                f'belongs to exit = "{"pulley" if key == "pulley_radius_mm" else "eyelet"}"'
                + ("" if key != "axis" else ' or "pulley"')
                + f', not "{kind}"; remove it or change exit',
            )
    if kind == "point":
        return True, None
    axis = _axis(enc)
    if kind == "pulley":
        radius = enc.number("pulley_radius_mm", above=0, hi=MAX_EXIT_RADIUS_MM, unit="mm")
        if axis is None or radius is None:
            return False, None
        return True, Pulley(axis, radius)
    cone = enc.number("max_exit_deg", above=0, hi=MAX_EXIT_DEG, unit="deg")
    edge = enc.number("exit_edge_radius_mm", lo=0, hi=MAX_EXIT_RADIUS_MM, unit="mm")
    if axis is None or cone is None or edge is None:
        return False, None
    return True, Eyelet(axis, cone, edge)


def _axis(enc: Table) -> tuple[float, float, float] | None:
    """Return the exit's ``axis``, a unit vector (normalised exactly), or None."""
    axis = enc.vector("axis", length=3, labels="(x, y, z)", lo=-1, hi=1)
    if axis is None:
        return None
    norm = float(np.linalg.norm(axis))
    if abs(norm - 1) > AXIS_TOLERANCE:
        enc.add(
            "axis",
            f"has length {norm:.4g}; give the unit vector of the encoder's axis in the base "
            f"frame (length 1 within {AXIS_TOLERANCE:g}), e.g. [0.0, 0.0, 1.0] for a wire "
            "leaving upwards",
        )
        return None
    x, y, z = (float(c) for c in axis / norm)
    return (x, y, z)


def _parameters(cal: Table, n: int | None) -> list[str] | None:
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


def _sanity(
    doc: Table,
    dh: np.ndarray | None,
    lo: np.ndarray | None,
    hi: np.ndarray | None,
    encoder: Encoder | None,
    radii: np.ndarray | None,
) -> None:
    """Return the unit and size rules of the module docstring, on values that passed their types."""
    if dh is not None:
        _check_not_radians(dh[:, 0], "α (column 1)", doc)
        _check_not_radians(dh[:, 2], "θ offsets (column 3)", doc)
    if lo is not None and hi is not None and lo.shape == hi.shape:
        _check_joint_ranges(lo, hi, doc)
    if encoder is not None:
        _check_counter(encoder, doc)
    if dh is not None and encoder is not None and radii is not None:
        _check_not_metres(dh, encoder.range_mm, radii, doc)


def _check_not_radians(column_deg: np.ndarray, what: str, doc: Table) -> None:
    """Report a column of angles that holds radians.

    Twists and θ offsets of real arms are 0 or multiples of 90°: non-zero values all within
    ±π, one of them ±π/2 or ±π, are radians.
    """
    nz = np.abs(column_deg[np.abs(column_deg) > 1e-9])
    if (
        nz.size
        and np.all(nz <= math.pi + 1e-6)
        and np.any(np.minimum(np.abs(nz - math.pi / 2), np.abs(nz - math.pi)) < 1e-3)
    ):
        doc.add(
            "kinematics.dh",
            f"{what} holds values like {nz[0]:g}: that looks like radians; give degrees "
            f"({nz[0]:g} rad = {math.degrees(nz[0]):.4g}°)",
        )


def _check_joint_ranges(lo: np.ndarray, hi: np.ndarray, doc: Table) -> None:
    """Per joint: limits in radians, or a range too narrow to plan."""
    for j in np.flatnonzero(hi > lo):
        span = hi[j] - lo[j]
        if max(abs(lo[j]), abs(hi[j])) <= 2 * math.pi + 1e-9:
            doc.add(
                "kinematics.joint_max_deg",
                f"joint {j + 1}: limits [{lo[j]:g}, {hi[j]:g}] are within ±2π: they look like "
                f"radians (that would be [{math.degrees(lo[j]):.4g}, "
                f"{math.degrees(hi[j]):.4g}] deg); give degrees",
            )
        elif span <= MIN_JOINT_RANGE_DEG:
            doc.add(
                "kinematics.joint_max_deg",
                f"joint {j + 1}: range [{lo[j]:g}, {hi[j]:g}] spans {span:g} deg, no more than "
                f"{MIN_JOINT_RANGE_DEG:g} deg: no room for plan points "
                f"{MIN_JOINT_RANGE_DEG / 2:g} deg inside both limits; check the limits",
            )


def _check_counter(enc: Encoder, doc: Table) -> None:
    """Report a counter too narrow for the encoder's range.

    2^(bits−1)·|mm_per_count| must exceed the range: the signed counter then holds every
    wire length the encoder can give, so no reading is a counter turn away from another.
    """
    half, mpc = enc.counter.half, abs(enc.mm_per_count)
    if enc.range_mm / mpc >= half:
        doc.add(
            "encoder.counter_bits",
            f"a signed {enc.counter_bits}-bit counter tells lengths apart up to {half} counts "
            f"({half * mpc:g} mm at {mpc:g} mm/count); range_mm {enc.range_mm:g} is "
            f"{enc.range_mm / mpc:.0f} counts: wire lengths a counter turn apart would read "
            "the same; give the width of the controller's counter (24 for a V+ belt encoder) "
            "or a smaller range_mm, and check mm_per_count",
        )


def _check_not_metres(dh: np.ndarray, range_mm: float, radii: np.ndarray, doc: Table) -> None:
    """Report lengths in metres.

    Links adding up to under 1 % of the encoder range, or under the widest link radius,
    are metres.
    """
    reach = float(np.abs(dh[:, [1, 3]]).sum())
    widest = float(radii.max(initial=0.0))
    if reach < max(METRES_RATIO * range_mm, widest):
        against = (
            f"the widest link radius ({widest:g} mm)"
            if widest > METRES_RATIO * range_mm
            else f"1 % of the encoder's range_mm ({range_mm:g})"
        )
        doc.add(
            "kinematics.dh",
            f"the links add up to {reach:g} mm (Σ|a| + Σ|d|), less than {against}: the "
            "lengths look like metres; give a and d in mm (the tool point, range_mm and "
            "link_radius_mm too)",
        )


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


TIDY = 1e-11
"""Numbers written to a robot file are the shortest decimals within TIDY (mm or deg) of the
value: 425.0 rather than 425.0000000000001 (a change of the tip far below 1e-9 mm)."""


LIMIT_TIDY = 1e-7
"""Joint limits and speeds are written to within LIMIT_TIDY (deg, deg/s): a URDF's limits in
radians with 11 digits give 185.00000000003°; 185.0 is what the vendor meant."""


def _num(x: float, tidy: float = TIDY) -> str:
    """Return the shortest decimal within ``tidy`` of ``x`` (−0 written as 0)."""
    x = float(x)
    for digits in range(13):
        r = round(x, digits)
        if abs(r - x) <= tidy:
            return repr(r + 0.0)
    return repr(x)


def _exit_lines(exit_: Exit | None) -> list[str]:
    """Return the robot file lines of an exit (none for the ideal point exit)."""
    if exit_ is None:
        return []
    lines = [
        f"exit = {json.dumps(exit_.kind)}",
        "axis = [" + ", ".join(_num(c) for c in exit_.axis) + "]",
    ]
    if isinstance(exit_, Pulley):
        return [*lines, f"pulley_radius_mm = {_num(exit_.radius_mm)}"]
    return [
        *lines,
        f"max_exit_deg = {_num(exit_.max_exit_deg)}",
        f"exit_edge_radius_mm = {_num(exit_.edge_radius_mm)}",
    ]


def _scale_lines(enc: Encoder) -> list[str]:
    """Return the ``[encoder]`` lines of the scale, the reference gauge and the drum."""
    lines = [f"scale_tolerance_ppm = {_num(enc.scale_tolerance_ppm)}"]
    if enc.reference_length_mm is not None:
        lines += [
            f"reference_length_mm = {_num(enc.reference_length_mm)}",
            f"reference_uncertainty_mm = {_num(enc.reference_uncertainty_mm)}",
            f"reference_repeats = {enc.reference_repeats}",
        ]
    lines.append(
        f"temperature_coefficient_ppm_per_k = {_num(enc.temperature_coefficient_ppm_per_k)}"
    )
    return lines


def _cell_lines(cell: CellModel) -> list[str]:
    """Return the robot file lines of ``[cell]`` (the floor and margin always written)."""

    def vec(values) -> str:
        return "[" + ", ".join(_num(v) for v in values) + "]"

    lines = [
        "",
        "[cell]",
        "# the mounting plane in frame 0, and the gap kept from it, the volumes and the arm itself",
        f"floor_z_mm = {_num(cell.floor_z_mm)}",
        f"margin_mm = {_num(cell.margin_mm)}",
    ]
    for key, limits in (("body_min_deg", cell.body_min_deg), ("body_max_deg", cell.body_max_deg)):
        if limits is not None:
            lines.append(f"{key} = {vec(limits)}")
    if cell.housing is not None:
        h = cell.housing
        lines += [
            "",
            "[cell.encoder_housing]",
            f"direction = {vec(h.direction)}",
            f"length_mm = {_num(h.length_mm)}",
            f"radius_mm = {_num(h.radius_mm)}",
        ]
    for b in cell.boxes:
        lines += ["", "[[cell.box]]", f"name = {json.dumps(b.name, ensure_ascii=False)}"]
        lines += [f"min_mm = {vec(b.min_mm)}", f"max_mm = {vec(b.max_mm)}"]
    for w in cell.half_spaces:
        lines += ["", "[[cell.half_space]]", f"name = {json.dumps(w.name, ensure_ascii=False)}"]
        lines += [f"point_mm = {vec(w.point_mm)}", f"normal = {vec(w.normal)}"]
    return lines


def robot_file_text(
    robot: Robot,
    *,
    header: list[str],
    row_notes: list[str],
    encoder_note: str,
    urdf_source: str | None = None,
    speed_notes: Sequence[str] = (),
    geometry_notes: Sequence[str] | None = None,
    tables: Sequence[str] = (),
    write_cell: bool = True,
) -> str:
    """Return a robot file for ``robot`` that reads back to the same numbers.

    A robot file for ``robot`` that :func:`load_robot` reads back to the same numbers
    (to :data:`TIDY`). ``header`` lines become comments at the top; ``row_notes``
    (one per joint) comment the DH rows and limits; ``urdf_source`` is written as given
    (relative to the robot file's folder). ``speed_notes`` comment the joint speeds;
    the link radii are written as a ``[geometry]`` table with ``geometry_notes`` as its
    comments, and the cell model as ``[cell]`` unless not ``write_cell`` (the caller writes
    its own, or none, in ``tables``: lines of further tables, appended as given).
    """
    dh = robot.dh_deg()

    def vec(values, tidy: float = TIDY) -> str:
        return "[" + ", ".join(_num(v, tidy) for v in values) + "]"

    lines = [f"# {h}" if h else "#" for h in header]
    lines += [
        f"name = {json.dumps(robot.name, ensure_ascii=False)}",
        "",
        "[kinematics]",
        'convention = "craig"',
        "# rows: [alpha_deg, a_mm, theta_offset_deg, d_mm]",
        "dh = [",
        *(f"    {vec(row)},  # {note}" for row, note in zip(dh, row_notes, strict=True)),
        "]",
        f"joint_min_deg = {vec(robot.joint_min_deg, LIMIT_TIDY)}",
        f"joint_max_deg = {vec(robot.joint_max_deg, LIMIT_TIDY)}",
        *(f"# {line}" for line in speed_notes),
        f"joint_speed_deg_s = {vec(robot.joint_speed_deg_s, LIMIT_TIDY)}",
        *([] if robot.joint_speed_confirmed else ["joint_speed_confirmed = false"]),
        "",
        "[tool]",
        "# wire attachment point in the last joint's frame",
        f"point_mm = {vec(robot.tool_point)}",
        "",
        "[encoder]",
        f"# {encoder_note}",
        f"mm_per_count = {_num(robot.encoder.mm_per_count)}",
        f"range_mm = {_num(robot.encoder.range_mm)}",
        f"counter_bits = {robot.encoder.counter_bits}",
        f"interface = {json.dumps(robot.encoder.interface)}",
        f"channel = {robot.encoder.channel}",
        f"belt_mode = {robot.encoder.belt_mode}",
        *(
            [f"pulse_inputs = [{robot.encoder.pulse_inputs[0]}, {robot.encoder.pulse_inputs[1]}]"]
            if robot.encoder.interface == "pulse"
            else []
        ),
        *_exit_lines(robot.encoder.exit),
        *(
            f"{key} = {_num(value)}"
            for key, value in (
                ("max_wire_speed_mm_s", robot.encoder.max_wire_speed_mm_s),
                ("max_wire_accel_mm_s2", robot.encoder.max_wire_accel_mm_s2),
            )
            if value is not None
        ),
        *_scale_lines(robot.encoder),
        "",
        "[controller]",
        f"language = {json.dumps(robot.controller.language)}",
        *(
            [f"software = {json.dumps(robot.controller.software)}"]
            if robot.controller.software
            else []
        ),
        *([f"host = {json.dumps(robot.controller.host)}"] if robot.controller.host else []),
        *([f"port = {robot.controller.port}"] if robot.controller.port else []),
        *([f"key = {json.dumps(robot.controller.key)}"] if robot.controller.key else []),
        "",
        "[calibration]",
        "parameters = [" + ", ".join(json.dumps(p) for p in robot.parameters) + "]",
    ]
    if robot.gravity_sag_deg_per_m != DEFAULT_GRAVITY_SAG_DEG_PER_M:
        lines.append(f"gravity_sag_deg_per_m = {_num(robot.gravity_sag_deg_per_m)}")
    if robot.link_radius_mm is not None:
        lines += ["", "[geometry]", *(f"# {line}" for line in geometry_notes or ())]
        lines.append(f"link_radius_mm = {vec(robot.link_radius_mm)}")
    if write_cell:
        lines += _cell_lines(robot.cell)
    if urdf_source is not None and robot.urdf is not None:
        lines += ["", *_urdf_lines(robot.urdf, urdf_source)]
    for line in tables:
        lines.append(line)
    return "\n".join(lines) + "\n"


def _urdf_lines(urdf: UrdfSource, source: str) -> list[str]:
    """Return the ``[urdf]`` table's lines (``source`` as the file should hold it)."""
    lines = [
        "[urdf]",
        "# the URDF this file was imported from; export-urdf changes only its joint origins",
        f"source = {json.dumps(source, ensure_ascii=False)}",
        f"base_link = {json.dumps(urdf.base_link, ensure_ascii=False)}",
        f"tip_link = {json.dumps(urdf.tip_link, ensure_ascii=False)}",
    ]
    if urdf.parallel_tol_deg is not None:
        lines.append(f"parallel_tol_deg = {_num(urdf.parallel_tol_deg)}")
    if urdf.wire_point_mm is not None:
        point = ", ".join(_num(v) for v in urdf.wire_point_mm)
        lines += [
            "# the wire attachment point in the tip link's frame (import-urdf --wire-point-mm)",
            f"wire_point_mm = [{point}]",
        ]
    return lines
