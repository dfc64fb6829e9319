"""The text ``wirecal solve`` prints.

The estimates side by side, the predicted accuracy, the encoder's scale and drift, the error
budget, the steps, and the controller solver's run in the twin.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.exit_geometry import describe

if TYPE_CHECKING:
    from wirecal.app.compare import ControllerComparison
    from wirecal.solver.identify import Estimate
    from wirecal.solver.solve import SolveResult
    from wirecal.solver.solve_pool import PriorFit


def controller_text(ctl: ControllerComparison) -> str:
    """Return the controller solver's estimates beside the Python reference as text."""
    if ctl.polished is None:
        return _stepwise_controller_text(ctl)
    lines = [
        "",
        f"Controller solver (the generated {ctl.language} run in the digital twin):",
        f"{'parameter':<10}{'wc.solve':>12}{'wc.solve2':>12}",
    ]
    for name, value in ctl.stepwise.offsets.items():
        lines.append(f"{name:<10}{value:12.4f}{ctl.polished.offsets[name]:12.4f}")
    lines.append(
        f"largest difference from the Python reference: "
        f"{ctl.stepwise_max_difference:.2g} (stepwise), "
        f"{ctl.polished_max_difference:.2g} (joint) deg/mm; "
        f"{ctl.stepwise.total_operations:,} and {ctl.polished.total_operations:,} "
        "arithmetic operations"
    )
    return "\n".join(lines)


def _stepwise_controller_text(ctl: ControllerComparison) -> str:
    """Return a controller solver's estimates of one method (step by step) as text."""
    run = ctl.stepwise
    lines = [
        "",
        f"Controller solver (the generated {ctl.language} {run.program} run in the digital "
        f"twin, {ctl.float_bits}-bit floats):",
        f"{'parameter':<10}{run.program:>12}",
    ]
    lines += [f"{name:<10}{value:12.6f}" for name, value in run.offsets.items()]
    syncs = (
        f", {run.syncs:,} sync() (at most {run.most_between_syncs} operations between two)"
        if run.syncs
        else ""
    )
    lines.append(
        f"largest difference from the Python reference (stepwise): "
        f"{ctl.stepwise_max_difference:.2g} deg/mm; {run.total_operations:,} arithmetic "
        f"operations{syncs}"
    )
    return "\n".join(lines)


def _sigma(std: float) -> str:
    """σ of the joint estimate, or that the points do not identify the parameter."""
    return f"{std:14.4f}" if np.isfinite(std) else f"{'unidentifiable':>16}"


def _mm(value: float) -> str:
    """Return a predicted error (mm), or that it is unbounded."""
    return f"{value:12.4f}" if np.isfinite(value) else f"{'unbounded':>12}"


def _encoder_text(result: SolveResult) -> list[str]:
    """Return the scale, the drift and each method's error budget as text lines."""
    enc = result.robot.encoder
    lines = [""]
    sc = result.scale
    if sc is not None:
        lines.append(
            f"encoder scale from the reference ({sc.pairs} pair(s) of nests "
            f"{sc.reference_length_mm:g} mm apart): {sc.ppm:+.1f} ± {sc.std_ppm:.1f} ppm, "
            "applied to every length"
        )
        jt = result.estimates.get("joint")
        if jt is not None and jt.scale_ppm is not None and jt.scale_std_ppm is not None:
            lines.append(
                f"  refined with the joint method: {jt.scale_ppm:+.1f} ± "
                f"{jt.scale_std_ppm:.1f} ppm more"
            )
    lines += [f"note: {n}" for n in result.encoder_notes]
    if not result.budgets:
        return lines
    methods = list(result.budgets)
    lines += ["", "Error budget: mean tool-point error over 1000 configurations (mm)"]
    lines.append(f"{'source':<15}" + "".join(f"{m:>12}" for m in methods))
    for term, label in (
        ("noise", "reading noise"),
        ("scale", "encoder scale"),
        ("drift", "drift"),
        ("exit", "wire exit"),
        ("sag", "gravity sag"),
        ("compliance", "compliances"),  # the unidentified ones; only when the file asks
        ("prior", "prior's share"),  # a plan from a pool: what the readings see weakly
    ):
        values = [result.budgets[m].terms.get(term) for m in methods]
        if any(v is not None for v in values):
            lines.append(
                f"{label:<15}"
                + "".join("-".rjust(12) if v is None else f"{v:12.4f}" for v in values)
            )
    lines.append(f"{'total':<15}" + "".join(f"{result.budgets[m].total:12.4f}" for m in methods))
    lines.append(
        f"{'95 % bound':<15}"
        + "".join(f"{result.budgets[m].bound:12.4f}" for m in methods)
        + "   below it in 95 % of calibrations (the total is a mean)"
    )
    lines += [f"  {n}" for n in result.budgets[methods[0]].notes]
    if sc is None:
        best = min(result.budgets[m].terms["scale"] for m in methods)
        lines.append(
            f"± {best:.3f} mm from the encoder scale alone (tolerance "
            f"{enc.scale_tolerance_ppm:g} ppm): measure the reference"
        )
    return lines


def _compliance_text(result: SolveResult) -> list[str]:
    """Return the compliances the robot file asked for: identified ones, the other bound."""
    comp, joint = result.compliance, result.estimates.get("joint")
    if comp is None or joint is None:
        return []
    lines = ["", "Gravity compliance (joint method; µrad/(N·m)):"]
    std = joint.std_by_name()
    for name, value in joint.as_dict().items():
        if name in comp.identified:
            total = result.robot.nominal_value(name) + value
            lines.append(f"  {name:<8}{total:12.4f}" + (_sigma(std[name]) if name in std else ""))
    lines += [f"  {line}" for line in comp.describe()]
    b = result.budgets.get("joint")
    if b is not None and b.bound_compensated is not None:
        lines.append(
            f"  95 % bound {b.bound:.4f} mm for the patch as the controller applies it (the "
            f"sag left in it); {b.bound_compensated:.4f} mm for targets compensated offline"
        )
    return lines


def solve_text(result: SolveResult) -> str:
    """Return ``wirecal solve``'s text: the estimates side by side, accuracy, budget, steps."""
    lines = _heading(result)
    lines += ["", *_estimates_table(result)]
    lines += _accuracy_lines(result)
    lines += _compliance_text(result)
    lines += _encoder_text(result)
    if "stepwise" in result.estimates:
        lines += ["", *_step_lines(result.estimates["stepwise"])]
    return "\n".join(lines)


def _heading(result: SolveResult) -> list[str]:
    """Return the robot, the log, the wire's exit and what the log lacks."""
    m = result.measurements
    lines = [
        f"Robot {result.robot.name}; log {m.source}; {int(m.present.sum())} points",
        f"wire exit: {describe(result.robot.encoder.exit)}",
    ]
    if result.plan.joint_only:
        lines.append(
            "plan: written from a pool for the joint method (joint_only = true): its steps do "
            "not isolate their parameters, so the step-by-step estimate does not apply; the "
            "joint method alone"
        )
    if result.prior is not None:
        lines += _pool_fit_lines(result.prior)
    for note in m.notes:
        lines.append(f"note: {note}")
    if m.missing:
        lines.append(f"missing: {m.missing_text()}")
    if result.left_nominal:
        lines.append("left at nominal (no points): " + ", ".join(result.left_nominal))
    return lines


def _estimates_table(result: SolveResult) -> list[str]:
    """Return the methods' estimates side by side, the joint method's σ beside them."""
    est = result.estimates
    methods = list(est)
    head = f"{'parameter':<10}{'unit':<5}" + "".join(f"{m:>12}" for m in methods)
    joint, sigma = est.get("joint"), None
    if joint is not None and joint.std is not None:
        sigma = joint.std_by_name()
        head += f"{'± σ (joint)':>14}"
    prior = None if result.prior is None else result.prior.prior_sd
    if prior is not None:
        head += f"{'σ/prior':>9}"
    lines = [head]
    for name in result.listed:
        if name in result.left_nominal:
            continue
        row = f"{name:<10}{P.unit_of(name):<5}" + "".join(
            f"{est[m].as_dict()[name]:12.4f}" for m in methods
        )
        if sigma is not None:
            row += _sigma(sigma[name])
        if prior is not None:
            finite = bool(np.isfinite(prior[name]))
            ratio = sigma[name] / prior[name] if sigma is not None and finite else None
            row += f"{'-':>9}" if ratio is None else f"{ratio:9.2f}"
        lines.append(row)
    return lines


def _pool_fit_lines(fit: PriorFit) -> list[str]:
    """Return what the fit of a plan from a pool is: the one the plan was made for."""
    return [
        "fit: the one the plan was made for (wirecal plan --pool): one wire from an anchor "
        "fitted with the geometry, one length offset, the attachment (tool_*, no prior), "
        "every DH error of rows 2…n and the file's compliances, each with a zero-mean prior "
        f"(σ {fit.prior_mm:g} mm, angles to match), soft-L1 loss; the readings carry "
        f"{fit.effective:.1f} of the {fit.fitted} parameters; σ/prior near 1: the prior "
        "holds it (the readings barely see it)",
        f"anchor {', '.join(f'{v:.2f}' for v in fit.anchor_mm)} mm (base frame), length "
        f"offset {fit.offset_mm:+.3f} mm: the fit's own, not in the patch",
    ]


def _accuracy_lines(result: SolveResult) -> list[str]:
    """Return each method's residual, predicted tool error and bound, and the noise σ."""
    est, methods = result.estimates, list(result.estimates)
    return [
        f"{'residual RMS (mm)':<15}" + "".join(f"{est[m].residual_rms_mm:12.4f}" for m in methods),
        f"{'tool error (mm)':<15}"
        + "".join(_mm(result.predicted[m]["mean"]) for m in methods)
        + "   predicted mean over 1000 configurations",
        f"{'  worst':<15}" + "".join(_mm(result.predicted[m]["max"]) for m in methods),
        f"{'  95 % bound':<15}"
        + "".join(
            _mm(result.budgets[m].bound if m in result.budgets else float("inf")) for m in methods
        )
        + "   the mean stays below it in 95 % of calibrations",
        f"noise σ from the joint residual: {result.sigma_mm:.4f} mm; "
        f"recommended: {result.recommended}",
    ]


def _step_lines(stepwise: Estimate) -> list[str]:
    """Return the step-by-step method's steps (paper): rms before and after, |Ψ_j|, leak."""
    lines = ["Step-by-step (paper): rms before → after, |Ψ_j|, leak of later parameters"]
    for j, s in enumerate(stepwise.steps, 1):
        worst = s.worst_leak
        leak = f"{worst[0]} {worst[1]:+.3f}/unit" if worst and abs(worst[1]) >= 5e-4 else "none"
        bound = "  ON BOUND Ω" if s.on_bound else ""
        lines.append(
            f"{j:3d} {s.parameter:<5}{s.n_points:3d} pts  {s.rms_before_mm:8.4f} → "
            f"{s.rms_after_mm:7.4f} mm  |Ψ| {s.psi_strength:5.2f}  leak {leak}"
            f"{bound}"
        )
    return lines
