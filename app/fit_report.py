"""Write ``wirecal fit --report``'s self-contained HTML page.

One page (Jinja2 template, matplotlib figures embedded as PNG, as ``wirecal report``): first
the plausibility verdict on each fit with why and its budget against its correction; then
the table and its resolution, the parameters with σ, the ones left out and why, the
sessions, the outliers, the held-out figures beside the quantisation floor, the x, y, z
cross-check, the refined fit, the error budget; figures of the residual row by row
(sessions and outliers marked) and of the inliers' residuals against the floor.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from wirecal.app.report import AFTER, BEFORE, _png
from wirecal.gen.templating import render
from wirecal.solver.fit.gate import Gate
from wirecal.solver.fit.result import FitResult, Run, parameters_json


def residual_figure(run: Run) -> str:
    """Plot the residual (model − measured) of every row; sessions and outliers marked."""
    core = run.core
    rows = np.arange(len(core.residual_mm))
    fig, ax = plt.subplots(figsize=(8, 3.2))
    ax.plot(rows[core.inliers], core.residual_mm[core.inliers], ".", ms=3, color=AFTER)
    out = ~core.inliers
    r = np.clip(core.residual_mm[out], -10 * core.sigma_mm, 10 * core.sigma_mm)
    ax.plot(rows[out], r, "x", color=BEFORE, label="outliers (clipped to ±10σ)")
    for s in core.starts[1:]:
        ax.axvline(s - 0.5, color="#444", lw=1, ls="--")
    ax.set_xlabel("data row (dashed: a new session starts)")
    ax.set_ylabel("model − measured (mm)")
    if out.any():
        ax.legend(loc="upper right", fontsize=8)
    return _png(fig)


def histogram_figure(run: Run) -> str:
    """Plot the inliers' residuals beside a normal of the quantisation floor's σ."""
    r = run.core.residual_mm[run.core.inliers]
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.hist(r, bins=40, density=True, color=AFTER, alpha=0.7, label="residuals (inliers)")
    x = np.linspace(r.min(), r.max(), 200)
    f = run.floor_mm
    ax.plot(
        x,
        np.exp(-0.5 * (x / f) ** 2) / (f * np.sqrt(2 * np.pi)),
        color=BEFORE,
        label=f"normal, σ = floor {f:.3f} mm",
    )
    ax.set_xlabel("model − measured (mm)")
    ax.legend(fontsize=8)
    return _png(fig)


def _run_context(run: Run) -> dict:
    core = run.core
    k0 = len(core.layout.names) - core.layout.n_sessions
    return {
        "run": run,
        "params": parameters_json(run),
        "offsets": core.x[k0:].tolist(),
        "outliers": np.flatnonzero(~core.inliers).tolist(),
        "figures": {"residuals": residual_figure(run), "histogram": histogram_figure(run)},
    }


def render_fit_report(result: FitResult, gate: Gate) -> str:
    """Render the fit's report as one self-contained HTML page, the gate's verdict first."""
    return render(
        "report/fit.html.j2",
        result=result,
        table=result.table,
        main=_run_context(result.main),
        refined=None if result.refined is None else _run_context(result.refined),
        gate=gate,
        budget=gate.chosen.budget,
    )
