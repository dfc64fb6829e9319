"""``wirecal gen``: the V+ module for a robot and plan, rendered from ``templates/vplus``.

One module file (``WIRECAL.V2``) holds the operator's programs (``wc.mount``,
``wc.check``, ``wc.run``, ``wc.solve``, ``wc.solve2``, ``wc.patch``), their subroutines
and the data program with the solver's tables. The output is deterministic: the same
robot, plan, options and wirecal version give the same bytes.
"""

from __future__ import annotations

import textwrap
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal import __version__
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import COLUMNS as LOG_COLUMNS
from wirecal.formats.log import MAGIC as LOG_MAGIC
from wirecal.formats.log import VERSION as LOG_VERSION
from wirecal.gen.tables import JOINT_ITERATIONS, STEP_ITERATIONS, Tables, build_tables
from wirecal.gen.targets import (
    give_move_speeds,
    joint_literal,
    name_problems,
    payload_context,
    run_steps,
)
from wirecal.gen.templating import render
from wirecal.gen.vplus.literals import MAX_LINE, double_literal, long_lines, ppoint
from wirecal.lang.vplus.parser import parse_module
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    SAFE_SPEED_PCT,
    SETTLE_SPREAD_COUNTS,
    SETTLE_WINDOW,
    RunParameters,
    run_timeline,
)
from wirecal.solver.validation.design import CONFIGS, Setup, config_poses, plate_grid

MODULE_NAME = "WIRECAL.V2"
STRIDE = 8  # flattened index c*STRIDE + k (k ≤ 7): tables by configuration and joint
AXES = 4  # flattened index i*AXES + a (a = 1..3)
PROBE_MARGIN_MM = 2.0
"""After a contact, the touch probe's 1 mm search at the next grid point, a neighbour
(:func:`~wirecal.solver.validation.design.plate_grid`), starts this far above the depth found.
The plate is flat and the controller's error changes little over a grid step: in the
twin, before calibration with true errors of up to 1 deg/mm, neighbouring depths differ
by at most 0.3 mm. A probe already touching there goes back up to the approach height
and searches from it."""
PROBE_HALVINGS = 7
"""Halvings of the touch probe's last 1 mm step: contact found to 1/128 mm (0.0078 mm,
finer than the 0.01 mm of a search in 0.1 then 0.01 mm steps, in 8 moves instead of
about 20)."""


@dataclass(frozen=True)
class GenOptions:
    """Options of the generated module."""

    run: RunParameters = DEFAULT_RUN  # speed, acceleration, settle, readings
    zero_tol_mm: float = 0.1  # a zero reading further from the previous: the wire slipped
    spread_tol_mm: float = 0.1  # a point's samples spread wider: the robot still moved
    margin_deg: float = 1.0  # every generated target at least this far inside a limit
    log_file: str = "WCLOG.CSV"
    result_file: str = "WCSOLVE.CSV"
    patch: dict[str, float] | None = None  # identified offsets (deg, mm) for wc.patch
    patch_warning: str | None = None  # the patch's overridden plausibility gate, if so
    validation: Setup | None = None  # adds wc.vcfg and wc.vpln (paper §3.6)
    echo_log: bool = False  # wc.run also TYPEs each log line (a controller without a disk)
    crlf: bool = True  # CRLF line ends, as ACE writes V+ files (LF with gen --lf)


_SPELLED = {"θ": "theta", "σ": "sigma", "°": " deg", "–": "-", "…": "..."}


def _ascii_lines(text: str | None, width: int) -> list[str]:
    """Return ``text`` wrapped to ``width`` for V+ comments and TYPE strings.

    Printable ASCII only, without '"': θ, σ and ° spelled out, others become '?'.
    """
    if text is None:
        return []
    for symbol, spelled in _SPELLED.items():
        text = text.replace(symbol, spelled)
    clean = "".join(ch if 32 <= ord(ch) <= 126 and ch != '"' else "?" for ch in text)
    return textwrap.wrap(clean, width, break_on_hyphens=False)


def _check_options(robot: Robot, opt: GenOptions, tables: Tables) -> None:
    problems = opt.run.problems()
    for name in (opt.log_file, opt.result_file):
        stem, _, ext = name.partition(".")
        if not (
            1 <= len(stem) <= 8 and len(ext) <= 3 and stem.isalnum() and (ext.isalnum() or not ext)
        ):
            problems.append(f"controller file name {name!r}: use 8.3 letters and digits")
    if robot.encoder.interface == "device":
        problems.append(
            f'{robot.source}: encoder.interface = "device": DEVICE(0, unit, err, 1) returns '
            "scale*(count-offset) clamped to the limits SETDEVICE set (V+ User's Guide "
            "p. 354), not the raw count the log needs, and the SETDEVICE syntax that would "
            "set scale 1, offset 0 and wide limits is not confirmed from the manual; wire "
            'the encoder to a belt-encoder input and use interface = "belt"'
        )
    elif robot.encoder.interface != "belt":
        problems.append(
            f'{robot.source}: encoder.interface = "{robot.encoder.interface}" is read by the '
            "URScript programs (gen --language urscript); the V+ module reads a belt-encoder "
            'input: interface = "belt"'
        )
    problems += robot.program_problems()
    problems += name_problems(robot, '"', "a V+ string")
    bound = tables.errors.to_boundary(tables.omega)
    if np.any(bound > 16):
        problems.append(
            "a step's Ω exceeds 16 deg/mm: the controller prints offsets with 6 "
            "decimals in a REAL; lower omega"
        )
    if problems:
        raise WirecalError(problems)


PULLEY_TABLES = ("wc.wn", "wc.sn", "wc.tn")
"""With a guide pulley: each point's nominal w, s and t (:mod:`wirecal.solver.exit_geometry`)."""


def data_lines(t: Tables, robot: Robot) -> list[str]:
    """Return the assignments of ``wc.data``: every table value as an exact literal."""
    # powers of ten first: every DOUBLE literal below divides by one of them
    lines = [
        "wc.p10[0] = ^D1",
        "FOR k = 1 TO 22",
        "    wc.p10[k] = wc.p10[k-1]*10",
        "END",
        f"wc.d2r = {double_literal(np.pi / 180)}",
        f"wc.mpc = {double_literal(robot.encoder.mm_per_count)}",
    ]
    if t.pulley is not None:  # the guide pulley: radius and swivel axis
        lines.append(f"wc.pur = {double_literal(t.pulley.radius_mm)}")
        lines += [_put("wc.pax", a + 1, t.pulley.axis[a]) for a in range(3)]
    for k in range(t.n):
        for name, arr in (("wc.ca", t.ca), ("wc.sa", t.sa), ("wc.la", t.la), ("wc.ld", t.ld)):
            lines.append(_put(name, k + 1, arr[k]))
    lines += [_put("wc.tp", a + 1, t.tool[a]) for a in range(3)]
    for c in range(len(t.ct)):
        lines += _configuration_lines(t, c)
    for s in range(len(t.first)):
        lines += [
            f"wc.first[{s + 1}] = {int(t.first[s])}",
            f"wc.count[{s + 1}] = {int(t.count[s])}",
        ]
        if s < len(t.spar):  # a payload step (last) has no parameter
            lines += [f"wc.spar[{s + 1}] = {int(t.spar[s])}", _put("wc.om", s + 1, t.omega[s])]
    for j, (name, unit) in enumerate(zip(t.names, t.errors.units, strict=True)):
        lines += [
            f"wc.pk[{j + 1}] = {int(t.pk[j])}",
            f"wc.pr[{j + 1}] = {int(t.pr[j])}",
            f'$wc.pn[{j + 1}] = "{name}"',
            f'$wc.pu[{j + 1}] = "{unit}"',
            f"wc.nom4[{j + 1}] = {round(t.nominal[j] * 10000)}",
            _put("wc.tb", j + 1, t.errors.boundary_per_internal[j]),
        ]
    return lines


def _put(name: str, idx: int, value: float) -> str:
    return f"{name}[{idx}] = {double_literal(value)}"


def _configuration_lines(t: Tables, c: int) -> list[str]:
    """Return the table values of configuration ``c`` (0 is theta0, which has no wire data)."""
    lines = [f"; configuration {c}" + (" (theta0)" if c == 0 else "")]
    for k in range(t.n):
        idx = c * STRIDE + k + 1
        lines += [
            _put("wc.ct", idx, t.ct[c, k]),
            _put("wc.st", idx, t.st[c, k]),
            _put("wc.qp", idx, t.qp[c, k]),
        ]
    if c:
        lines += [_put("wc.vn", c * AXES + a + 1, t.vn[c, a]) for a in range(3)]
        lines += [
            _put("wc.dn", c, t.dn[c]),
            _put("wc.dni", c, t.dni[c]),
            _put("wc.dnf", c, t.dnf[c]),
        ]
        if t.bend is not None:
            lines += [_put(name, c, t.bend[c, k]) for k, name in enumerate(PULLEY_TABLES)]
    return lines


def module_text(robot: Robot, plan: Plan, opt: GenOptions = GenOptions()) -> str:
    """Return the whole V+ module; raise :class:`WirecalError` if a rule would be broken.

    Rendering only: the plan's safety is the pre-flight's
    (:meth:`wirecal.gen.backends.Generator.programs`).
    """
    tables = build_tables(robot, plan)
    _check_options(robot, opt, tables)
    _check_printable(robot, tables)
    steps = run_steps(plan, tables.first, ppoint)
    speeds = (_num(x) for x in run_timeline(robot, plan, opt.run).speed_pct)
    closing_speed = give_move_speeds(steps, speeds, "speed")  # each move's SPEED
    patch = _patch_literals(plan, tables, opt.patch)
    fp = plan.fingerprint()
    text = render(
        "vplus/wirecal.v2.j2",
        version=__version__,
        robot=robot.name,
        fingerprint=fp,
        fp_a=fp[:32],
        fp_b=fp[32:],
        n=robot.n_joints,
        nsteps=len(plan.steps),
        npoints=plan.n_points,
        m=len(plan.order),
        stride=STRIDE,
        axes=AXES,
        closing_speed=closing_speed,
        wire_limits=_wire_limits(robot),
        log_file=opt.log_file,
        log_magic=f"{LOG_MAGIC} {LOG_VERSION}",
        log_columns=",".join(LOG_COLUMNS),
        result_file=opt.result_file,
        theta0=ppoint(plan.theta0_deg),
        steps=steps,
        data=data_lines(tables, robot),
        nit=STEP_ITERATIONS,
        njit=JOINT_ITERATIONS,
        patch=patch,
        patch_warning=_ascii_lines(opt.patch_warning, MAX_LINE - 16),  # in a TYPE string
        names=list(plan.order),
        v=_validation_context(robot, opt),
        echo=opt.echo_log,
        pulley=tables.pulley is not None,
        payload=payload_context(robot, plan),
        solver=not plan.joint_only,  # a pool's plan: the stepwise solver does not apply
        **_run_context(opt),
        **_encoder_context(robot, opt),
    )
    _check_module(text)
    return text


def _check_printable(robot: Robot, tables: Tables) -> None:
    """Refuse a nominal value the controller's SPEC table cannot print (±1677 mm/deg)."""
    if np.any(np.abs(tables.nominal) * 10000 >= 2**24):
        raise WirecalError(
            f"{robot.source}: a nominal value of {tables.names} is beyond "
            "±1677 mm/deg; the controller's SPEC table cannot print it"
        )


def _patch_literals(plan: Plan, tables: Tables, patch: dict[str, float] | None) -> list[str] | None:
    """Return the patch's values as V+ literals in the plan's order (internal units).

    Refuses a patch with parameters beyond the plan's order (a plan from a pool is solved
    for every DH error and the attachment): wc.patch types the plan's alone, and part of
    a fit entered in SPEC is not the fit.
    """
    if patch is None:
        return None
    missing = [n for n in plan.order if n not in patch]
    if missing:
        raise WirecalError(f"patch: no value for {', '.join(missing)}")
    beyond = [n for n in patch if n not in plan.order]
    if beyond:
        raise WirecalError(
            f"patch: holds {', '.join(beyond)} beyond the plan's parameters "
            f"({', '.join(plan.order)}), and wc.patch types the plan's alone: entering part "
            "of a fit is not the fit. Enter every value from the .spec.txt file 'wirecal solve "
            "-o' wrote beside the patch, or generate without --patch"
        )
    return [double_literal(x) for x in tables.errors.to_internal([patch[n] for n in plan.order])]


def _run_context(opt: GenOptions) -> dict[str, object]:
    """Return the template's run settings: speeds, acceleration, settling, samples, tolerances."""
    return {
        "speed": _num(min(SAFE_SPEED_PCT, opt.run.speed_pct)),
        "speed_cap": _num(opt.run.speed_pct),
        "accel": _num(opt.run.accel_pct),
        "settle": _num(opt.run.settle_s),
        "settle_max": _num(opt.run.settle_max_s),
        "settle_window": SETTLE_WINDOW,
        "settle_counts": SETTLE_SPREAD_COUNTS,
        "samples": opt.run.readings,
        "zero_tol": _num(opt.zero_tol_mm),
        "margin": _num(opt.margin_deg),
        "spread_tol": _num(opt.spread_tol_mm),
    }


def _encoder_context(robot: Robot, opt: GenOptions) -> dict[str, object]:
    """Return the template's encoder settings: resolution, counter and the spread in counts."""
    enc = robot.encoder
    return {
        "spread_counts": _num(np.floor(opt.spread_tol_mm / abs(enc.mm_per_count))),
        "mpc": repr(enc.mm_per_count),
        "bits": enc.counter.bits,
        "half": enc.counter.half,
        # 2^24 is beyond the integer range (UG p. 102): written as a real, which holds it
        "full": f"{enc.counter.full}.0",
        "encoder": enc,
    }


def _check_module(text: str) -> None:
    """Refuse a module that breaks a V+ rule: a generator defect, never the user's."""
    problems = long_lines(text, MODULE_NAME)
    try:
        parse_module(text, MODULE_NAME)
    except WirecalError as exc:
        problems += exc.problems
    if problems:  # a generator defect, never the user's: say so plainly
        raise WirecalError(
            [
                "internal error: the generated module breaks a V+ rule (please report):",
                *problems[:20],
            ]
        )


def _validation_context(robot: Robot, opt: GenOptions) -> dict | None:
    setup = opt.validation
    if setup is None:
        return None
    poses = config_poses(robot, setup, opt.margin_deg)
    index, _, targets = plate_grid(robot, setup, opt.margin_deg)
    fp = setup.fingerprint()

    def args(values):
        return ", ".join(joint_literal(x) for x in values)

    return {
        "poses": [args(p) for p in poses],
        "configs": [(a.upper(), f.upper()) for a, f in CONFIGS],
        "grid_points": [(i, j, args(t)) for (i, j), t in zip(index, targets, strict=True)],
        "grid": setup.grid,
        "encoder": args(setup.encoder_mm),
        "probe": args(setup.probe_mm),
        "signal": setup.signal,
        "approach": _num(setup.approach_mm),
        "coarse_steps": int(np.ceil(2 * setup.approach_mm)),
        # after a contact, the next search starts this far above the depth found
        "margin": _num(min(PROBE_MARGIN_MM, setup.approach_mm)),
        "halvings": PROBE_HALVINGS,
        "fp_a": fp[:32],
        "fp_b": fp[32:],
    }


def _wire_limits(robot: Robot) -> str:
    """Return the encoder's wire limits in words, for the generated comment."""
    enc = robot.encoder
    parts = [
        f"{value:g} {unit}"
        for value, unit in (
            (enc.max_wire_speed_mm_s, "mm/s"),
            (enc.max_wire_accel_mm_s2, "mm/s2"),
        )
        if value is not None
    ]
    return " and ".join(parts) if parts else "no limit (the robot file gives none)"


def _num(x: float) -> str:
    return f"{x:g}"


def line_ends(text: str, crlf: bool = True) -> str:
    """Return the module as it goes to the controller.

    CRLF line ends (ACE writes V+ files so; whether LOAD accepts LF-only is not confirmed),
    or LF.
    """
    return text.replace("\n", "\r\n") if crlf else text


def write_module(
    out_dir: str | Path,
    text: str,
    force: bool = False,
    inputs: Iterable[str | Path] = (),
    crlf: bool = True,
) -> Path:
    """Write the module into ``out_dir``; never over one of ``inputs``.

    The module is LF text, as :func:`module_text` returns it, written with
    :func:`line_ends` (the folder created if missing, and removed again if the write
    fails).
    """
    path = Path(out_dir) / MODULE_NAME
    with Outputs([path], force=force, inputs=inputs, folder=out_dir) as out:
        out.put(path, line_ends(text, crlf))
    return path
