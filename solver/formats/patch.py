"""Parameter patch files: the identified offsets, and the table to enter in the controller.

The patch (TOML) records, per parameter, the nominal value, the identified offset, the new
value and its σ, with the plan fingerprint, the log's sha256, the method and the date.
Beside it, ``<name>.spec.txt`` lists the values to enter in the controller's kinematic
settings (Adept's SPEC utility).
"""

from __future__ import annotations

import json
import math
from datetime import UTC, datetime
from pathlib import Path

from wirecal.solver import params as P
from wirecal.solver.errors import Problems, WirecalError
from wirecal.solver.formats.fileio import Outputs, read_toml
from wirecal.solver.identify import Estimate
from wirecal.solver.plausibility import OVERRIDDEN
from wirecal.solver.robot import Robot

_FIELD = {"th": "theta offset", "d": "d", "a": "a", "al": "alpha", "tool": "tool point"}


def _rows(robot: Robot, estimate: Estimate):
    for k, name in enumerate(estimate.names):
        p = P.parse(name, robot.n_joints)
        nominal = robot.nominal_value(name)
        offset = float(estimate.values[k])
        std = None if estimate.std is None else float(estimate.std[k])
        yield name, p, nominal, offset, nominal + offset, std


def patch_text(
    robot: Robot,
    estimate: Estimate,
    *,
    plan_fingerprint: str,
    log_path: str,
    log_sha256: str,
    version: str,
    plausibility: str = "",
    date: datetime | None = None,
) -> str:
    """The patch TOML; ``plausibility`` is the gate's verdict ("passed …" or
    "overridden: …" when the user accepted an implausible result)."""
    date = date or datetime.now(UTC)
    lines = [
        "# wirecal patch: identified kinematic error offsets (deg, mm).",
        "# value = nominal + offset; std is the 1-sigma uncertainty (joint method only).",
        f"robot = {json.dumps(robot.name, ensure_ascii=False)}",
        f"plan = {json.dumps(plan_fingerprint)}",
        f"log = {json.dumps(log_path, ensure_ascii=False)}",
        f"log_sha256 = {json.dumps(log_sha256)}",
        f"method = {json.dumps(estimate.method)}",
        f"date = {json.dumps(date.strftime('%Y-%m-%dT%H:%M:%SZ'))}",
        f"wirecal = {json.dumps(version)}",
        f"residual_rms_mm = {estimate.residual_rms_mm!r}",
    ]
    if plausibility:
        lines.append(f"plausibility = {json.dumps(plausibility, ensure_ascii=False)}")
    for name, p, nominal, offset, value, std in _rows(robot, estimate):
        lines += [
            "",
            f"[parameters.{name}]",
            f'unit = "{p.unit}"',
            f"nominal = {nominal!r}",
            f"offset = {offset!r}",
            f"value = {value!r}",
        ]
        if std is not None:  # inf (valid TOML) where the points do not identify it
            lines.append(f"std = {std!r}")
    return "\n".join(lines) + "\n"


def spec_table(robot: Robot, estimate: Estimate, plausibility: str = "") -> str:
    """The plain table of new values for the controller's kinematic settings."""
    lines = []
    if plausibility.startswith(OVERRIDDEN):
        lines += [
            "WARNING: wirecal's plausibility gate refused this result and the refusal was",
            f"overridden (--accept-implausible): {plausibility[len(OVERRIDDEN) :]}",
            "",
        ]
    lines += [
        f"Kinematic parameters for {robot.name} identified by wirecal ({estimate.method}).",
        "Enter the 'new value' column in the controller's kinematic settings (Adept SPEC",
        "utility: link dimensions and joint calibration offsets). Save a copy of SPEC first.",
        "DH row i holds alpha(i-1), a(i-1), theta(i), d(i) (Craig). Check the sign",
        "convention of the controller's joint-offset field on one joint before entering all.",
        "",
        f"{'parameter':<10}{'DH row':>7}  {'field':<14}{'unit':<6}{'nominal':>12}"
        f"{'new value':>12}{'offset':>11}{'sigma':>9}",
    ]
    for name, p, nominal, offset, value, std in _rows(robot, estimate):
        row = "-" if p.kind == "tool" else p.row + 1
        sigma = f"{'-':>9}" if std is None else f"{std:9.4f}" if math.isfinite(std) else " unident."
        lines.append(
            f"{name:<10}{row!s:>7}  {_FIELD[p.kind]:<14}{p.unit:<6}{nominal:12.4f}"
            f"{value:12.4f}{offset:+11.4f}{sigma}"
        )
    return "\n".join(lines) + "\n"


def spec_path(path: str | Path) -> Path:
    """Where the SPEC table of the patch ``path`` goes: ``<name>.spec.txt`` beside it."""
    path = Path(path)
    return path.with_name(path.stem + ".spec.txt")


def put_patch(out: Outputs, path: str | Path, robot: Robot, estimate: Estimate, **meta) -> None:
    """Put the patch and its SPEC table (:func:`spec_path`) into the output set ``out``,
    which must hold both names: they are published together or not at all."""
    out.put(path, patch_text(robot, estimate, **meta))
    out.put(spec_path(path), spec_table(robot, estimate, meta.get("plausibility", "")))


def load_patch(path: str | Path, robot: Robot) -> dict[str, float]:
    """The identified offsets (deg, mm) of a patch written by :func:`put_patch`, checked
    against the robot: its name, each parameter's name and nominal value."""
    data = read_toml(path, "patch file")
    pr = Problems(str(path))
    if data.get("robot") != robot.name:
        pr.add("robot", f"is {data.get('robot')!r}; the robot file is {robot.name!r}")
    table = data.get("parameters")
    if not isinstance(table, dict) or not table:
        raise WirecalError(f"{path}: parameters: missing [parameters.<name>] tables")
    out: dict[str, float] = {}
    for name, entry in table.items():
        where = f"parameters.{name}"
        try:
            P.parse(name, robot.n_joints)
        except ValueError as exc:
            pr.add(where, str(exc))
            continue
        values = [entry.get(k) if isinstance(entry, dict) else None for k in ("offset", "nominal")]
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
            for v in values
        ):
            pr.add(where, "needs finite numbers nominal and offset")
            continue
        offset, nominal = (float(v) for v in values)  # type: ignore[arg-type]
        if abs(nominal - robot.nominal_value(name)) > 1e-9 * max(1.0, abs(nominal)):
            pr.add(
                f"{where}.nominal",
                f"is {nominal!r}; the robot file's is {robot.nominal_value(name)!r}: "
                "this patch was solved for another robot file",
            )
            continue
        out[name] = offset
    pr.raise_if_any()
    return out
