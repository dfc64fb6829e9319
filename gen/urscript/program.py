"""``wirecal gen --language urscript``: the URScript programs, from ``templates/urscript``.

One ``.script`` file per role, each a single ``def … end`` program as the controller takes
it (:mod:`wirecal.gen.urscript.facts`, "script over port 30002"): ``wc_mount`` (move to θ0,
mount the encoder), ``wc_check`` (live counts in the log tab) and ``wc_run`` (the
measurement; sends the log to ``wirecal receive`` over TCP and mirrors every line with
``textmsg``). The output is deterministic: the same robot, plan, options and wirecal
version give the same bytes.

Units at the controller: ``movej`` takes radians, rad/s and rad/s² (UR e-Series Script
Directory §14.22); the joints read back with ``get_actual_joint_positions()`` are radians
and are written to the log in degrees, as every wirecal file holds them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from itertools import repeat
from pathlib import Path

import numpy as np

from wirecal import __version__
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import COLUMNS as LOG_COLUMNS
from wirecal.formats.log import COLUMNS_V1
from wirecal.formats.log import VERSION as LOG_VERSION
from wirecal.formats.run_token import run_token, token_line
from wirecal.gen.tables import STEP_ITERATIONS, Tables, build_tables
from wirecal.gen.targets import (
    flange_loads,
    give_move_speeds,
    joint_target,
    name_problems,
    payload_context,
    run_steps,
    stepwise_solver,
    tool_mass_problems,
)
from wirecal.gen.templating import render
from wirecal.gen.urscript.cb3 import (
    FILTERED_RANGE,
    is_cb3,
    leg_joints,
    leg_speeds_pct,
    move_legs,
)
from wirecal.lang.urscript import URScript
from wirecal.lang.urscript.versions import is_refusal, needed
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    MOVE_OVERHEAD_S,
    PAPER_RUN,
    READING_INTERVAL_S,
    RunParameters,
    run_timeline,
)

ROLES = ("mount", "check", "run")
"""The programs, one ``wc_<role>.script`` each."""

RAW_COUNTER_BITS = URScript.capabilities.counter_bits
"""The programs read the raw count, an int32 (SD §14.4): the robot file's counter_bits."""

MOVEJ_DEFAULT_ACCEL_RAD_S2 = 1.4
"""movej's default joint acceleration (SD §14.22): what ``--accel`` at its default gives."""


@dataclass(frozen=True)
class UrOptions:
    """Options of the generated URScript programs."""

    # the paper's speed (each move slower where the wire's limits ask for it, as V+'s and
    # RAPID's) and fixed settle: the URScript programs do not yet read the settle rule of
    # the V+ module (wirecal.solver.run_parameters)
    run: RunParameters = PAPER_RUN
    host: str | None = None  # the PC running 'wirecal receive' (default: the robot file's)
    port: int | None = None  # its port (default: the robot file's)
    zero_tol_mm: float = 0.1  # a zero reading further from the previous: the wire slipped
    spread_tol_mm: float = 0.1  # a point's samples spread wider: the robot still moved
    solver: bool = True  # wc_run ends with wc_solve, the controller's step-by-step solver


def rad_literal(q_deg: Iterable[float]) -> str:
    """Write a joint target (deg) as URScript's list of radians, 9 decimals (< 1e-6 deg)."""
    return "[" + ", ".join(_fixed(math.radians(x), 9) for x in q_deg) + "]"


def float_literal(x: float) -> str:
    """Write ``x`` as the nearest 32-bit float, with the fewest digits that give it back.

    The controller holds every float in 32 bits (UR16e manual p. 181), so more digits
    would not be read; always with a decimal point (a float literal, not an int).
    """
    return str(np.format_float_positional(np.float32(x), unique=True, trim="0"))


def _list(values: Iterable, literal=float_literal) -> str:
    """Write a URScript list literal."""
    return "[" + ", ".join(literal(v) for v in values) + "]"


OPS_PER_SYNC = 400
"""wc_solve calls sync() after fewer operations than this (pinned by the tests)."""

SOLVER_DECIMALS = 6
"""The offsets wc_solve writes: 6 decimals through an int32, so |offset| < 2147 deg/mm."""


def solver_tables(robot: Robot, plan: Plan, tables: Tables) -> dict[str, str]:
    """Return wc_solve's tables as URScript list literals (0-based, :mod:`gen.tables`).

    Joint angles enter as integers in 1e-4 deg (as the log writes them): the plan angle
    rounded (``qi``) and its remainder (``qf``), so the solver subtracts integers only.
    Raises :class:`WirecalError` if an offset's bound Ω could not be written through an
    int32 at :data:`SOLVER_DECIMALS` decimals.
    """
    bound = tables.errors.to_boundary(tables.omega)
    big = [n for n, b in zip(tables.names, bound, strict=True) if abs(b) * 10**6 >= 2**31]
    if big:
        raise WirecalError(
            f"{plan.source}: the bound of {', '.join(big)} is 2147 deg/mm or more: wc_solve "
            "writes offsets to 6 decimals through 32-bit integers; generate with --no-solver"
        )
    q4 = tables.qp * 10000
    qi = np.round(q4)
    n = tables.n
    out = {
        "ca": _list(tables.ca),
        "sa": _list(tables.sa),
        "la": _list(tables.la),
        "ld": _list(tables.ld),
        "tp": _list(tables.tool),
        "ct": _list(tables.ct.ravel()),
        "st": _list(tables.st.ravel()),
        "qi": _list(qi.ravel(), lambda v: str(int(v))),
        "qf": _list((q4 - qi).ravel()),
        "vn": _list(tables.vn.ravel()),
        "dn": _list(tables.dn),
        "dni": _list(tables.dni, lambda v: str(int(v))),
        "dnf": _list(tables.dnf),
        "first": _list(tables.first, lambda v: str(int(v))),
        "count": _list(tables.count, lambda v: str(int(v))),
        "spar": _list(tables.spar - 1, lambda v: str(int(v))),
        "om": _list(tables.omega),
        "pk": _list(tables.pk, lambda v: str(int(v))),
        "pr": _list(tables.pr - 1, lambda v: str(int(v))),
        "tb": _list(tables.errors.boundary_per_internal),
        "nom4": _list(np.round(tables.nominal * 10000), lambda v: str(int(v))),
        "pn": _list(tables.names, lambda v: f'"{v}"'),
        "pu": _list(tables.errors.units, lambda v: f'"{v}"'),
        "d2r4": float_literal(math.pi / 180 / 10000),
        "mpc": float_literal(tables.mpc),
        "zeros3n": _list([0.0] * 3 * n),
        "zerosn": _list([0.0] * n),
        "zerosm": _list([0.0] * len(tables.names)),
    }
    out["longest"] = str(max(len(f"    local {k} = {v}") for k, v in out.items()))
    out["most_ops"] = str(OPS_PER_SYNC)
    return out


def _payload(robot: Robot, plan: Plan) -> dict[str, object] | None:
    """Return the payload step for the templates: what the programs tell set_payload.

    set_payload(mass, CoG) sets the whole active payload (kg, CoG in m in the flange frame;
    :data:`~wirecal.lang.urscript.versions.PAYLOAD_ARTICLE`), and a program starts with the
    Installation's (the same article). On e-Series the program reads that payload when the
    step starts (``get_target_payload()``, ``get_target_payload_cog()``:
    :data:`~wirecal.lang.urscript.versions.PAYLOAD_READ`), declares it with the step's mass
    at their common centre (``moment_m``: the mass times its centre, kg·m, each a signed
    term, "+ 0.25") and restores it after: never less than the flange carries, whatever the
    robot file says; ``rated_kg``: the program refuses to move when that payload and the
    step's mass exceed the rating. Those calls are read on e-Series pages only, so on CB3
    the tool is the robot file's ``[gravity] payload_mass_kg`` at its ``payload_com_mm``
    (``total_kg``/``cog_m``, ``tool_kg``/``tool_cog_m`` after), and a robot file without it
    is refused.
    """
    ctx, step, loads = payload_context(robot, plan), plan.payload_step, flange_loads(robot, plan)
    if ctx is None or step is None or loads is None:
        return None
    if not is_cb3(robot.controller.software):
        moment = [step.payload_kg * x / 1000 for x in step.payload_com_mm]
        terms = [f"{'-' if m < 0 else '+'} {_fixed(abs(m), 9)}" for m in moment]
        return ctx | {"read": True, "moment_m": terms}
    problems = tool_mass_problems(
        robot,
        "a CB3 program's payload step declares it with the step's mass (set_payload), the "
        "Installation's payload being unreadable there (get_target_payload is read on "
        "e-Series pages only)",
    )
    if problems:
        raise WirecalError(problems)
    (total, cog), (tool_kg, tool_cog) = loads
    return ctx | {
        "read": False,
        "total_kg": f"{total:g}",
        "cog_m": _metres(cog),
        "tool_kg": f"{tool_kg:g}",
        "tool_cog_m": _metres(tool_cog),
    }


def _metres(v_mm: np.ndarray) -> str:
    """Return a point in mm as a URScript list in m."""
    return "[" + ", ".join(_fixed(x / 1000, 6) for x in v_mm) + "]"


def _fixed(x: float, digits: int) -> str:
    """Return ``x`` with at most ``digits`` decimals, no trailing zeros, never ``-0``."""
    s = f"{x:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _check(robot: Robot, opt: UrOptions) -> tuple[str, int]:
    """Return the PC's host and port; raise naming every rule the inputs break."""
    problems = opt.run.problems()
    enc = robot.encoder
    if enc.interface != "pulse":
        problems.append(
            f'{robot.source}: encoder.interface = "{enc.interface}": the URScript programs read '
            'the controller\'s pulse decoder; give interface = "pulse", channel (encoder '
            "index 0 or 1) and pulse_inputs (two digital inputs 8-11)"
        )
    if enc.counter_bits != RAW_COUNTER_BITS:
        problems.append(
            f"{robot.source}: encoder.counter_bits = {enc.counter_bits}: the URScript programs "
            f"log the raw count, an int32; give counter_bits = {RAW_COUNTER_BITS}"
        )
    problems += robot.program_problems()
    problems += name_problems(robot, '"\\', "a URScript string")
    host = opt.host or robot.controller.host
    port = opt.port or robot.controller.port
    if host is None:
        problems.append(
            f"{robot.source}: no PC address for the log: give [controller] host (the PC "
            "running 'wirecal receive', as the robot reaches it) or gen --host"
        )
    elif not all(33 <= ord(c) <= 126 and c not in '"\\' for c in host):
        problems.append(f"--host {host!r}: give an address or host name (printable, no spaces)")
    if port is None:
        problems.append(f"{robot.source}: no port for the log: give [controller] port or --port")
    elif not 1 <= port <= 65535:
        problems.append(f"--port {port}: give 1-65535")
    if problems:
        raise WirecalError(problems)
    return str(host), int(port)  # type: ignore[arg-type]


def scripts(robot: Robot, plan: Plan, opt: UrOptions = UrOptions()) -> dict[str, str]:
    """Return the programs by file name; raise :class:`WirecalError` if a rule would be broken.

    Rendering only: the plan's safety is the pre-flight's
    (:meth:`wirecal.gen.backends.Generator.programs`).
    """
    host, port = _check(robot, opt)
    opt = replace(opt, solver=stepwise_solver(plan, opt.solver))
    tables = build_tables(robot, plan)
    mpc = robot.encoder.mm_per_count
    speed_rad_s = _speed_rad_s(robot, opt.run.speed_pct)
    accel = _accel_rad_s2(opt.run)
    context: dict[str, object] = {
        "version": __version__,
        "robot": robot.name,
        "software": robot.controller.software,
        "fingerprint": plan.fingerprint(),
        "token_line": token_line(run_token(robot, plan.fingerprint())),
        "host": host,
        "port": port,
        "encoder": robot.encoder,
        "filtered_mm": _fixed(FILTERED_RANGE * abs(mpc), 1),
        "speed": f"{opt.run.speed_pct:g}",
        "speed_rad": _fixed(speed_rad_s, 6),
        "accel_rad": _fixed(accel, 6),
        "ramp_s": f"{MOVE_OVERHEAD_S:g} s",
        "settle": f"{opt.run.settle_s:g}",
        "settle_3": f"{opt.run.settle_s:.3f}",
        "interval": f"{READING_INTERVAL_S:g}",
        "samples": opt.run.readings,
        "deg_per_rad_1e4": _fixed(10000 * 180 / math.pi, 9),
        "mpc": repr(mpc),
        "mpc_1e4": _fixed(mpc * 10000, 9),
        "zero_tol": f"{opt.zero_tol_mm:g}",
        "spread_tol": f"{opt.spread_tol_mm:g}",
        "spread_counts": f"{np.floor(opt.spread_tol_mm / abs(mpc)):g}",
        "theta0": joint_target(plan.theta0_deg, rad_literal),
        "nsteps": len(plan.steps),
        "npoints": plan.n_points,
        "solver": opt.solver,
        "joint_only": plan.joint_only,
        "rd_zeros": _list([0] * 8 * (len(plan.steps) + plan.n_points), str),
        "nit": STEP_ITERATIONS,
        "n": tables.n,
        "m": len(tables.names),
        "payload": _payload(robot, plan),
    }
    steps = run_steps(plan, tables.first, rad_literal)
    legs = leg_joints(robot, plan) if is_cb3(robot.controller.software) else None
    context["closing"] = movej_speeds(robot, plan, opt.run, steps, legs)
    context |= line_context(steps, legs)
    if opt.solver:
        context["t"] = solver_tables(robot, plan, tables)
    return {f"wc_{role}.script": render(f"urscript/{role}.script.j2", **context) for role in ROLES}


def _speed_rad_s(robot: Robot, speed_pct: float) -> float:
    """Return movej's v (rad/s, leading axis) at ``speed_pct`` of the slowest joint's speed."""
    return math.radians(float(np.min(robot.joint_speed_deg_s))) * speed_pct / 100


def _accel_rad_s2(run: RunParameters) -> float:
    """Return the run's movej a (rad/s²): the default at ``--accel``'s default, in proportion."""
    return MOVEJ_DEFAULT_ACCEL_RAD_S2 * run.accel_pct / DEFAULT_RUN.accel_pct


def movej_speeds(
    robot: Robot,
    plan: Plan,
    run: RunParameters,
    steps: list[dict],
    legs: list[np.ndarray] | None = None,
) -> dict[str, str]:
    """Give every move of ``steps`` its movej v and a; return the closing move's.

    v: the run's speed unless the encoder's wire speed or acceleration asks for less
    (:func:`~wirecal.solver.run_parameters.run_timeline`'s speeds, the V+ and RAPID
    rule). a: the run's, at most v / ``MOVE_OVERHEAD_S``, so the leading axis's ramp
    (v/a of movej's trapezoid, SD §14.22) lasts at least the ramp the wire's acceleration
    was bounded with. Both rounded down to 6 decimals. A CB3 move cut into ``legs``
    (:func:`~.cb3.leg_joints`): the slowest leg's (each leg stops, :func:`~.cb3.leg_speeds_pct`).
    """
    run_a = _accel_rad_s2(run)

    def movej(pct: float) -> dict[str, str]:
        v = _down(_speed_rad_s(robot, pct))
        return {"v": _fixed(v, 6), "a": _fixed(_down(min(run_a, v / MOVE_OVERHEAD_S)), 6)}

    pct = run_timeline(robot, plan, run).speed_pct
    if legs is not None:  # θ0 first (in place), then run_moves' moves
        pct = np.r_[pct[:1], np.minimum(pct[1:], leg_speeds_pct(robot, plan, legs, run.speed_pct))]
    speeds = (movej(float(x)) for x in pct)
    return give_move_speeds(steps, speeds, "move")


def _down(x: float) -> float:
    """Return ``x`` rounded down to 6 decimals (a limit's value never rounds up)."""
    return math.floor(x * 1e6) / 1e6


def line_context(steps: list[dict], legs: list[np.ndarray] | None) -> dict[str, object]:
    """Return what the programs take from the declared product line (:mod:`.cb3` for CB3).

    ``steps`` (:func:`run_steps`) get each move's intermediate targets of its ``legs``
    (:func:`~.cb3.leg_joints`, in ``run_moves`` order; θ0 first, in place): none but on CB3.
    """
    cb3 = legs is not None
    targets = [[], *move_legs(legs, rad_literal)] if legs is not None else repeat([])
    home = give_move_speeds(steps, targets, "legs")
    return {
        "cb3": cb3,
        "clock": not cb3,
        "t0": "" if cb3 else ", t0",
        "needed": ".".join(map(str, needed(3 if cb3 else 5))),
        "log_version": 1 if cb3 else LOG_VERSION,
        "columns": ",".join(COLUMNS_V1 if cb3 else LOG_COLUMNS),
        "steps": steps,
        "closing_legs": home,
    }


def software_problems(robot: Robot, problems: list[str]) -> list[str]:
    """Return the refused calls among the checker's problems with the programs.

    ``problems``: ``wirecal lint --software``'s over the generated programs. A call the
    declared software is not documented to have is the user's problem: each rule once, at
    its first call (:mod:`wirecal.lang.urscript.versions`; none when ``[controller]
    software`` is not declared). Any other problem is a generator defect: raise
    :class:`WirecalError` saying so.
    """
    software = robot.controller.software
    seen: set[str] = set()
    refused, defects = [], []
    for problem in problems:
        where, _, why = problem.partition(": ")
        if not is_refusal(why):
            defects.append(problem)
        elif why not in seen:
            seen.add(why)
            refused.append(
                f'{robot.source}: controller.software = "{software}": {where}: {why}; '
                "wirecal knows no confirmed alternative: not generated"
            )
    if defects:
        head = "internal error: a generated program breaks a URScript rule (please report):"
        raise WirecalError([head, *defects[:20]])
    return refused


def write_scripts(
    out_dir: str | Path,
    programs: dict[str, str],
    force: bool = False,
    inputs: Iterable[str | Path] = (),
) -> list[Path]:
    """Write the programs into ``out_dir`` (LF line ends, SD "script over port 30002").

    All together or none; never over one of ``inputs``.
    """
    paths = [Path(out_dir) / name for name in programs]
    with Outputs(paths, force=force, inputs=inputs, folder=out_dir) as out:
        for path, text in zip(paths, programs.values(), strict=True):
            out.put(path, text)
    return paths


def pc_address(robot: Robot, opt: UrOptions = UrOptions()) -> tuple[str, int]:
    """Return where the programs send the log: the PC's (host, port), checked."""
    return _check(robot, opt)
