"""Write a robot file: the text :mod:`wirecal.formats.robot_file` reads back.

``wirecal import-urdf`` writes its robot file with :func:`robot_file_text`; numbers are the
shortest decimals that read back to the value.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

from wirecal.solver.cell.model import CellModel
from wirecal.solver.exit_geometry import Exit, Pulley
from wirecal.solver.gravity import DOWN
from wirecal.solver.joint_speeds import placeholder_speeds
from wirecal.solver.robot import (
    DEFAULT_GRAVITY_SAG_DEG_PER_M,
    Controller,
    Encoder,
    Robot,
    UrdfSource,
)

TIDY = 1e-11
"""Numbers written to a robot file are the shortest decimals within TIDY (mm or deg) of the
value: 425.0 rather than 425.0000000000001 (a change of the tip far below 1e-9 mm)."""


LIMIT_TIDY = 1e-7
"""Joint limits and speeds are written to within LIMIT_TIDY (deg, deg/s): a URDF's limits in
radians with 11 digits give 185.00000000003°; 185.0 is what the vendor meant."""


SCALE_TIDY = 1e-12
"""``mm_per_count`` is a scale: written to within SCALE_TIDY of itself, not of a mm (a
length of range_mm then moves by 1e-12 of it; 1e-300 stays 1e-300, not 0)."""


def _num(x: float, tidy: float = TIDY) -> str:
    """Return the shortest decimal within ``tidy`` of ``x`` (−0 written as 0)."""
    x = float(x)
    for digits in range(13):
        r = round(x, digits)
        if abs(r - x) <= tidy:
            return repr(r + 0.0)
    return repr(x)


def _vec(values, tidy: float = TIDY) -> str:
    """Return ``values`` as a TOML array of :func:`_num` decimals."""
    return "[" + ", ".join(_num(v, tidy) for v in values) + "]"


def _confirmed_line(robot: Robot) -> list[str]:
    """Return the ``joint_speed_confirmed`` line when it says something.

    False: a URDF's placeholders; true: speeds that would read as placeholders otherwise (a
    heavy arm's, given by the user).
    """
    if robot.joint_speed_confirmed is False:
        return ["joint_speed_confirmed = false"]
    if robot.joint_speed_confirmed and placeholder_speeds(robot.joint_speed_deg_s):
        return ["joint_speed_confirmed = true"]
    return []


def _exit_lines(exit_: Exit | None) -> list[str]:
    """Return the robot file lines of an exit (none for the ideal point exit)."""
    if exit_ is None:
        return []
    lines = [
        f"exit = {json.dumps(exit_.kind)}",
        f"axis = {_vec(exit_.axis)}",
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
    lines = [
        "",
        "[cell]",
        "# the mounting plane in frame 0, and the gap kept from it, the volumes and the arm itself",
        f"floor_z_mm = {_num(cell.floor_z_mm)}",
        f"margin_mm = {_num(cell.margin_mm)}",
    ]
    for key, limits in (("body_min_deg", cell.body_min_deg), ("body_max_deg", cell.body_max_deg)):
        if limits is not None:
            lines.append(f"{key} = {_vec(limits)}")
    if cell.housing is not None:
        h = cell.housing
        lines += [
            "",
            "[cell.encoder_housing]",
            f"direction = {_vec(h.direction)}",
            f"length_mm = {_num(h.length_mm)}",
            f"radius_mm = {_num(h.radius_mm)}",
        ]
    for b in cell.boxes:
        lines += ["", "[[cell.box]]", f"name = {json.dumps(b.name, ensure_ascii=False)}"]
        lines += [f"min_mm = {_vec(b.min_mm)}", f"max_mm = {_vec(b.max_mm)}"]
    for w in cell.half_spaces:
        lines += ["", "[[cell.half_space]]", f"name = {json.dumps(w.name, ensure_ascii=False)}"]
        lines += [f"point_mm = {_vec(w.point_mm)}", f"normal = {_vec(w.normal)}"]
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

    A robot file for ``robot`` that
    :func:`~wirecal.formats.robot_file.load_robot` reads back to the same numbers
    (to :data:`TIDY`). ``header`` lines become comments at the top; ``row_notes``
    (one per joint) comment the DH rows and limits; ``urdf_source`` is written as given
    (relative to the robot file's folder). ``speed_notes`` comment the joint speeds;
    the link radii are written as a ``[geometry]`` table with ``geometry_notes`` as its
    comments, and the cell model as ``[cell]`` unless not ``write_cell`` (the caller writes
    its own, or none, in ``tables``: lines of further tables, appended as given).
    """
    lines = [f"# {h}" if h else "#" for h in header]
    lines += [
        f"name = {json.dumps(robot.name, ensure_ascii=False)}",
        *_kinematics_lines(robot, row_notes, speed_notes),
        *_encoder_lines(robot.encoder, encoder_note),
        *_controller_lines(robot.controller),
        *_calibration_lines(robot),
    ]
    if robot.link_radius_mm is not None:
        lines += ["", "[geometry]", *(f"# {line}" for line in geometry_notes or ())]
        lines.append(f"link_radius_mm = {_vec(robot.link_radius_mm)}")
    lines += _gravity_lines(robot)
    if write_cell:
        lines += _cell_lines(robot.cell)
    if urdf_source is not None and robot.urdf is not None:
        lines += ["", *_urdf_lines(robot.urdf, urdf_source)]
    for line in tables:
        lines.append(line)
    return "\n".join(lines) + "\n"


def _kinematics_lines(robot: Robot, row_notes: list[str], speed_notes: Sequence[str]) -> list[str]:
    """Return the ``[kinematics]`` table (DH rows, one note each; limits; speeds) and ``[tool]``."""
    return [
        "",
        "[kinematics]",
        'convention = "craig"',
        "# rows: [alpha_deg, a_mm, theta_offset_deg, d_mm]",
        "dh = [",
        *(
            f"    {_vec(row)},  # {note}"
            for row, note in zip(robot.dh_deg(), row_notes, strict=True)
        ),
        "]",
        f"joint_min_deg = {_vec(robot.joint_min_deg, LIMIT_TIDY)}",
        f"joint_max_deg = {_vec(robot.joint_max_deg, LIMIT_TIDY)}",
        *(f"# {line}" for line in speed_notes),
        f"joint_speed_deg_s = {_vec(robot.joint_speed_deg_s, LIMIT_TIDY)}",
        *_confirmed_line(robot),
        "",
        "[tool]",
        "# wire attachment point in the last joint's frame",
        f"point_mm = {_vec(robot.tool_point)}",
    ]


def _encoder_lines(enc: Encoder, note: str) -> list[str]:
    """Return the ``[encoder]`` table, ``note`` its comment."""
    return [
        "",
        "[encoder]",
        f"# {note}",
        f"mm_per_count = {_num(enc.mm_per_count, SCALE_TIDY * abs(enc.mm_per_count))}",
        f"range_mm = {_num(enc.range_mm)}",
        f"counter_bits = {enc.counter_bits}",
        f"interface = {json.dumps(enc.interface)}",
        f"channel = {enc.channel}",
        f"belt_mode = {enc.belt_mode}",
        *(
            [f"pulse_inputs = [{enc.pulse_inputs[0]}, {enc.pulse_inputs[1]}]"]
            if enc.interface == "pulse"
            else []
        ),
        *_exit_lines(enc.exit),
        *(
            f"{key} = {_num(value)}"
            for key, value in (
                ("max_wire_speed_mm_s", enc.max_wire_speed_mm_s),
                ("max_wire_accel_mm_s2", enc.max_wire_accel_mm_s2),
            )
            if value is not None
        ),
        *_scale_lines(enc),
    ]


def _controller_lines(ctrl: Controller) -> list[str]:
    """Return the ``[controller]`` table (the keys not given left out)."""
    return [
        "",
        "[controller]",
        f"language = {json.dumps(ctrl.language)}",
        *([f"software = {json.dumps(ctrl.software)}"] if ctrl.software else []),
        *([f"host = {json.dumps(ctrl.host)}"] if ctrl.host else []),
        *([f"port = {ctrl.port}"] if ctrl.port else []),
        *([f"key = {json.dumps(ctrl.key)}"] if ctrl.key else []),
    ]


def _calibration_lines(robot: Robot) -> list[str]:
    """Return the ``[calibration]`` table: parameters, compliances or the gravity sag."""
    lines = [
        "",
        "[calibration]",
        "parameters = [" + ", ".join(json.dumps(p) for p in robot.parameters) + "]",
    ]
    if robot.compliances:
        lines.append("compliances = [" + ", ".join(json.dumps(c) for c in robot.compliances) + "]")
    if robot.repeatability_mm is not None:
        lines.append(f"repeatability_mm = {_num(robot.repeatability_mm)}")
    if robot.gravity_sag_deg_per_m != DEFAULT_GRAVITY_SAG_DEG_PER_M and not robot.compliances:
        lines.append(f"gravity_sag_deg_per_m = {_num(robot.gravity_sag_deg_per_m)}")
    return lines


def _gravity_lines(robot: Robot) -> list[str]:
    """Return the ``[gravity]`` table's lines (none for a rigid arm without masses)."""
    m = robot.masses
    if m is None:
        return []
    lines = ["", "[gravity]"]
    if m.source:
        lines.append(f"source = {json.dumps(m.source, ensure_ascii=False)}")
    if not m.assumed:
        lines.append("link_mass_kg = [" + ", ".join(_num(v) for v in m.link_mass_kg) + "]")
        rows = ", ".join("[" + ", ".join(_num(v) for v in r) + "]" for r in m.link_com_mm)
        lines.append(f"link_com_mm = [{rows}]")
    if m.payload_mass_kg:
        lines.append(f"payload_mass_kg = {_num(m.payload_mass_kg)}")
        lines.append("payload_com_mm = [" + ", ".join(_num(v) for v in m.payload_com_mm) + "]")
    if tuple(m.direction) != DOWN:
        lines.append("direction = [" + ", ".join(_num(v) for v in m.direction) + "]")
    if robot.compliance_urad_per_nm is not None:
        c = ", ".join(_num(v) for v in robot.compliance_urad_per_nm)
        lines.append(f"compliance_urad_per_nm = [{c}]")
    return lines


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
