"""The plausibility gate of ``wirecal fit``: which fit may be written, and why not.

:func:`assess_run` judges one fit (:class:`~wirecal.solver.fit.result.Run`):

* **residual** — σ of the final fit against σ_model = √(floor² + noise² + σ_a²) by the gate's
  χ² bound (:func:`~wirecal.solver.verdict.residual_limit_mm`); σ_a what the robot file's
  ``[calibration] repeatability_mm`` adds to a length (0 without it; ``solve``'s rule,
  :func:`~wirecal.solver.zero_reading.landing_sigma_mm`, through the fitted ∂L/∂q);
* **bound** — no DH error beyond :data:`~wirecal.solver.verdict.PLAUSIBLE_DEG` deg or
  :data:`~wirecal.solver.verdict.PLAUSIBLE_MM` mm;
* **holdout** — the held-out RMS at most :data:`HOLDOUT_FLOORS` times the quantisation
  floor (with σ_a: an arm's landing is no allowance but the arm's, at most 1 mm);
  ``--noise-mm`` does not move it, so no noise allowance makes a unit error pass (a joint
  in radians read as degrees: hundreds of floors);
* **budget** — the error budget (:func:`fit_budget`: the mean tool-point error over the
  workspace that the fit's own uncertainty predicts) below the correction it makes
  (:func:`correction_mm`: the mean over the same workspace of how far the fitted DH errors
  move the tool point). A patch less certain than its own size corrects nothing one can
  trust.

Identifiability holds by construction (every parameter chosen has its σ below the gate's
limit). :func:`gate_fit` chooses the fit to write: the one from refined joints when it
passes, else the one from the logged joints when that passes; with ``accept`` and none
passing, the refined (or only) one, the override recorded. Otherwise :class:`Implausible`
(exit 3, nothing written), each fit's findings first.

The budget's nuisance parameters (anchor, offsets, scale) are projected out of the
Jacobian first (Frisch–Waugh–Lovell: the DH block of J⁺ is the pseudo-inverse of the DH
columns less their projection on the nuisance columns), so the budget is the DH errors'
own; its sag term is the robot file's gravity sag at the fitted model, from the fitted
anchor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.accuracy import workspace
from wirecal.solver.budget import Budget, budget, sources
from wirecal.solver.errors import Implausible
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.fit.model import (
    geometry_jacobian,
    length_joint_gradient,
    lengths_and_jacobian,
    model_of,
)
from wirecal.solver.fit.result import FitResult, Run, copies_note
from wirecal.solver.fit.sessions import MIN_SESSION_ROWS
from wirecal.solver.kinematics import Model, tool_position, with_errors
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
from wirecal.solver.zero_reading import landing_sigma_mm

HOLDOUT_FLOORS = 10.0
"""A held-out RMS beyond this many quantisation floors is refused (module docstring)."""

ZERO_RUN_CORRELATION = 0.2
"""Successive rows' residuals correlated beyond this (and 4 standard errors, 4/√N) name a
length zero that moves every few rows: rows sharing an offset share their residual."""


@dataclass(frozen=True)
class Judged:
    """One fit with its error budget, the correction it makes and the gate's verdict."""

    label: str  # "fit" or "refined fit"
    run: Run
    budget: Budget
    correction_mm: float
    verdict: Plausibility


@dataclass(frozen=True)
class Gate:
    """The fit to write (``chosen``) and every fit judged, in the order reported."""

    chosen: Judged
    judged: tuple[Judged, ...]


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


def fit_budget(result: FitResult, run: Run) -> Budget:
    """Return the error budget of a fit's DH errors and attachment (module docstring)."""
    core, layout = run.core, run.core.layout
    base = point_model(result.robot)
    rows = np.flatnonzero(core.inliers)
    _, J = lengths_and_jacobian(
        base, layout, core.x, np.radians(run.q_deg[rows]), core.session[rows]
    )
    g = len(layout.geometry)
    J_geo = geometry_jacobian(J, g)
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


def correction_mm(robot: Robot, run: Run) -> float:
    """Return the mean over the workspace of how far the fitted DH errors move the tool point.

    At the robot file's tool point; the attachment (the wire's, not the tool's) is left out.
    """
    layout, x = run.core.layout, run.core.x
    dh = [k for k, n in enumerate(layout.geometry) if n not in P.TOOL_NAMES]
    base = point_model(robot)
    fitted = with_errors(base, [layout.geometry[k] for k in dh], x[dh])
    q = workspace(robot)
    moved = tool_position(fitted, q) - tool_position(base, q)
    return float(np.mean(np.linalg.norm(moved, axis=1)))


def _zero_runs(residual_mm: np.ndarray) -> str:
    """Return the finding's evidence of a zero that moves every few rows ('' if none).

    Rows in a run that shares an offset share their residual, so successive residuals
    correlate; unrelated rows' correlation is 0 ± 1/√N.
    """
    r = residual_mm - residual_mm.mean()
    n, power = len(r), float(r @ r)
    rho = float(r[:-1] @ r[1:]) / power if n > 2 and power > 0 else 0.0
    if rho < max(ZERO_RUN_CORRELATION, 4 / np.sqrt(n)):
        return ""
    return (
        f"; successive rows share their residual (correlation {rho:.2f}; unrelated rows "
        f"0 ± {1 / np.sqrt(n):.2f}): the length's zero moves every few rows (a sensor "
        "re-zeroed or re-mounted between rows), or the rows follow a path along which the "
        "model misfits"
    )


def _findings(
    result: FitResult, run: Run, budget_mm: float, moved_mm: float, limit: float, landing: float
):
    """Return the gate's findings on one fit (module docstring), the table's problems first."""
    core, ho = run.core, run.holdout
    out = []
    floor = float(np.hypot(ho.floor_mm, landing))
    if ho.rows and not ho.rms_mm <= HOLDOUT_FLOORS * floor:
        cols = ", ".join(
            repr(c) for c in (*result.table.columns.joints, result.table.columns.length)
        )
        arm = f" with the arm's repeatability {landing:.3g} mm (σ)" if landing else ""
        out.append(
            Finding(
                "holdout",
                f"the held-out RMS {ho.rms_mm:.4g} mm is {ho.rms_mm / floor:.0f} times the "
                f"quantisation floor {ho.floor_mm:.4g} mm{arm} (more than {HOLDOUT_FLOORS:g}): "
                "check the columns "
                f"{cols}: this robot's joints in degrees (its convention) and the cable length "
                "in mm read with the joints of its own row (rows not shifted)",
            )
        )
    if not core.sigma_mm <= limit:
        out.append(
            Finding(
                "residual",
                f"the residual σ {core.sigma_mm:.4g} mm exceeds {limit:.4f} mm, what the "
                f"quantisation floor {run.floor_mm:.4f} mm and the reading noise allow (χ²): "
                "the table does not fit this robot model; check the column map, the units "
                "and the robot file (a sensor noisier than --noise-mm: give its σ; a length "
                f"sensor re-zeroed every row or every few rows: offsets of runs shorter than "
                f"{MIN_SESSION_ROWS} rows cannot be fitted, keep its zero between rows)"
                + _zero_runs(core.residual_mm[core.inliers]),
            )
        )
    if budget_mm >= moved_mm:
        what = (
            f"is not below the correction it makes, {moved_mm:.3g} mm: these rows do not "
            "carry its parameters"
            if moved_mm > 0
            else "while it corrects nothing: no DH error is worth a parameter on these rows"
        )
        out.append(
            Finding(
                "budget",
                f"the error budget {budget_mm:.3g} mm (the tool-point error this fit's own "
                f"uncertainty predicts) {what}; take more rows in more varied poses (each "
                "joint moved widely) or a table with x, y, z (--refine-joints)",
            )
        )
    return out


def assess_run(
    result: FitResult, run: Run, label: str, noise_mm: float = READING_NOISE_MM
) -> Judged:
    """Return one fit's budget, correction and the gate's verdict (module docstring)."""
    core = run.core
    landing = _landing_mm(result, run)
    sigma_model = float(np.sqrt(run.floor_mm**2 + noise_mm**2 + landing**2))
    dof = int(core.inliers.sum()) - len(core.x)
    limit = residual_limit_mm(sigma_model, dof) if dof > 0 else float("inf")
    spent = fit_budget(result, run)
    moved = correction_mm(result.robot, run)
    findings = _findings(result, run, spent.total, moved, limit, landing)
    est = result.estimate(run)
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
    verdict = Plausibility(
        method="fit",
        findings=tuple(findings),
        noise_model_mm=sigma_model,
        residual_limit_mm=float(limit),
        residual_sigma_mm=core.sigma_mm,
        identifiability=core.identifiability,
        unidentified=(),
    )
    return Judged(label, run, spent, moved, verdict)


def _landing_mm(result: FitResult, run: Run) -> float:
    """Return σ_a, what the declared repeatability adds to a length (0 without the key).

    ``solve``'s rule (:func:`~wirecal.solver.zero_reading.landing_sigma_mm`) with the
    fitted model's ∂L/∂q (the wire from the fitted anchor) at the fit's rows.
    """
    r = result.robot.repeatability_mm
    if r is None:
        return 0.0
    core = run.core
    q = np.radians(run.q_deg[core.inliers])
    return landing_sigma_mm(
        length_joint_gradient(point_model(result.robot), core.layout, core.x, q), r
    )


def gate_fit(
    result: FitResult, *, accept: bool = False, noise_mm: float = READING_NOISE_MM
) -> Gate:
    """Return the fit to write and every fit judged; raise :class:`Implausible` (docstring)."""
    judged = [assess_run(result, result.main, "fit", noise_mm)]
    if result.refined is not None:
        judged.insert(0, assess_run(result, result.refined, "refined fit", noise_mm))
    passing = [j for j in judged if j.verdict.passed]
    if passing or accept:
        return Gate((passing or judged)[0], tuple(judged))
    copies = copies_note(result)
    raise Implausible(
        [
            *(
                f"{result.table.source}: {j.label}: {f.message}"
                for j in judged
                for f in j.verdict.findings
            ),
            *([f"{result.table.source}: {copies}"] if copies else []),
            "nothing was written: no fit passed the plausibility gate. To see the estimates "
            "anyway pass --accept-implausible (a patch written with it records the override)",
        ]
    )


def gate_json(gate: Gate) -> list[dict]:
    """Return each fit's verdict, budget and correction, and which one a patch holds."""
    return [
        {
            "fit": j.label,
            "chosen": j is gate.chosen,
            "passed": j.verdict.passed,
            "findings": [{"check": f.check, "message": f.message} for f in j.verdict.findings],
            "budget_mm": j.budget.total,
            "correction_mm": j.correction_mm,
        }
        for j in gate.judged
    ]
