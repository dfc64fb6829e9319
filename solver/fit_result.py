"""``wirecal fit`` as a Python function: a table in, parameters, sessions and validation out.

:func:`fit_table` checks the table's units (:mod:`~wirecal.solver.fit_units`), cross-checks
the controller's x, y, z when given (:mod:`~wirecal.solver.fit_xyz`), fits
(:mod:`~wirecal.solver.fit`), validates on held-out rows
(:mod:`~wirecal.solver.fit_holdout`), and, with ``refine_joints``, fits again from joints
refined from x, y, z (reported separately). :func:`assess_fit` is the plausibility gate's
verdict on it and :func:`fit_budget` its error budget (:mod:`~wirecal.solver.budget`): the
nuisance parameters (anchor, offsets, scale) are projected out of the Jacobian first
(Frisch–Waugh–Lovell: the DH block of J⁺ is the pseudo-inverse of the DH columns less
their projection on the nuisance columns), so the budget is the DH errors' own; its sag
term is the robot file's gravity sag at the fitted model, from the fitted anchor.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from wirecal.solver.accuracy import workspace
from wirecal.solver.budget import Budget, budget, sources
from wirecal.solver.cable_data import CableTable
from wirecal.solver.errors import Implausible, WirecalError
from wirecal.solver.fit import Core, Data, fit_core, holdout, nominal_floor, point_model
from wirecal.solver.fit_holdout import Holdout, copies, first_same, row_floor
from wirecal.solver.fit_model import lengths_and_jacobian, model_of
from wirecal.solver.fit_units import check_units
from wirecal.solver.fit_xyz import XyzCheck, check_xyz, refine_joints
from wirecal.solver.identify import Estimate
from wirecal.solver.kinematics import Model
from wirecal.solver.robot import Robot
from wirecal.solver.scale import PPM
from wirecal.solver.simulate import sagged_tool_points
from wirecal.solver.verdict import (
    PLAUSIBLE_DEG,
    PLAUSIBLE_MM,
    READING_NOISE_MM,
    Finding,
    Plausibility,
    implausible,
    residual_limit_mm,
)

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

    @property
    def best(self) -> Run:
        """Return the run the patch is written from: the refined one when asked for."""
        return self.refined or self.main

    def estimate(self) -> Estimate:
        """Return the DH errors and the attachment as a patch's estimate (deg, mm)."""
        core = self.best.core
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


def _run(base: Model, data: Data, options: FitOptions, res: tuple[float, float]) -> Run:
    core = fit_core(base, data, scale=options.scale, single_session=options.single_session)
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
    check_units(base, table)
    res = (
        options.joint_resolution_deg or table.joint_resolution_deg,
        options.length_resolution_mm or table.length_resolution_mm,
    )
    xyz = None
    if table.xyz_mm is not None and table.xyz_resolution_mm is not None:
        xyz = check_xyz(base, table.q_deg, table.xyz_mm, res[0], table.xyz_resolution_mm)
    main = _run(base, _data(base, table.q_deg, table, res, xyz), options, res)
    _refuse_ignored_jumps(table, main.core, options)
    refined = None
    if options.refine_joints:
        if xyz is None or table.xyz_mm is None or table.xyz_resolution_mm is None:
            raise WirecalError(f"{table.source}: --refine-joints needs x, y, z columns (--map)")
        q, cov = refine_joints(
            base, xyz, table.q_deg, table.xyz_mm, res[0], table.xyz_resolution_mm
        )
        refined = _run(base, _data(base, q, table, res, xyz, cov), options, res)
    return FitResult(robot, table, options, res, main, xyz, refined)


def _refuse_ignored_jumps(table: CableTable, core: Core, options: FitOptions) -> None:
    """Refuse a fit whose residual still jumps (unless one session was asked for)."""
    if core.ignored_jumps and not options.single_session:
        where = ", ".join(f"row {r} ({table.where(r)})" for r in core.ignored_jumps)
        raise WirecalError(
            f"{table.source}: the residual still jumps at {where} after fitting an offset per "
            "session: the lengths do not follow one model; check the column map and the "
            "robot file, or pass --single-session to fit one offset anyway"
        )


def assess_fit(result: FitResult, noise_mm: float = READING_NOISE_MM) -> Plausibility:
    """Return the plausibility gate's verdict on a fit: residual and plausible sizes.

    Residual: σ of the final fit against σ_model = √(floor² + noise²) by the gate's χ² bound
    (:func:`~wirecal.solver.verdict.residual_limit_mm`); sizes: no DH error beyond
    :data:`PLAUSIBLE_DEG` deg or :data:`PLAUSIBLE_MM` mm. Identifiability holds by
    construction (every parameter chosen has its σ below the gate's limit).
    """
    run = result.best
    core = run.core
    sigma_model = float(np.hypot(run.floor_mm, noise_mm))
    dof = int(core.inliers.sum()) - len(core.x)
    limit = residual_limit_mm(sigma_model, dof)
    findings = []
    if dof > 0 and not core.sigma_mm <= limit:
        findings.append(
            Finding(
                "residual",
                f"the residual σ {core.sigma_mm:.4g} mm exceeds {limit:.4f} mm, what the "
                f"quantisation floor {run.floor_mm:.4f} mm and reading noise {noise_mm:g} mm "
                f"allow (χ², {dof} degrees of freedom): the table does not fit this robot "
                "model (a noisier sensor: --noise-mm)",
            )
        )
    est = result.estimate()
    dh = [not n.startswith("tool_") for n in est.names]  # the attachment is fitted freely
    huge = implausible([n for n, d in zip(est.names, dh, strict=True) if d], est.values[dh])
    if huge:
        findings.append(
            Finding(
                "bound",
                f"estimates beyond a physically plausible size ({PLAUSIBLE_DEG:g} deg, "
                f"{PLAUSIBLE_MM:g} mm): {', '.join(huge)}: the robot file or the table is wrong",
            )
        )
    return Plausibility(
        method="fit",
        findings=tuple(findings),
        noise_model_mm=sigma_model,
        residual_limit_mm=float(limit),
        residual_sigma_mm=core.sigma_mm,
        identifiability=core.identifiability,
        unidentified=(),
    )


def gate_fit(result: FitResult, *, accept: bool = False, noise_mm: float = READING_NOISE_MM):
    """Return :func:`assess_fit`'s verdict; raise :class:`Implausible` unless passed/accepted."""
    verdict = assess_fit(result, noise_mm)
    if verdict.passed or accept:
        return verdict
    raise Implausible(
        [
            *(f"{result.table.source}: {f.message}" for f in verdict.findings),
            "nothing was written: this fit is not plausible; check the column map, the units "
            "and the robot file. To see the estimates anyway pass --accept-implausible (a "
            "patch written with it records the override)",
        ]
    )


def _sag_mm(
    robot: Robot,
    model: Model,
    parts: tuple[np.ndarray, np.ndarray, float, np.ndarray],
    q_deg: np.ndarray,
) -> np.ndarray:
    """Return what the robot file's gravity sag adds to each row's length at the fit (mm).

    The sag of :func:`~wirecal.solver.simulate.sagged_tool_points` at the fitted model, the
    wire from the fitted anchor, times the fitted scale (1 + κ).
    """
    _, anchor, kappa, _ = parts
    p, sagged = sagged_tool_points(robot, model, q_deg)
    extra = np.linalg.norm(sagged - anchor, axis=1) - np.linalg.norm(p - anchor, axis=1)
    return (1 + kappa) * extra


def fit_budget(result: FitResult) -> Budget:
    """Return the error budget of the DH errors and attachment (module docstring)."""
    run = result.best
    core, layout = run.core, run.core.layout
    base = point_model(result.robot)
    rows = np.flatnonzero(core.inliers)
    _, J = lengths_and_jacobian(
        base, layout, core.x, np.radians(run.q_deg[rows]), core.session[rows]
    )
    g = len(layout.geometry)
    nuisance = J[:, g:]
    J_geo = J[:, :g] - nuisance @ np.linalg.lstsq(nuisance, J[:, :g], rcond=None)[0]
    enc = result.robot.encoder
    model = model_of(base, layout, core.x)
    src = sources(
        sigma_mm=core.sigma_mm,
        lengths_mm=result.table.length_mm[rows],
        scale_std=enc.scale_tolerance_ppm * PPM,
        measured_scale=False,
        drum_ppm_per_k=enc.temperature_coefficient_ppm_per_k,
        t_s=None,
        drift=None,
        t_zero_ref_s=None,
        exit_mm=np.zeros(len(rows)),
        sag_mm=_sag_mm(result.robot, model, layout.split(core.x), run.q_deg[rows]),
    )
    return budget(model, layout.geometry, J_geo, None, src, workspace(result.robot))


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
