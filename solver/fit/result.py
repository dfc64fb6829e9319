"""``wirecal fit`` as a Python function: a table in, parameters, sessions and validation out.

:func:`fit_table` checks the table's units (:mod:`~wirecal.solver.fit.units`), cross-checks
the controller's x, y, z when given (:mod:`~wirecal.solver.fit.xyz`), fits
(:mod:`~wirecal.solver.fit.calibrate`), validates on held-out rows
(:mod:`~wirecal.solver.fit.holdout`), and, with ``refine_joints``, fits again from joints
refined from x, y, z (reported separately). The gate's verdict on each fit and its error
budget are :mod:`~wirecal.solver.fit.gate`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.cable_data import CableTable
from wirecal.solver.fit.calibrate import Core, Data, fit_core, holdout, nominal_floor, point_model
from wirecal.solver.fit.holdout import Holdout, copies, first_same, row_floor
from wirecal.solver.fit.sessions import MIN_SESSION_ROWS
from wirecal.solver.fit.units import check_columns, check_units
from wirecal.solver.fit.xyz import XyzCheck, check_xyz, refine_joints
from wirecal.solver.identify import Estimate
from wirecal.solver.kinematics import Model
from wirecal.solver.robot import Robot

MIN_ROWS = 20
"""Fewer rows than this cannot carry the anchor, the attachment, offsets and DH errors."""


@dataclass(frozen=True)
class FitOptions:
    """What ``wirecal fit`` is asked to do (its options)."""

    holdout: str = "random:0.2"
    repeats: int = 5
    seed: int = 0
    scale: bool = False
    single_session: bool = False
    refine_joints: bool = False
    joint_resolution_deg: float | None = None  # None: read off the table
    length_resolution_mm: float | None = None


@dataclass(frozen=True)
class Run:
    """One fit and its held-out validation."""

    core: Core
    holdout: Holdout
    floor_mm: float  # the floor's RMS over the inlier rows, at the estimate
    q_deg: np.ndarray  # the joints it was fitted from


@dataclass(frozen=True)
class FitResult:
    """Everything ``wirecal fit`` reports."""

    robot: Robot
    table: CableTable
    options: FitOptions
    resolution: tuple[float, float]  # joints (deg), length (mm)
    main: Run
    xyz: XyzCheck | None
    refined: Run | None

    @property
    def copies(self) -> tuple[tuple[int, int], ...]:
        """Return (row, the earlier row it copies) of each copied row (left out of the fit)."""
        return copies(self.table.q_deg, self.table.length_mm)

    def estimate(self, run: Run) -> Estimate:
        """Return a run's DH errors and attachment as a patch's estimate (deg, mm)."""
        core = run.core
        g = len(core.layout.geometry)
        per = core.layout.boundary_per_internal[:g]
        return Estimate(
            method="fit",
            names=core.layout.geometry,
            values=core.x[:g] * per,
            residual_rms_mm=core.sigma_mm,
            std=core.std[:g] * per,
        )


def _data(
    base: Model,
    q_deg: np.ndarray,
    table: CableTable,
    res: tuple[float, float],
    xyz: XyzCheck | None,
    cov: np.ndarray | None = None,
) -> Data:
    n = len(table.length_mm)
    excluded = np.zeros(n, dtype=bool)
    if xyz is not None:
        excluded[list(xyz.flagged)] = True
    excluded[[r for r, _ in copies(table.q_deg, table.length_mm)]] = True
    group = first_same(table.q_deg)
    session = np.zeros(n, dtype=int)
    data = Data(np.radians(q_deg), table.length_mm, session, 0.0, cov, excluded, group)
    return replace(data, floor_mm=nominal_floor(base, data, *res))


def _run(
    base: Model,
    data: Data,
    options: FitOptions,
    res: tuple[float, float],
    compliances: tuple[str, ...],
) -> Run:
    core = fit_core(
        base,
        data,
        scale=options.scale,
        single_session=options.single_session,
        compliances=compliances,
    )
    ho = holdout(
        base,
        core,
        data,
        options.holdout,
        repeats=options.repeats,
        seed=options.seed,
        resolution=res,
    )
    rows = core.inliers
    cov = None if data.joint_cov_rad2 is None else data.joint_cov_rad2[rows]
    f = row_floor(base, core.layout, core.x, data.q_rad[rows], *res, cov)
    return Run(core, ho, float(np.sqrt(np.mean(f**2))), np.degrees(data.q_rad))


MAX_RESOLUTION_RATIO = 10.0
"""A declared resolution at most this many times the table's own steps: a controller may
print more decimals than its counts resolve (a few times finer), never a hundred times."""


def _resolution(given: float | None, read: float, table: CableTable, what: str) -> float:
    """Return the resolution of ``what`` (joint deg, length mm): ``given``, or ``read``.

    A given one far coarser than the steps the table's values take inflates the
    quantisation floor the gate allows: refused.
    """
    if given is None:
        return read
    unit, option = (
        ("deg", "--joint-resolution-deg") if what == "joint" else ("mm", "--length-resolution-mm")
    )
    if given > MAX_RESOLUTION_RATIO * read:
        raise WirecalError(
            f"{table.source}: {option} {given:g}: the {what} values take steps of {read:g} "
            f"{unit}, more than {MAX_RESOLUTION_RATIO:g} times finer; a coarser resolution "
            "widens the quantisation floor the gate allows: leave it out (read off the "
            "values) or give the controller's own"
        )
    return given


def fit_table(robot: Robot, table: CableTable, options: FitOptions | None = None) -> FitResult:
    """Fit ``robot``'s cable model to ``table`` (module docstring); raise what blocks it."""
    options = options or FitOptions()
    if len(table.length_mm) < MIN_ROWS:
        raise WirecalError(
            f"{table.source}: {len(table.length_mm)} data rows; a fit needs at least {MIN_ROWS}"
        )
    if table.q_deg.shape[1] != robot.n_joints:
        raise WirecalError(f"{table.source}: joints for {table.q_deg.shape[1]}-joint arm")
    base = point_model(robot)
    check_columns(robot, table)
    check_units(base, table)
    res = (
        _resolution(options.joint_resolution_deg, table.joint_resolution_deg, table, "joint"),
        _resolution(options.length_resolution_mm, table.length_resolution_mm, table, "length"),
    )
    xyz = None
    if table.xyz_mm is not None and table.xyz_resolution_mm is not None:
        xyz = check_xyz(base, table.q_deg, table.xyz_mm, res[0], table.xyz_resolution_mm)
    asked = robot.compliances if base.masses is not None else ()  # point_model's rule
    main = _run(base, _data(base, table.q_deg, table, res, xyz), options, res, asked)
    _refuse_ignored_jumps(table, main.core, options)
    refined = None
    if options.refine_joints:
        if xyz is None or table.xyz_mm is None or table.xyz_resolution_mm is None:
            raise WirecalError(f"{table.source}: --refine-joints needs x, y, z columns (--map)")
        q, cov = refine_joints(
            base, xyz, table.q_deg, table.xyz_mm, res[0], table.xyz_resolution_mm
        )
        refined = _run(base, _data(base, q, table, res, xyz, cov), options, res, asked)
    return FitResult(robot, table, options, res, main, xyz, refined)


def copies_note(result: FitResult, shown: int = 10) -> str:
    """Return the line naming the rows that copy earlier rows ('' when none)."""
    pairs, t = result.copies, result.table
    if not pairs:
        return ""
    named = ", ".join(
        f"row {r} (line {int(t.lines[r])}) = row {f} (line {int(t.lines[f])})"
        for r, f in pairs[:shown]
    )
    more = f", … and {len(pairs) - shown} more" if len(pairs) > shown else ""
    return (
        f"copies (the joints and the length of an earlier row; left out of the fit, and a "
        f"held-out split keeps rows at the same joints on one side): {len(pairs)}: "
        f"{named}{more}; delete them unless they are repeated readings"
    )


def _refuse_ignored_jumps(table: CableTable, core: Core, options: FitOptions) -> None:
    """Refuse a fit whose residual still jumps (unless one session was asked for)."""
    if core.ignored_jumps and not options.single_session:
        where = ", ".join(f"row {r} ({table.where(r)})" for r in core.ignored_jumps)
        raise WirecalError(
            f"{table.source}: the residual still jumps at {where} after fitting an offset per "
            "session: the lengths do not follow one model; check the column map and the "
            "robot file, and whether the length sensor was re-zeroed every few rows (the fit "
            f"finds sessions of {MIN_SESSION_ROWS} rows or more; keep its zero between rows), "
            "or pass --single-session to fit one offset anyway"
        )


def parameters_json(run: Run) -> dict[str, Any]:
    """Return each parameter's unit, value (DH and attachment: the offset) and σ."""
    core = run.core
    per = core.layout.boundary_per_internal
    return {
        n: {"unit": u, "value": float(v), "std": float(s)}
        for n, u, v, s in zip(
            core.layout.names, core.layout.units, core.x * per, core.std * per, strict=True
        )
    }


def run_json(run: Run, table: CableTable, flagged: tuple[int, ...] = ()) -> dict[str, Any]:
    """Return one run's parameters, sessions, outliers and validation for ``--json``."""
    core = run.core
    outliers = np.flatnonzero(~core.inliers)
    k0 = len(core.layout.names) - core.layout.n_sessions
    return {
        "parameters": parameters_json(run),
        "dropped": [{"name": n, "reason": why} for n, why in core.dropped],
        "rank": core.identifiability.rank,
        "condition_O2": core.identifiability.indices["O2"],
        "sessions": list(core.starts[1:]),
        "session_lines": [int(table.lines[r]) for r in core.starts[1:]],
        "offsets_mm": [float(v) for v in core.x[k0:]],
        "ignored_jumps": list(core.ignored_jumps),
        "outliers": [
            {
                "row": int(r),
                "line": int(table.lines[r]),
                "residual_mm": float(core.residual_mm[r]),
                "xyz_disagrees": r in flagged,
            }
            for r in outliers
        ],
        "sigma_mm": core.sigma_mm,
        "holdout": run.holdout.as_json(),
        "floor_mm": run.holdout.floor_mm if run.holdout.rows else run.floor_mm,
        "fit_floor_mm": run.floor_mm,
    }


def result_json(result: FitResult) -> dict[str, Any]:
    """Return what ``wirecal fit --json`` prints (see docs/fit.md for the keys)."""
    t = result.table
    flagged = () if result.xyz is None else result.xyz.flagged
    data: dict[str, Any] = {
        "robot": result.robot.name,
        "table": t.source,
        "table_sha256": t.sha256,
        "rows": len(t.length_mm),
        "resolution": {"joint_deg": result.resolution[0], "length_mm": result.resolution[1]},
        "copies": [
            {"row": r, "line": int(t.lines[r]), "of_row": f, "of_line": int(t.lines[f])}
            for r, f in result.copies
        ],
        **run_json(result.main, t, flagged),
        "xyz": None,
        "refined": None if result.refined is None else run_json(result.refined, t, flagged),
    }
    if result.xyz is not None:
        x = result.xyz
        data["xyz"] = {
            "tcp_mm": x.tcp_mm.tolist(),
            "agreement_rms_mm": x.agreement_rms_mm,
            "flagged": [
                {
                    "row": r,
                    "line": int(t.lines[r]),
                    "disagreement_mm": float(x.disagreement_mm[r]),
                    "tolerance_mm": float(x.tolerance_mm[r]),
                }
                for r in x.flagged
            ],
        }
    return data
