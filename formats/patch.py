"""Parameter patch files: the identified offsets, and the table to enter in the controller.

The patch (TOML) records, per parameter, the nominal value, the identified offset, the new
value and its σ, with the plan fingerprint, the log's sha256, the method and the date; the
joint method's identified compliances (:mod:`wirecal.solver.compliance`) go to their own
``[compliance]`` table, in µrad/(N·m). No controller file wirecal writes carries them (the
SPEC table and the languages' companions say so, :data:`COMPLIANCE_NOT_CARRIED`).
Beside it, ``<name>.spec.txt`` lists the values to enter in the controller's kinematic
settings (Adept's SPEC utility). :func:`read_patch` reads a patch back (``wirecal gen
--patch``) with the field rules of :mod:`wirecal.formats.toml_fields`, and refuses
a file that is not a patch (a truth file, a plan) or a patch of another robot or plan.
A σ may be of any size (an implausible result written with --accept-implausible has huge
ones); the gate's verdict is kept in ``plausibility`` and carried, when it was
overridden, into every artefact made from the patch (:attr:`Patch.warning`).
"""

from __future__ import annotations

import json
import math
import re
import textwrap
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

from wirecal.formats.fileio import Outputs, read_toml
from wirecal.formats.patch_digest import DIGEST_TABLE, edits, seal
from wirecal.formats.robot_file import MAX_DH_ANGLE_DEG, MAX_LENGTH_MM
from wirecal.formats.toml_fields import Table, document, valid
from wirecal.lang.base import Language
from wirecal.lang.registry import language
from wirecal.solver import params as P
from wirecal.solver.errors import WirecalError
from wirecal.solver.identify import Estimate
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.verdict import override_warning

UNCHECKED_ADVICE = "Measure the step(s) again before entering these values."
_FIELD = {"th": "theta offset", "d": "d", "a": "a", "al": "alpha", "tool": "tool point"}


COMPLIANCE_NOT_CARRIED = (
    "Not carried: the gravity compliances in the patch's [compliance] table. The values "
    "here are link dimensions and joint offsets only (no kinematic setting wirecal writes, "
    "V+ SPEC, UR calibration.conf or ABB fine calibration, takes a joint compliance; "
    "whether a controller option such as ABB's Absolute Accuracy does is unconfirmed "
    "here). The arm sags as before: bound95_mm includes that sag. To remove it, command "
    "compensated targets computed offline: wirecal.compensated_joints(model, q) gives the "
    "joints to command for the joints q of the calibrated geometry (docs/accuracy.md)."
)
"""What the SPEC table and the companions say when the patch has compliances."""


def _is_compliance(name: str) -> bool:
    return P.unit_of(name) == "urad/Nm"


def _rows(robot: Robot, estimate: Estimate, compliance: bool = False):
    """Yield each parameter's row (the compliances' with ``compliance``, else the others')."""
    for k, name in enumerate(estimate.names):
        if _is_compliance(name) != compliance:
            continue
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
    unchecked: tuple[str, ...] = (),
    date: datetime | None = None,
) -> str:
    """Return the patch TOML.

    ``plausibility`` is the gate's verdict ("passed …" or "overridden: …" when the user
    accepted an implausible result); ``unchecked`` names the steps solved without their
    closing zero check (:attr:`~wirecal.solver.solve.SolveResult.unchecked`).
    """
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
    if unchecked:
        lines.append(f"unchecked = {json.dumps(list(unchecked), ensure_ascii=False)}")
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
    for name, p, nominal, offset, value, std in _rows(robot, estimate, compliance=True):
        lines += [
            "",
            f"[compliance.{name}]",
            "# joint compliance under gravity: the joint turns by value × its gravity torque",
            f'unit = "{p.unit}"',
            f"nominal = {nominal!r}",
            f"offset = {offset!r}",
            f"value = {value!r}",
        ]
        if std is not None:
            lines.append(f"std = {std!r}")
    return seal("\n".join(lines) + "\n")


def spec_table(
    robot: Robot, estimate: Estimate, plausibility: str = "", unchecked: tuple[str, ...] = ()
) -> str:
    """Return the plain table of new values for the controller's kinematic settings."""
    lines = []
    warning = override_warning(plausibility)
    if warning is not None:
        lines += [*textwrap.wrap(f"WARNING: {warning}", 88, break_on_hyphens=False), ""]
    if unchecked:
        lines += [f"WARNING: {w}." for w in unchecked]
        lines += [UNCHECKED_ADVICE, ""]
    lines += [
        f"Kinematic parameters for {robot.name} identified by wirecal ({estimate.method}).",
        *_entry_advice(language(robot.controller.language)),
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
    if any(_is_compliance(n) for n in estimate.names):
        lines += ["", *textwrap.wrap(COMPLIANCE_NOT_CARRIED, 88, break_on_hyphens=False)]
    return "\n".join(lines) + "\n"


def _entry_advice(lang: Language) -> tuple[str, ...]:
    """Where the table's values go: Adept's SPEC, or the language's own companion file."""
    if lang.patch_companion is None:
        return (
            "Enter the 'new value' column in the controller's kinematic settings (Adept SPEC",
            "utility: link dimensions and joint calibration offsets). Save a copy of SPEC first.",
            "DH row i holds alpha(i-1), a(i-1), theta(i), d(i) (Craig). Check the sign",
            "convention of the controller's joint-offset field on one joint before entering all.",
        )
    return (
        f"A {lang.title} controller takes no Craig DH table: this table is for reading.",
        f"What the controller can take is in the file ending {lang.patch_companion} beside",
        "this one (it says which values have no place there). DH row i holds alpha(i-1),",
        "a(i-1), theta(i), d(i) (Craig).",
    )


def spec_path(path: str | Path) -> Path:
    """Where the SPEC table of the patch ``path`` goes: ``<name>.spec.txt`` beside it."""
    path = Path(path)
    return path.with_name(path.stem + ".spec.txt")


def _companion(lang: Language, path: str | Path) -> Path | None:
    """Where the language's own patch companion goes beside ``path`` (None: it has none)."""
    path = Path(path)
    suffix = lang.patch_companion
    return None if suffix is None else path.with_name(path.stem + suffix)


def companion_paths(robot: Robot, path: str | Path) -> list[Path]:
    """Return the files written beside the patch ``path`` for ``robot``'s controller.

    The SPEC table always, and the language's own companion if it has one
    (:attr:`wirecal.lang.base.Language.patch_companion`: for URScript UR's standard-DH
    deltas).
    """
    own = _companion(language(robot.controller.language), path)
    return [spec_path(path), *([own] if own is not None else [])]


def put_patch(out: Outputs, path: str | Path, robot: Robot, estimate: Estimate, **meta) -> None:
    """Put the patch and its companions into an output set.

    Put the patch, its SPEC table (:func:`spec_path`) and the language's own companion
    (:meth:`wirecal.lang.base.Language.patch_section`) into the output set ``out``, which
    must hold every name of :func:`companion_paths`: they are published together or not
    at all.
    """
    out.put(path, patch_text(robot, estimate, **meta))
    out.put(
        spec_path(path),
        spec_table(robot, estimate, meta.get("plausibility", ""), meta.get("unchecked", ())),
    )
    lang = language(robot.controller.language)
    own = _companion(lang, path)
    if own is not None:
        geometry = {n: v for n, v in estimate.as_dict().items() if not _is_compliance(n)}
        text = lang.patch_section(robot, geometry) or ""
        if len(geometry) < len(estimate.names):
            note = textwrap.wrap(COMPLIANCE_NOT_CARRIED, 86, break_on_hyphens=False)
            text += "\n" + "\n".join(f"# {line}" for line in note) + "\n"
        out.put(own, text)


def write_patch(
    path: str | Path, robot: Robot, estimate: Estimate, *, force: bool = False, **meta
) -> tuple[Path, Path]:
    """Write the patch and its SPEC table beside it, both or neither.

    The Python API's one-call form of :func:`put_patch`; refuse to replace either unless
    ``force``.
    """
    path = Path(path)
    with Outputs([path, *companion_paths(robot, path)], force=force) as out:
        put_patch(out, path, robot, estimate, **meta)
    return path, spec_path(path)


_KEYS = (
    "robot",
    "plan",
    "log",
    "log_sha256",
    "method",
    "date",
    "wirecal",
    "residual_rms_mm",
    "plausibility",
    "unchecked",
    "parameters",
    DIGEST_TABLE,
    "compliance",
)
_VALUE_KEYS = ("unit", "nominal", "offset", "value", "std")
_SHA256 = re.compile(r"^[0-9a-f]{64}$")


@dataclass(frozen=True)
class PatchMeta:
    """Where a patch came from.

    Robot, plan fingerprint, log and its sha256, method, date, the wirecal version, the
    fit's residual RMS (mm), the plausibility verdict ("" in patches written before
    the gate), and the steps solved without their closing zero check.
    """

    robot: str
    plan: str
    log: str
    log_sha256: str
    method: str
    date: str
    wirecal: str
    residual_rms_mm: float
    plausibility: str = ""
    unchecked: tuple[str, ...] = ()


@dataclass(frozen=True)
class PatchValue:
    """One parameter of a patch (deg or mm).

    value = nominal + offset; std when known (``inf`` where the measured points do not
    identify the parameter).
    """

    unit: str
    nominal: float
    offset: float
    value: float
    std: float | None = None


@dataclass(frozen=True)
class Patch:
    """A patch file read back: its metadata and its parameters, in file order."""

    meta: PatchMeta
    parameters: dict[str, PatchValue]
    source: str
    compliance: dict[str, PatchValue] = field(default_factory=dict)  # c<j>, µrad/(N·m)

    @property
    def warning(self) -> str | None:
        """Return the warning every artefact made from the patch carries; None if it has none.

        The overridden gate's (:func:`~wirecal.solver.verdict.override_warning`) and each
        step solved without its zero check (a --partial run's ``unchecked``).
        """
        parts = [override_warning(self.meta.plausibility)]
        parts += [f"{u}." for u in self.meta.unchecked]
        if self.meta.unchecked:
            parts.append(UNCHECKED_ADVICE)
        return " ".join(p for p in parts if p) or None

    def offsets_for(self, robot: Robot, plan: Plan | None = None) -> dict[str, float]:
        """Return the identified offsets, once the patch is shown to belong here.

        Same robot name, every parameter one of the robot's, in its unit, with the robot
        file's nominal value, and (when ``plan`` is given) the same plan fingerprint;
        otherwise a :class:`WirecalError` listing each mismatch.
        """
        problems = []
        if self.meta.robot != robot.name:
            problems.append(
                f"{self.source}: robot: the patch is for {self.meta.robot!r} but the robot "
                f"file describes {robot.name!r}; use the matching robot file"
            )
        if plan is not None and self.meta.plan != plan.fingerprint():
            problems.append(
                f"{self.source}: plan: the patch comes from `wirecal fit` (table "
                f"{self.meta.log}), which has no plan: only a patch `wirecal solve` wrote "
                "for this plan goes here; a fit's patch goes to export-urdf --patch (its "
                "controller companion was written beside it)"
                if self.meta.method == "fit"
                else f"{self.source}: plan: the patch was solved from another plan; generate "
                "with the plan it came from"
            )
        for name, v in self.parameters.items():
            try:
                unit = P.parse(name, robot.n_joints).unit
            except ValueError as exc:
                problems.append(f"{self.source}: parameters.{name}: {exc}")
                continue
            if v.unit != unit:
                problems.append(
                    f"{self.source}: parameters.{name}.unit: is {v.unit!r} but {name} is in "
                    f"{unit}; the patch was edited or is for another arm"
                )
            elif abs(v.nominal - robot.nominal_value(name)) > 1e-9 * max(1.0, abs(v.nominal)):
                problems.append(
                    f"{self.source}: parameters.{name}.nominal: is {v.nominal!r}; the robot "
                    f"file's is {robot.nominal_value(name)!r}: this patch was solved for "
                    "another robot file"
                )
        if problems:
            raise WirecalError(problems)
        return {name: v.offset for name, v in self.parameters.items()}


def read_patch(path: str | Path) -> Patch:
    """Read and validate a patch written by :func:`put_patch` (module docstring)."""
    data = read_toml(path, "patch file")
    doc = document(data, str(path), "patch file", _KEYS)
    text = {key: doc.string(key) for key in ("robot", "log", "method", "date", "wirecal")}
    digests = {key: doc.string(key) for key in ("plan", "log_sha256")}
    for key, digest in digests.items():
        if digest is not None and not _SHA256.match(digest):
            doc.add(key, f"is {digest!r}; give a sha256 (64 lowercase hex digits)")
    rms = doc.number("residual_rms_mm", lo=0, hi=MAX_LENGTH_MM, unit="mm")
    plausibility = doc.string("plausibility", "")
    unchecked = doc.strings("unchecked", [], what="warnings")
    table = doc.table("parameters", None)
    values = {name: _value(table.table(name, _VALUE_KEYS)) for name in table.keys()}
    if table.present and not values:
        table.add("", "is empty; a patch holds at least one parameter")
    ctable = doc.table("compliance", None, required=False)
    compliance = {n: _compliance(ctable, n) for n in ctable.keys()}
    doc.raise_if_any()
    _check_digest(data, str(path))
    meta = PatchMeta(
        **{k: valid(v) for k, v in (text | digests).items()},
        residual_rms_mm=valid(rms),
        plausibility=valid(plausibility),
        unchecked=tuple(valid(unchecked)),
    )
    return Patch(
        meta,
        {n: v for n, v in values.items() if v is not None},
        str(path),
        {n: v for n, v in compliance.items() if v is not None},
    )


_WHAT = {
    "plausibility": " (the mark that the plausibility gate was overridden)",
    "unchecked": " (the mark of the steps solved without their zero check)",
}


def _check_digest(data: dict, source: str) -> None:
    """Refuse a patch edited since it was written, naming each edit (:mod:`.patch_digest`)."""
    problems = [
        f"{source}: {entry}{_WHAT.get(entry, '')}: {what} since wirecal wrote the patch; a "
        "patch is not edited by hand: write it again with wirecal solve … -o PATCH --force "
        "(docs/formats.md)"
        for entry, what in edits(data)
    ]
    if problems:
        raise WirecalError(problems)


def _compliance(table: Table, name: str) -> PatchValue | None:
    """Read one ``[compliance.<name>]`` table: a compliance c<j>, in µrad/(N·m)."""
    if not (name.startswith("c") and name[1:].isdigit()):
        table.add(name, "is not a compliance; name them c1, c2, …")
        return None
    return _value(table.table(name, _VALUE_KEYS), {"urad/Nm": "µrad/(N·m)"})


def _value(t: Table, units: dict[str, str] = P.UNIT_KINDS) -> PatchValue | None:
    unit = t.string("unit", choices=units)
    bound = MAX_DH_ANGLE_DEG if unit == "deg" else MAX_LENGTH_MM
    nominal, offset, value = (
        t.number(key, lo=-bound, hi=bound, unit=unit or "")
        for key in ("nominal", "offset", "value")
    )
    unidentified = t.present and t.data.get("std") == math.inf  # type: ignore[union-attr]
    std = math.inf if unidentified else t.number("std", None, lo=0, unit=unit or "")
    if unit is None or nominal is None or offset is None or value is None:
        return None
    if not math.isclose(value, nominal + offset, rel_tol=1e-9, abs_tol=1e-9):
        t.add(
            "value",
            f"is {value!r} but nominal + offset is {nominal + offset!r}: the patch was edited; "
            "write it again with wirecal solve",
        )
    return PatchValue(unit, nominal, offset, value, std)
