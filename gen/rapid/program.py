"""``wirecal gen`` for ABB RAPID: the module ``WIRECAL.mod`` from ``templates/rapid``.

One module with the routines the operator runs by "PP to Routine" (docs/rapid.md):
``wc_mount`` (MoveAbsJ to θ0, mount the encoder: TPReadNum), ``wc_check`` (live counts on
the FlexPendant) and ``wc_run`` (the measurement: MoveAbsJ through the θ0 checks, vias and
calibration points, settle, read the counter's group input with GInputDnum; the log written
to a file on the controller with Open/Write/Close and echoed with TPWrite in the format
``wirecal solve`` reads from a paste), ending with ``wc_solve``, the controller's
step-by-step solver (the port of templates/urscript/solve.script.j2). Deterministic: the
same robot, plan, options and wirecal version give the same bytes.

RAPID facts used are listed, with what is unconfirmed, in the module's own header
(templates/rapid/wirecal.mod.j2): no page of ABB's RAPID reference was read for them but
tooldata's (:data:`~wirecal.lang.rapid.tables.TOOLDATA_PAGE`: every move declares the tool's
own load, ``wc_tool``) and loaddata's (a payload plan's GripLoad,
:data:`~wirecal.lang.rapid.tables.LOADDATA_PAGE`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from wirecal import __version__
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import COLUMNS as LOG_COLUMNS
from wirecal.formats.log import VERSION as LOG_VERSION
from wirecal.gen.tables import STEP_ITERATIONS, Tables, build_tables
from wirecal.gen.targets import (
    give_move_speeds,
    joint_target,
    name_problems,
    payload_context,
    run_steps,
    stepwise_solver,
    tool_mass_problems,
)
from wirecal.gen.templating import render
from wirecal.lang.rapid.module import (
    GROUP_COUNTER_BITS,
    LOG_DIR,
    LOG_FILE,
    MODULE_FILE,
    dnum_literal,
    num_literal,
    signal_name,
)
from wirecal.lang.rapid.tables import STRING_MAX
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    PAPER_RUN,
    READING_INTERVAL_S,
    RunParameters,
    run_timeline,
)

EXTERNAL_AXES = "[9E+09, 9E+09, 9E+09, 9E+09, 9E+09, 9E+09]"
"""A jointtarget's extax for a robot without external axes (9E+09: not used)."""

V_TCP_MM_S = 250
"""wc_v's TCP speed (mm/s): high enough that the joints' v_ori cap leads (unconfirmed)."""


MAX_LINE = 200
"""The longest line the module may have (characters). Controllers loaded longer ones: 248 in
SDEBEUL/Kraker1@5a5835c RAPID/TASK1/PROGMOD/mStation.mod line 206 (an IRC5 backup), 231 in
COMPAS RRC's RRC_Control_Ctrl.sys line 293 (compas-rrc/compas_rrc_start@5d95af8, RobotWare
6); ABB's own limit is unconfirmed, so wirecal stays below every line seen loaded."""

AGGREGATE_WIDTH = 100
"""Characters of values on one line of a long aggregate (a table's line stays far within
:data:`MAX_LINE`)."""


@dataclass(frozen=True)
class RapidOptions:
    """Options of the generated RAPID module."""

    # the paper's one speed and fixed settle, as the URScript programs (MoveAbsJ ... fine
    # stops at the point; the settle rule of the V+ module is not ported)
    run: RunParameters = PAPER_RUN
    zero_tol_mm: float = 0.1  # a zero reading further from the previous: the wire slipped
    spread_tol_mm: float = 0.1  # a point's samples spread wider: the robot still moved
    solver: bool = True  # wc_run ends with wc_solve, the controller's step-by-step solver


def _aggregate(values: Iterable, literal=num_literal) -> str:
    """Write a RAPID aggregate ``[a, b, …]``, wrapped to lines of :data:`AGGREGATE_WIDTH`."""
    lines, line = [], ""
    for item in (literal(v) for v in values):
        if line and len(line) + len(item) + 2 > AGGREGATE_WIDTH:
            lines.append(line + ",")
            line = ""
        line = f"{line}, {item}" if line else item
    return "[" + "\n    ".join([*lines, line]) + "]"


def _matrix(rows: np.ndarray, literal=num_literal) -> str:
    """Write a 2-D array's aggregate, one row a line."""
    inner = ",\n    ".join(_aggregate(r, literal) for r in rows)
    return "[\n    " + inner + "]"


def _int(v: float) -> str:
    return str(int(v))


def _string(v: str) -> str:
    return f'"{v}"'


def jointtarget(q_deg: Iterable[float]) -> str:
    """Write a jointtarget: the six robot axes (deg, 4 decimals) and no external axes."""
    robax = ", ".join(_fixed(x, 4) for x in q_deg)
    return f"[[{robax}], {EXTERNAL_AXES}]"


def _fixed(x: float, digits: int) -> str:
    """Return ``x`` with at most ``digits`` decimals, no trailing zeros, never ``-0``."""
    s = f"{x:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def v_ori_deg_s(robot: Robot, speed_pct: float) -> str:
    """Return a speeddata's v_ori for ``speed_pct``: that share of the slowest joint's speed."""
    return _fixed(float(np.min(robot.joint_speed_deg_s)) * speed_pct / 100, 3)


def move_speeds(
    robot: Robot, plan: Plan, run: RunParameters, steps: list[dict]
) -> tuple[list[dict[str, str]], str]:
    """Give every move of ``steps`` its speeddata; return the slower ones, the closing move's.

    Each move at the run's speed (``wc_v``) unless the encoder's wire speed or acceleration
    asks for less (:func:`~wirecal.solver.run_parameters.run_timeline`'s speeds, the V+
    module's rule): those get a speeddata of their own, ``wc_v1``, ``wc_v2``… from the
    fastest down. The moves in the run's order: per step θ0, its vias, its points; last θ0.
    """
    speeds = [float(x) for x in run_timeline(robot, plan, run).speed_pct]
    slower = sorted({x for x in speeds if x < run.speed_pct}, reverse=True)
    names = {x: f"wc_v{k}" for k, x in enumerate(slower, 1)}
    closing = give_move_speeds(steps, (names.get(x, "wc_v") for x in speeds), "v")
    declared = [{"name": names[x], "v_ori": v_ori_deg_s(robot, x), "pct": f"{x:g}"} for x in slower]
    return declared, closing


def solver_tables(tables: Tables) -> dict[str, str]:
    """Return wc_solve's tables as RAPID aggregates (1-based, configuration 1 = θ0).

    The plan's angles and the nominal lengths in counts are dnum, so the readings'
    differences from them are exact; everything else is num.
    """
    return {
        "ca": _aggregate(tables.ca),
        "sa": _aggregate(tables.sa),
        "la": _aggregate(tables.la),
        "ld": _aggregate(tables.ld),
        "tp": _aggregate(tables.tool),
        "ct": _matrix(tables.ct),
        "st": _matrix(tables.st),
        "qp": _matrix(tables.qp, dnum_literal),
        "vn": _matrix(tables.vn),
        "dn": _aggregate(tables.dn),
        "dnc": _aggregate(tables.dn / tables.mpc, dnum_literal),
        "first": _aggregate(tables.first + 1, _int),
        "count": _aggregate(tables.count, _int),
        "spar": _aggregate(tables.spar, _int),
        "om": _aggregate(tables.omega),
        "pk": _aggregate(tables.pk, _int),
        "pr": _aggregate(tables.pr, _int),
        "tb": _aggregate(tables.errors.boundary_per_internal),
        "nom": _aggregate(tables.nominal),
        "pn": _aggregate(tables.names, _string),
        "pu": _aggregate(tables.errors.units, _string),
        "d2r": dnum_literal(math.pi / 180),
        "mpc": dnum_literal(tables.mpc),
    }


def _check(robot: Robot, opt: RapidOptions) -> None:
    """Raise naming every rule the inputs break."""
    problems = opt.run.problems()
    enc = robot.encoder
    if enc.interface != "group":
        problems.append(
            f'{robot.source}: encoder.interface = "{enc.interface}": the RAPID module reads '
            'the counter through a group input; give interface = "group"'
        )
    if enc.counter_bits != GROUP_COUNTER_BITS:
        problems.append(
            f"{robot.source}: encoder.counter_bits = {enc.counter_bits}: the RAPID module "
            f"reads a {GROUP_COUNTER_BITS}-bit group input (GInputDnum); give "
            f"counter_bits = {GROUP_COUNTER_BITS}"
        )
    problems += robot.program_problems()
    problems += tool_mass_problems(
        robot,
        "the RAPID module declares the load at the flange in every move (tooldata wc_tool)",
    )
    problems += name_problems(robot, '"\\', "a RAPID string")
    header = f"# robot: {robot.name}"  # the log's header line, one string in run.mod.j2
    if len(header) > STRING_MAX:
        problems.append(
            f"{robot.source}: name {robot.name!r}: {len(robot.name)} characters; the module logs "
            f"it in one string, '# robot: …', and a RAPID string holds {STRING_MAX}: shorten the "
            f"name to {STRING_MAX - len(header) + len(robot.name)} characters or fewer"
        )
    if problems:
        raise WirecalError(problems)


def module_text(robot: Robot, plan: Plan, opt: RapidOptions = RapidOptions()) -> str:
    """Return the module WIRECAL's text; raise :class:`WirecalError` if a rule would break.

    Rendering only: the plan's safety is the pre-flight's
    (:meth:`wirecal.gen.backends.Generator.programs`).
    """
    _check(robot, opt)
    opt = replace(opt, solver=stepwise_solver(plan, opt.solver))
    tables = build_tables(robot, plan)
    mpc = robot.encoder.mm_per_count
    bits = GROUP_COUNTER_BITS
    steps = run_steps(plan, tables.first, jointtarget)
    slower, closing_v = move_speeds(robot, plan, opt.run, steps)
    spread_counts = float(np.floor(opt.spread_tol_mm / abs(mpc)))  # the test's real size
    context = {
        "version": __version__,
        "robot": robot.name,
        "software": robot.controller.software,
        "fingerprint": plan.fingerprint(),
        "signal": signal_name(robot),
        "log_dir": LOG_DIR,
        "log_file": LOG_FILE,
        "log_path": f"{LOG_DIR}/{LOG_FILE}",
        "counter_bits": bits,
        "half_range": str(2 ** (bits - 1)),
        "full_range": str(2**bits),
        "v_tcp": V_TCP_MM_S,
        "v_ori": v_ori_deg_s(robot, opt.run.speed_pct),
        "slower": slower,
        "closing_v": closing_v,
        "settle": f"{opt.run.settle_s:g}",
        "settle_3": f"{opt.run.settle_s:.3f}",
        "log_version": LOG_VERSION,
        "columns": ",".join(LOG_COLUMNS),
        "interval": f"{READING_INTERVAL_S:g}",
        "samples": opt.run.readings,
        "mpc": repr(mpc),
        "zero_tol": f"{opt.zero_tol_mm:g}",
        "spread_counts": f"{spread_counts:g}",
        "spread_test": f"{spread_counts:g} counts ({spread_counts * abs(mpc):.3f} mm)",
        "theta0": joint_target(plan.theta0_deg, jointtarget),
        "steps": steps,
        "nsteps": len(plan.steps),
        "npoints": plan.n_points,
        "nreadings": len(plan.steps) + plan.n_points,
        "solver": opt.solver,
        "joint_only": plan.joint_only,
        "nit": STEP_ITERATIONS,
        "n": tables.n,
        "m": len(tables.names),
        "tool": _tool(robot),
        "payload": _payload(robot, plan),
    }
    if opt.solver:
        context["t"] = solver_tables(tables)
    text = render("rapid/wirecal.mod.j2", **context)
    _check_strings(text)
    return text


def _tool(robot: Robot) -> dict[str, str]:
    """Return ``wc_tool``'s tooldata: held by the robot, TCP the flange, the tool's load.

    :data:`~wirecal.lang.rapid.tables.TOOLDATA_PAGE`: robhold TRUE; tframe tool0's (the
    centre of the mounting flange, the wrist frame: the targets are jointtargets, so the
    TCP moves no path); tload the robot file's ``[gravity] payload_mass_kg`` at its
    ``payload_com_mm`` (the wrist frame), axes of moment [1, 0, 0, 0], inertia 0 (a
    point mass: the robot file gives none). 0 kg is refused
    (:func:`~wirecal.gen.targets.tool_mass_problems`).
    """
    masses = robot.masses
    assert masses is not None  # tool_mass_problems
    mass, cog = _fixed(masses.payload_mass_kg, 6), _mm(np.asarray(masses.payload_com_mm))
    return {
        "kg": mass,
        "cog_mm": cog,
        "tooldata": f"[TRUE, [[0, 0, 0], [1, 0, 0, 0]], [{mass}, {cog}, [1, 0, 0, 0], 0, 0, 0]]",
    }


def _payload(robot: Robot, plan: Plan) -> dict[str, object] | None:
    """Return the payload step for the templates, with GripLoad's loaddata (None without one).

    The loaddata (:data:`~wirecal.lang.rapid.tables.LOADDATA_PAGE`): the plan's mass alone,
    at its centre (mm; a payload's is in the tool frame, ``wc_tool``'s: the flange), axes
    of moment [1, 0, 0, 0] and inertia 0 (a point mass: the mass's own inertia is not in
    the plan). The tool's own load is ``wc_tool``'s tload, declared in every move: the
    tooldata page (:data:`~wirecal.lang.rapid.tables.TOOLDATA_PAGE`) has tload hold the
    tool's load only, the payload connected with GripLoad.
    """
    ctx = payload_context(robot, plan)
    step = plan.payload_step
    if ctx is None or step is None:
        return None
    centre, mass = _mm(np.asarray(step.payload_com_mm)), _fixed(step.payload_kg, 6)
    return ctx | {
        "centre_mm": centre,
        "loaddata": f"[{mass}, {centre}, [1, 0, 0, 0], 0, 0, 0]",
    }


def _mm(v_mm: np.ndarray) -> str:
    """Return a point in mm as a RAPID pos aggregate, 4 decimals (within 80 characters)."""
    return "[" + ", ".join(_fixed(x, 4) for x in v_mm) + "]"


def _check_strings(text: str) -> None:
    """Refuse a string literal over RAPID's 80 characters or a line over :data:`MAX_LINE`."""
    long = [
        f"{MODULE_FILE}:{n}: a string of more than {STRING_MAX} characters"
        for n, line in enumerate(text.splitlines(), 1)
        for piece in line.split('"')[1::2]
        if len(piece) > STRING_MAX
    ] + [
        f"{MODULE_FILE}:{n}: a line of {len(line)} characters (at most {MAX_LINE})"
        for n, line in enumerate(text.splitlines(), 1)
        if len(line) > MAX_LINE
    ]
    if long:
        raise WirecalError(["internal error: the generated module breaks a RAPID rule:", *long])


def line_ends(text: str, crlf: bool = True) -> str:
    """Return the module as it goes to the controller: CRLF line ends, or LF.

    RobotStudio, on Windows, writes modules with CRLF; whether the controller needs them is
    unconfirmed.
    """
    return text.replace("\n", "\r\n") if crlf else text


def write_module(
    out_dir: str | Path, text: str, *, crlf: bool = True, force: bool = False, inputs=()
) -> Path:
    """Write WIRECAL.mod into ``out_dir`` (created if missing); never over one of ``inputs``."""
    path = Path(out_dir) / MODULE_FILE
    with Outputs([path], force=force, inputs=inputs, folder=out_dir) as out:
        out.put(path, line_ends(text, crlf))
    return path
