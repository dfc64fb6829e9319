"""The robot file's ``[controller]`` and ``[encoder]`` tables.

The controller language the programs are generated in, where they report to, and the
draw-wire encoder: its scale, counter, the controller input it is read through and the wire's
exit (:mod:`wirecal.solver.exit_geometry`). The format is in
:mod:`wirecal.formats.robot_file`.
"""

from __future__ import annotations

import math

from wirecal.formats.robot_values import (
    MAX_EXIT_DEG,
    MAX_EXIT_RADIUS_MM,
    MAX_MM_PER_COUNT,
    MAX_RANGE_MM,
    MAX_REFERENCE_U_MM,
    MAX_SCALE_PPM,
    MAX_TEMPCO_PPM_PER_K,
    MAX_WIRE_ACCEL_MM_S2,
    MAX_WIRE_SPEED_MM_S,
    MIN_RANGE_MM,
    MIN_WIRE_ACCEL_MM_S2,
    MIN_WIRE_SPEED_MM_S,
    unit_vector,
)
from wirecal.formats.run_token import MIN_KEY_CHARS
from wirecal.formats.toml_fields import Table, valid
from wirecal.lang.registry import default_language, first_channel, languages
from wirecal.solver.exit_geometry import Exit, Eyelet, Pulley
from wirecal.solver.robot import (
    DEFAULT_DRUM_PPM_PER_K,
    DEFAULT_SCALE_TOLERANCE_PPM,
    SOFTWARE_PATTERN,
    Controller,
    Encoder,
)

CONTROLLER_KEYS = ("language", "software", "host", "port", "key")
"""The keys of ``[controller]``."""
EXIT_KEYS = ("exit", "axis", "max_exit_deg", "exit_edge_radius_mm", "pulley_radius_mm")
"""The ``[encoder]`` keys of the wire exit (:mod:`wirecal.solver.exit_geometry`)."""
ENCODER_KEYS = (
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
)
"""The keys of ``[encoder]``."""
_EXIT_OWN: dict[str, tuple[str, ...]] = {
    "eyelet": ("axis", "max_exit_deg", "exit_edge_radius_mm"),
    "pulley": ("axis", "pulley_radius_mm"),
}
PULSE_INPUTS = (8, 11)
"""Digital inputs the URScript pulse decoder takes for signals A and B ("Must be 8-11":
UR e-Series Script Directory §14.2, encoder_enable_pulse_decode, p. 26)."""


def read_language_and_interface(controller: Table, enc: Table) -> tuple[str | None, str | None]:
    """Read ``[controller] language`` (V+ when absent) and ``[encoder] interface``.

    The interface defaults to the language's first (its registered ``encoder_interfaces``)
    and must be one the language's programs read. None for a value with a problem (reported).
    """
    titles = {key: lang.title for key, lang in languages().items()}
    language = controller.string("language", default_language().key, choices=titles)
    lang = languages()[language] if language is not None else default_language()
    readable = lang.capabilities.encoder_interfaces
    interface = enc.string(
        "interface",
        readable[0],
        choices=dict(
            sorted(
                (i, f"{other.title}: {other.interface_notes.get(i, '')}")
                for other in languages().values()
                for i in other.capabilities.encoder_interfaces
            )
        ),
    )
    if language is not None and interface is not None and interface not in readable:
        enc.add(
            "interface",
            f"is {interface!r}, which the {lang.title} programs cannot read; give "
            + " or ".join(map(repr, readable))
            + " (or change [controller] language)",
        )
        interface = None
    return language, interface


def read_controller(table: Table, language: str | None) -> Controller | None:
    """Read the rest of the optional ``[controller]`` table, for ``language``."""
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
    lang = languages()[language] if language else None
    if lang is not None and not lang.knows_software(software):
        table.add("software", f"is {software!r}; wirecal knows {lang.software_lines_text()}")
        return None
    return software


MIN_REFERENCE_MM = 50.0
"""The shortest reference gauge: 0.01 mm of reading noise is 200 ppm of 50 mm."""


def _round_angle_in_radians(value: float) -> bool:
    """Whether ``value`` is a multiple of 15 deg (up to 90) written in radians (1.5708)."""
    return any(abs(value - math.radians(k * 15)) < 1e-3 for k in range(1, 7))


def read_encoder(enc: Table, interface: str | None) -> Encoder | None:
    """Read the rest of ``[encoder]``, read through ``interface``."""
    mpc = enc.number("mm_per_count", lo=-MAX_MM_PER_COUNT, hi=MAX_MM_PER_COUNT, unit="mm")
    if mpc == 0:
        enc.add("mm_per_count", "must not be zero")
        mpc = None
    rng = _range_mm(enc)
    bits = enc.integer("counter_bits", lo=8, hi=64)
    pulse = interface == "pulse"
    channel = enc.integer("channel", first_channel(interface), lo=0, hi=1 if pulse else 16)
    mode = enc.integer("belt_mode", 0, lo=0, hi=16)
    inputs = _pulse_inputs(enc, pulse)
    tol, ref, ref_u, repeats, tempco = _scale(enc, rng)
    scale = (tol, ref_u, repeats, tempco)
    exit_ok, exit_ = _exit(enc)
    wire_speed, wire_accel = _wire_limits(enc)
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
        inputs,
        exit_,
        wire_speed,
        wire_accel,
        scale_tolerance_ppm=valid(tol),
        reference_length_mm=ref,
        reference_uncertainty_mm=valid(ref_u),
        reference_repeats=valid(repeats),
        temperature_coefficient_ppm_per_k=valid(tempco),
    )


def _range_mm(enc: Table) -> float | None:
    """Read ``range_mm``; None, with a problem naming the unit, when it is in metres."""
    rng = enc.number("range_mm", above=0, hi=MAX_RANGE_MM, unit="mm")
    return _in_unit(
        enc,
        "range_mm",
        rng,
        MIN_RANGE_MM,
        f"a wire under {MIN_RANGE_MM:g} mm spans no arm; that looks like metres "
        f"({(rng or 0) * 1000:g} mm); give the encoder's range in mm",
    )


def _in_unit(enc: Table, key: str, value: float | None, least: float, why: str) -> float | None:
    """Return ``value``; None, with a problem ``is value: why``, under ``least``.

    Such a value is in a larger unit (metres for mm): ``why`` says which.
    """
    if value is None or value >= least:
        return value
    enc.add(key, f"is {value:g}: {why}")
    return None


def _scale(
    enc: Table, range_mm: float | None
) -> tuple[float | None, float | None, float | None, int | None, float | None]:
    """Read the scale's keys: tolerance, reference gauge (length, uncertainty, repeats), drum.

    A reference gauge too short to tell the scale, or beyond ``range_mm``, is refused
    (its length then None).
    """
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
    if ref is not None and ref < MIN_REFERENCE_MM:
        enc.add(
            "reference_length_mm",
            f"is {ref:g} mm: a gauge shorter than {MIN_REFERENCE_MM:g} mm reads the scale "
            "no better than its tolerance; give the certified length of the gauge's nests "
            "in mm (e.g. 500)",
        )
        ref = None
    if ref is not None and range_mm is not None and ref > range_mm:
        enc.add(
            "reference_length_mm",
            f"is {ref:g} mm, beyond range_mm {range_mm:g}: the wire cannot reach nest B; "
            "use a shorter gauge",
        )
        ref = None
    return tol, ref, ref_u, repeats, tempco


def _wire_limits(enc: Table) -> tuple[float | None, float | None]:
    """Read the wire's speed and acceleration limits (mm/s, mm/s²; None: not given)."""
    speed = enc.number("max_wire_speed_mm_s", None, above=0, hi=MAX_WIRE_SPEED_MM_S, unit="mm/s")
    accel = enc.number("max_wire_accel_mm_s2", None, above=0, hi=MAX_WIRE_ACCEL_MM_S2, unit="mm/s²")
    speed = _in_unit(
        enc,
        "max_wire_speed_mm_s",
        speed,
        MIN_WIRE_SPEED_MM_S,
        f"a wire limited to under {MIN_WIRE_SPEED_MM_S:g} mm/s would take about a minute per "
        f"metre; that looks like m/s ({(speed or 0) * 1000:g} mm/s); give mm/s",
    )
    accel = _in_unit(
        enc,
        "max_wire_accel_mm_s2",
        accel,
        MIN_WIRE_ACCEL_MM_S2,
        f"under {MIN_WIRE_ACCEL_MM_S2:g} mm/s² (0.1 g); that looks like m/s² "
        f"({(accel or 0) * 1000:g} mm/s²) or g; give mm/s²",
    )
    return speed, accel


def _pulse_inputs(enc: Table, pulse: bool) -> tuple[int, int] | None:
    """Read ``pulse_inputs``, the digital inputs (A, B) of the URScript pulse decoder."""
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
    return None if inputs is None else (int(inputs[0]), int(inputs[1]))


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
    axis = unit_vector(
        enc,
        "axis",
        "the unit vector of the encoder's axis in the base frame",
        ", e.g. [0.0, 0.0, 1.0] for a wire leaving upwards",
    )
    if kind == "pulley":
        radius = enc.number("pulley_radius_mm", above=0, hi=MAX_EXIT_RADIUS_MM, unit="mm")
        if axis is None or radius is None:
            return False, None
        return True, Pulley(axis, radius)
    cone = enc.number("max_exit_deg", above=0, hi=MAX_EXIT_DEG, unit="deg")
    if cone is not None and _round_angle_in_radians(cone):
        enc.add(
            "max_exit_deg",
            f"is {cone:g}: that is {math.degrees(cone):.0f} deg in radians; give degrees",
        )
        cone = None
    edge = enc.number("exit_edge_radius_mm", lo=0, hi=MAX_EXIT_RADIUS_MM, unit="mm")
    if axis is None or cone is None or edge is None:
        return False, None
    return True, Eyelet(axis, cone, edge)
