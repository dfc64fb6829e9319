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
    [calibration]
    parameters = ["th2", "th3", ...]      # names from wirecal.solver.params

Every problem is reported as ``file: key: problem``, all at once.
"""

from __future__ import annotations

import difflib
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.errors import Problems
from wirecal.solver.formats.fileio import read_toml
from wirecal.solver.robot import DEFAULT_LINK_RADIUS_MM, Encoder, Robot, UrdfSource

_SCHEMA: dict[str, tuple[str, ...]] = {
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
    ),
    "kinematics": ("convention", "dh", "joint_min_deg", "joint_max_deg", "joint_speed_deg_s"),
    "tool": ("point_mm",),
    "encoder": ("mm_per_count", "range_mm", "counter_bits", "interface", "channel", "belt_mode"),
    "calibration": ("parameters",),
    "geometry": ("link_radius_mm",),
    "urdf": ("source", "base_link", "tip_link", "parallel_tol_deg"),
}


_REQUIRED = {
    "": ("name", "kinematics", "tool", "encoder", "calibration"),
    "kinematics": ("convention", "dh", "joint_min_deg", "joint_max_deg", "joint_speed_deg_s"),
    "tool": ("point_mm",),
    "encoder": ("mm_per_count", "range_mm", "counter_bits"),
    "calibration": ("parameters",),
    "geometry": (),
    "urdf": ("source", "base_link", "tip_link"),
}


def load_robot(path: str | Path) -> Robot:
    """Read and validate a robot file; raise :class:`WirecalError` listing every problem."""
    data = read_toml(path, "robot file")
    return robot_from_dict(data, str(path))


def robot_from_dict(data: dict[str, Any], source: str = "<robot>") -> Robot:
    """Validate a parsed robot description (see module docstring)."""
    pr = Problems(source)
    _check_keys(data, pr)

    name = data.get("name")
    if "name" in data and (not isinstance(name, str) or not name.strip()):
        pr.add("name", "must be a non-empty string")

    kin = _table(data, "kinematics", pr)
    if "convention" in kin and kin["convention"] != "craig":
        pr.add(
            "kinematics.convention",
            f'is {kin["convention"]!r}; only "craig" (modified DH) is supported',
        )

    dh = _matrix(kin, "dh", "kinematics.dh", 4, pr)
    n = dh.shape[0] if dh is not None else None
    if dh is not None:
        if n < 2:
            pr.add("kinematics.dh", f"has {n} row(s); a serial arm needs at least 2")
        _check_not_radians(dh[:, 0], "kinematics.dh", "α (column 1)", pr)

    vec = {}
    for key in ("joint_min_deg", "joint_max_deg", "joint_speed_deg_s"):
        vec[key] = _vector(kin, key, f"kinematics.{key}", n, pr)
    lo, hi, speed = vec["joint_min_deg"], vec["joint_max_deg"], vec["joint_speed_deg_s"]
    if lo is not None and hi is not None and lo.shape == hi.shape:
        for j in np.flatnonzero(lo >= hi):
            pr.add(
                "kinematics.joint_min_deg",
                f"joint {j + 1}: min {lo[j]:g} is not below max {hi[j]:g}",
            )
        spans = hi - lo
        if np.all(spans <= 2 * math.pi + 1e-9):
            pr.add(
                "kinematics.joint_max_deg",
                "every joint range is within ±2π: the limits look like radians; give degrees",
            )
    if speed is not None:
        for j in np.flatnonzero(speed <= 0):
            pr.add("kinematics.joint_speed_deg_s", f"joint {j + 1}: speed must be > 0")

    tool = _table(data, "tool", pr)
    point = _vector(tool, "point_mm", "tool.point_mm", 3, pr)

    enc = _table(data, "encoder", pr)
    mpc = _number(enc, "mm_per_count", "encoder.mm_per_count", pr)
    if mpc is not None and mpc == 0:
        pr.add("encoder.mm_per_count", "must not be zero")
    rng = _number(enc, "range_mm", "encoder.range_mm", pr)
    if rng is not None and rng <= 0:
        pr.add("encoder.range_mm", "must be > 0")
    bits = enc.get("counter_bits")
    if "counter_bits" in enc and (
        not isinstance(bits, int) or isinstance(bits, bool) or not 8 <= bits <= 64
    ):
        pr.add("encoder.counter_bits", f"is {bits!r}; give an integer between 8 and 64")

    interface = enc.get("interface", "belt")
    if interface not in ("belt", "device"):
        pr.add(
            "encoder.interface",
            f'is {interface!r}; give "belt" (DEFBELT/BELT) or "device" (DEVICE)',
        )
    channel = enc.get("channel", 1 if interface == "belt" else 0)
    mode = enc.get("belt_mode", 0)
    for key, value in (("channel", channel), ("belt_mode", mode)):
        if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= 16:
            pr.add(f"encoder.{key}", f"is {value!r}; give a whole number 0–16")

    cal = _table(data, "calibration", pr)
    names = cal.get("parameters")
    if "parameters" in cal:
        if not isinstance(names, list) or not all(isinstance(x, str) for x in names):
            pr.add("calibration.parameters", "must be a list of parameter names")
        elif not names:
            pr.add("calibration.parameters", "is empty; name at least one parameter")
        else:
            seen = set()
            for x in names:
                if x in seen:
                    pr.add("calibration.parameters", f"{x!r} is listed twice")
                seen.add(x)
                if n is not None:
                    try:
                        P.parse(x, n)
                    except ValueError as exc:
                        pr.add("calibration.parameters", str(exc))

    geometry = _table(data, "geometry", pr)
    radii = _vector(
        geometry, "link_radius_mm", "geometry.link_radius_mm", None if n is None else n - 1, pr
    )
    if radii is not None and np.any(radii < 0):
        pr.add("geometry.link_radius_mm", "radii cannot be negative")

    urdf = None
    if "urdf" in data:
        table = _table(data, "urdf", pr)
        values = [table.get(k) for k in ("source", "base_link", "tip_link")]
        for key, value in zip(("source", "base_link", "tip_link"), values, strict=True):
            if key in table and (not isinstance(value, str) or not value):
                pr.add(f"urdf.{key}", "must be a non-empty string")
        tol = _number(table, "parallel_tol_deg", "urdf.parallel_tol_deg", pr)
        if tol is not None and not 0 < tol < 0.05:
            pr.add("urdf.parallel_tol_deg", f"is {tol!r}; give an angle between 0 and 0.05 deg")
        if all(isinstance(v, str) and v for v in values):
            here = Path() if source.startswith("<") else Path(source).parent
            urdf = UrdfSource(str(here / values[0]), values[1], values[2], tol)

    pr.raise_if_any()
    dh_rad = dh.copy()
    dh_rad[:, [0, 2]] = np.radians(dh_rad[:, [0, 2]])
    return Robot(
        name=name.strip(),
        dh=dh_rad,
        joint_min_deg=lo,
        joint_max_deg=hi,
        joint_speed_deg_s=speed,
        tool_point=point,
        encoder=Encoder(float(mpc), float(rng), int(bits), interface, channel, mode),
        parameters=tuple(names),
        source=source,
        link_radius_mm=radii if radii is not None else np.full(n - 1, DEFAULT_LINK_RADIUS_MM),
        urdf=urdf,
    )


def _check_keys(data: dict[str, Any], pr: Problems) -> None:
    for section, allowed in _SCHEMA.items():
        table = data if section == "" else data.get(section)
        if not isinstance(table, dict):
            continue
        prefix = f"{section}." if section else ""
        for key in _REQUIRED[section]:
            if key not in table:
                pr.add(f"{prefix}{key}", "is missing")
        for key in table:
            if key not in allowed:
                hint = difflib.get_close_matches(key, allowed, n=1)
                extra = f" (did you mean {hint[0]!r}?)" if hint else ""
                pr.add(f"{prefix}{key}", f"unknown key{extra}")


def _table(data: dict[str, Any], key: str, pr: Problems) -> dict[str, Any]:
    value = data.get(key, {})
    if not isinstance(value, dict):
        pr.add(key, f"must be a table [{key}]")
        return {}
    return value


def _is_number(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool)


def _number(table: dict[str, Any], key: str, where: str, pr: Problems) -> float | None:
    if key not in table:
        return None
    x = table[key]
    if not _is_number(x) or not math.isfinite(x):
        pr.add(where, f"is {x!r}; give a finite number")
        return None
    return float(x)


def _vector(
    table: dict[str, Any], key: str, where: str, length: int | None, pr: Problems
) -> np.ndarray | None:
    if key not in table:
        return None
    x = table[key]
    if not isinstance(x, list) or not all(_is_number(v) for v in x):
        pr.add(where, "must be a list of numbers")
        return None
    arr = np.asarray(x, dtype=float)
    if length is not None and arr.shape != (length,):
        pr.add(
            where,
            f"has {arr.size} values; expected {length} (one per joint)"
            if length != 3
            else f"has {arr.size} values; expected 3 (x, y, z)",
        )
        return None
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        pr.add(where, f"value {bad[0] + 1} is not finite")
        return None
    return arr


def _matrix(
    table: dict[str, Any], key: str, where: str, cols: int, pr: Problems
) -> np.ndarray | None:
    if key not in table:
        return None
    rows = table[key]
    if not isinstance(rows, list) or not rows:
        pr.add(where, "must be a list of rows [alpha_deg, a_mm, theta_offset_deg, d_mm]")
        return None
    ok = True
    for i, row in enumerate(rows, 1):
        if not isinstance(row, list) or len(row) != cols or not all(_is_number(v) for v in row):
            pr.add(
                where, f"row {i} must be {cols} numbers [alpha_deg, a_mm, theta_offset_deg, d_mm]"
            )
            ok = False
        elif not all(math.isfinite(v) for v in row):
            pr.add(where, f"row {i} has a value that is not finite")
            ok = False
    return np.asarray(rows, dtype=float) if ok else None


def _check_not_radians(alpha_deg: np.ndarray, where: str, what: str, pr: Problems) -> None:
    """Twist angles of real arms are multiples of 90° or 0; values like 1.5708 are radians."""
    nz = np.abs(alpha_deg[np.abs(alpha_deg) > 1e-9])
    if nz.size and np.all(nz <= math.pi + 1e-6) and np.any(np.abs(nz - math.pi / 2) < 1e-3):
        pr.add(where, f"{what} holds values like {nz[0]:g}: that looks like radians; give degrees")


TIDY = 1e-11
"""Numbers written to a robot file are the shortest decimals within TIDY (mm or deg) of the
value: 425.0 rather than 425.0000000000001 (a change of the tip far below 1e-9 mm)."""


LIMIT_TIDY = 1e-7
"""Joint limits and speeds are written to within LIMIT_TIDY (deg, deg/s): a URDF's limits in
radians with 11 digits give 185.00000000003°; 185.0 is what the vendor meant."""


def _num(x: float, tidy: float = TIDY) -> str:
    """The shortest decimal within ``tidy`` of ``x`` (−0 written as 0)."""
    x = float(x)
    for digits in range(13):
        r = round(x, digits)
        if abs(r - x) <= tidy:
            return repr(r + 0.0)
    return repr(x)


def robot_file_text(
    robot: Robot,
    *,
    header: list[str],
    row_notes: list[str],
    encoder_note: str,
    urdf_source: str | None = None,
) -> str:
    """A robot file for ``robot`` that :func:`load_robot` reads back to the same numbers
    (to :data:`TIDY`). ``header`` lines become comments at the top; ``row_notes``
    (one per joint) comment the DH rows and limits; ``urdf_source`` is written as given
    (relative to the robot file's folder)."""
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
        f"joint_speed_deg_s = {vec(robot.joint_speed_deg_s, LIMIT_TIDY)}",
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
        "",
        "[calibration]",
        "parameters = [" + ", ".join(json.dumps(p) for p in robot.parameters) + "]",
    ]
    if urdf_source is not None and robot.urdf is not None:
        lines += [
            "",
            "[urdf]",
            "# the URDF this file was imported from; export-urdf changes only its joint origins",
            f"source = {json.dumps(urdf_source, ensure_ascii=False)}",
            f"base_link = {json.dumps(robot.urdf.base_link, ensure_ascii=False)}",
            f"tip_link = {json.dumps(robot.urdf.tip_link, ensure_ascii=False)}",
        ]
        if robot.urdf.parallel_tol_deg is not None:
            lines.append(f"parallel_tol_deg = {_num(robot.urdf.parallel_tol_deg)}")
    return "\n".join(lines) + "\n"
