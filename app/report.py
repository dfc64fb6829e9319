"""Write ``wirecal report``'s self-contained HTML page.

``wirecal report``: one self-contained HTML page (Jinja2 template, matplotlib figures
embedded as PNG) with the robot, the plan's Ψ per step, the per-step residuals, the
parameters with σ and correlations, step-by-step against joint (and the controller), and
the validation histograms before and after calibration.
"""

from __future__ import annotations

import base64
import io
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING, Any

import numpy as np

from wirecal.gen.templating import render
from wirecal.solver import params as P
from wirecal.solver.accuracy import tool_error, workspace
from wirecal.solver.compliance import workspace_sag
from wirecal.solver.kinematics import bends
from wirecal.solver.memo import Kept, digest
from wirecal.solver.solve import SolveResult
from wirecal.solver.validation.analysis import Stats, reduction
from wirecal.solver.verdict import OVERRIDDEN

if TYPE_CHECKING:
    from wirecal.app.compare import ControllerComparison

BEFORE, AFTER = "#d1495b", "#2e86ab"


KINDS = {
    "configuration": (
        "configuration change (§3.6.1)",
        "Maximum discrepancy among configurations (mm)",
        "Maximum discrepancy among the wire lengths at one pose in four configurations "
        "(paper Fig. 6).",
    ),
    "plane": (
        "plane fit (§3.6.2)",
        "Residuals of the plane fit (mm)",
        "Residuals of the plane fitted to the probed points (paper Fig. 7).",
    ),
    "distance": (
        "wire lengths at new points",
        "|measured − predicted wire length| (mm)",
        "Wire lengths measured in a second run at points not used for calibration, against "
        "those the nominal (before) and the calibrated (after) model predict.",
    ),
}
"""Validation procedures: their name, histogram axis and caption in the report."""


@dataclass(frozen=True)
class Validation:
    """Before/after statistics of one validation procedure."""

    kind: str  # a key of KINDS
    before: Stats
    after: Stats

    @property
    def title(self) -> str:
        """Return the procedure's name in the report's table."""
        return KINDS[self.kind][0]

    @property
    def axis(self) -> str:
        """Return the histogram's x label."""
        return KINDS[self.kind][1]

    @property
    def caption(self) -> str:
        """Return the histogram's caption."""
        return KINDS[self.kind][2]

    @property
    def reduction(self) -> dict[str, float | None]:
        """Return the reduction of each statistic from before to after calibration."""
        return reduction(self.before, self.after)


@cache
def _pyplot() -> Any:
    """Return matplotlib's pyplot on the Agg backend, imported when a figure is first drawn.

    The demo draws its figures in a worker process: its own process never imports it.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def ready_to_draw() -> None:
    """Import matplotlib now (a worker's idle time, before it is asked for figures)."""
    _pyplot()


DPI = 110
"""The figures' resolution (dots per inch)."""


def _png(fig) -> str:
    """Return ``fig`` as an embeddable PNG, cropped to its tight box, and close it.

    The PNG of ``savefig(bbox_inches="tight")``, byte for byte, drawn once: the tight box
    is measured at the figure's resolution as matplotlib measures it, without the layout
    pass it draws first (the figures have no layout engine for it to run).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig.set_dpi(DPI)
    renderer = FigureCanvasAgg(fig).get_renderer()
    pad = _pyplot().rcParams["savefig.pad_inches"]
    box = fig.get_tightbbox(renderer).padded(pad)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches=box)
    _pyplot().close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def psi_figure(result: SolveResult) -> str:
    """|Ψ| of every measured point (the Ψ ``solve`` computed), steps separated.

    Kept by what it shows (:mod:`~wirecal.solver.memo`): every run of one plan has the same
    Ψ, and the report of another run shows the figure drawn for the first, byte for byte.
    """
    shown = (np.abs(result.psi), result.step, result.plan.order, result.names)
    return _PSI_FIGURES.get(digest(*shown), lambda: _psi_png(*shown))


_PSI_FIGURES: Kept[str] = Kept(8)
"""The last Ψ figures (PNG data URIs, about 50 kB each)."""


def _psi_png(psi: np.ndarray, step: np.ndarray, order: Sequence[str], names: Sequence[str]) -> str:
    """Return :func:`psi_figure` drawn: |Ψ| (N, k), each point's step in ``order``, k names."""
    fig, ax = _pyplot().subplots(figsize=(7, 6.5))
    im = ax.imshow(psi, aspect="auto", cmap="magma_r", vmin=0)
    for b in np.flatnonzero(np.diff(step)) + 0.5:
        ax.axhline(b, color="white", lw=1.5)
    ax.set_xticks(range(len(names)), names)
    steps = [j for j in range(1, len(order) + 1) if np.any(step == j)]
    centres = [np.mean(np.flatnonzero(step == j)) for j in steps]
    ax.set_yticks(centres, [f"step {j}: {order[j - 1]}" for j in steps])
    ax.set_title("|Ψ| of every calibration point (mm/deg, mm/mm)")
    fig.colorbar(im, ax=ax, shrink=0.8)
    return _png(fig)


def residual_figure(result: SolveResult) -> str:
    """Plot the stepwise method's residuals per step; the figure as embeddable PNG."""
    steps = result.estimates["stepwise"].steps
    fig, ax = _pyplot().subplots(figsize=(7, 3))
    x = np.arange(len(steps))
    ax.bar(
        x - 0.2,
        [s.rms_before_mm for s in steps],
        0.4,
        color=BEFORE,
        label="before the step's estimate",
    )
    ax.bar(x + 0.2, [s.rms_after_mm for s in steps], 0.4, color=AFTER, label="after")
    ax.set_yscale("log")
    ax.set_xticks(x, [f"{j + 1}: {s.parameter}" for j, s in enumerate(steps)], rotation=30)
    ax.set_ylabel("residual RMS (mm)")
    ax.legend()
    ax.set_title("Step-by-step identification: each step's residuals")
    return _png(fig)


def correlation_figure(names: Sequence[str], correlation: np.ndarray) -> str:
    """Plot the joint estimate's parameter correlations; the figure as embeddable PNG."""
    fig, ax = _pyplot().subplots(figsize=(5, 4.3))
    im = ax.imshow(correlation, cmap="coolwarm", vmin=-1, vmax=1)
    ax.set_xticks(range(len(names)), names, rotation=45)
    ax.set_yticks(range(len(names)), names)
    ax.set_title("Joint estimate: correlations")
    fig.colorbar(im, ax=ax, shrink=0.8)
    return _png(fig)


def histogram_figure(v: Validation) -> str:
    """Plot a validation's before/after histogram; the figure as embeddable PNG."""
    fig, ax = _pyplot().subplots(figsize=(7, 3.2))
    hi = max(v.before.max, v.after.max)
    bins = np.linspace(0, hi * 1.02, 34).tolist()
    for s, colour, name in ((v.before, BEFORE, "Before"), (v.after, AFTER, "After")):
        ax.hist(
            s.values,
            bins=bins,
            color=colour,
            alpha=0.75,
            label=f"{name} calibration: mean = {s.mean:.3f} mm, std = {s.std:.3f} mm",
        )
    ax.set_xlabel(v.axis)
    ax.set_ylabel("Number of measurements")
    ax.legend()
    ax.grid(alpha=0.3)
    return _png(fig)


def sag_summary(result: SolveResult) -> dict[str, float] | None:
    """Return the calibrated arm's tool-point sag over the budget's workspace (mm).

    Before (uncompensated, as a controller applies the patch) and after compensating
    the identified compliances offline (what the file's values of the others leave), mean
    and largest over the 1,000 configurations; ``sigma``: the mean RMS tool-point error
    the identified compliances' σ leave in the compensation. None when the robot file
    asks for no compliance or the calibrated arm does not bend.
    """
    jt, comp = result.estimates.get("joint"), result.compliance
    if comp is None or jt is None:
        return None
    robot = result.robot
    model = robot.model(jt.as_dict())
    if not bends(model):
        return None
    q = workspace(robot)
    names = [n for n in jt.names if n in comp.identified]
    sag = workspace_sag(model, [P.parse(n, robot.n_joints).row for n in names], q)
    sigma = 0.0
    if names and jt.std is not None and jt.correlation is not None:
        k = [jt.names.index(n) for n in names]
        sd = robot.errors(names).to_internal(jt.std[k])
        sigma = tool_error(model, names, jt.correlation[np.ix_(k, k)] * np.outer(sd, sd), q).mean_mm
    return {
        "before_mean": float(sag.before_mm.mean()),
        "before_max": float(sag.before_mm.max()),
        "after_mean": float(sag.after_mm.mean()),
        "after_max": float(sag.after_mm.max()),
        "sigma": sigma,
    }


def result_figures(result: SolveResult) -> dict[str, str | None]:
    """Return the report's figures of the identification alone: Ψ, residuals, correlations.

    As embeddable PNGs (None: a figure the result has nothing for). They need no
    validation, so the demo draws them in another process while it validates.
    """
    sw, jt = result.estimates.get("stepwise"), result.estimates.get("joint")
    return {
        "psi": psi_figure(result),
        "residuals": residual_figure(result) if sw else None,
        "correlation": correlation_figure(jt.names, jt.correlation)
        if jt is not None and jt.correlation is not None
        else None,
    }


def histograms(validations: Sequence[Validation]) -> list[str]:
    """Return each validation's histogram (:func:`histogram_figure`), as embeddable PNGs."""
    return [histogram_figure(v) for v in validations]


def render_report(
    result: SolveResult,
    validations: Sequence[Validation] = (),
    controller: ControllerComparison | None = None,
    truth: dict[str, float] | None = None,
    plausibility: str = "",
    figures: dict[str, str | None] | None = None,
    drawn: Sequence[str] | None = None,
) -> str:
    """Render the report's HTML; ``plausibility`` the gate's verdict (a patch's field).

    ``figures``: :func:`result_figures` of ``result``, ``drawn``: :func:`histograms` of
    ``validations``, when drawn already.
    """
    robot, plan = result.robot, result.plan
    sw, jt = result.estimates.get("stepwise"), result.estimates.get("joint")
    params = []
    std = jt.std_by_name() if jt is not None else {}
    for name in result.listed:  # a partial log's parameters left at nominal: no estimate
        params.append(
            {
                "name": name,
                "unit": P.unit_of(name),
                "nominal": robot.nominal_value(name),
                "stepwise": sw.as_dict().get(name) if sw else None,
                "joint": jt.as_dict().get(name) if jt else None,
                "std": std.get(name),
                "identified": name not in std or bool(np.isfinite(std[name])),
                "controller": controller.stepwise.offsets.get(name) if controller else None,
                "polished": controller.polished.offsets.get(name)
                if controller and controller.polished
                else None,
                "truth": (truth or {}).get(name),
            }
        )
    return render(
        "report/report.html.j2",
        robot=robot,
        plan=plan,
        result=result,
        params=params,
        dh=robot.dh_deg(),
        steps=sw.steps if sw else [],
        controller=controller,
        truth=truth is not None,
        plausibility=plausibility.removeprefix(OVERRIDDEN),
        overridden=plausibility.startswith(OVERRIDDEN),
        figures=result_figures(result) if figures is None else figures,
        validations=[
            {"v": v, "figure": f}
            for v, f in zip(
                validations, histograms(validations) if drawn is None else drawn, strict=True
            )
        ],
        sag=sag_summary(result),
    )
