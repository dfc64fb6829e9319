"""Provide ``wirecal simulate`` and ``wirecal solve``.

Measurement runs on a simulated robot, and identification from a measurement log.
"""

from __future__ import annotations

import re
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np

from wirecal import __version__
from wirecal.app.languages import gate
from wirecal.cli.main import print_json, user_errors
from wirecal.cli.options import (
    ACCEPT_IMPLAUSIBLE,
    NON_NEGATIVE,
    PATCH_FORCE,
    PATCH_OUTPUT,
    POSITIVE,
    SEED,
    number,
)
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import describe
from wirecal.solver.formats.csv_table import STDIN
from wirecal.solver.formats.fileio import Outputs
from wirecal.solver.formats.log import read_log
from wirecal.solver.formats.patch import companion_paths, put_patch
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import (
    MAX_DH_ANGLE_DEG,
    MAX_RANGE_MM,
    MAX_SCALE_PPM,
    load_robot,
)
from wirecal.solver.formats.truth import load_errors, random_errors, truth_text
from wirecal.solver.identify import DEFAULT_OMEGA
from wirecal.solver.measurements import Tolerances, check_log
from wirecal.solver.plausibility import READING_NOISE_MM
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    MAX_DRIFT_MM_PER_H,
    EncoderTruth,
    Faults,
    realistic_encoder,
    simulate_log,
)
from wirecal.solver.solve import solve as solve_api

if TYPE_CHECKING:
    from wirecal.app.compare import ControllerComparison

ROBOT = click.argument("robot", type=click.Path(dir_okay=False))
PLAN = click.argument("plan", type=click.Path(dir_okay=False))


def _slip(ctx, param, value):
    if value is None:
        return None
    m = re.fullmatch(r"\s*(\d+)\s*:\s*([-+]?\d*\.?\d+(?:[eE][-+]?\d+)?)\s*", value)
    if not m:
        raise click.BadParameter("give STEP:MM, e.g. 4:0.5")
    if not abs(float(m.group(2))) <= MAX_RANGE_MM:
        raise click.BadParameter(f"give a slip within ±{MAX_RANGE_MM:g} mm (the longest range_mm)")
    return int(m.group(1)), float(m.group(2))


@click.command()
@ROBOT
@PLAN
@click.option(
    "-o",
    "--output",
    "log_path",
    required=True,
    type=click.Path(dir_okay=False),
    help="Log file to write (the format the controller program writes).",
)
@click.option(
    "--errors",
    "errors_file",
    type=click.Path(dir_okay=False),
    help="Truth file with an [errors] table of true offsets (deg, mm).",
)
@click.option(
    "--random",
    "scale",
    type=number(0.0, MAX_DH_ANGLE_DEG),
    help="Draw true offsets uniform within ±SCALE deg/mm for the robot file's "
    "parameters (default 1.0 when --errors is not given).",
)
@click.option(
    "--seed",
    type=SEED,
    default=0,
    show_default=True,
    help="Random seed: the same seed gives the same truth and readings.",
)
@click.option(
    "--noise-mm",
    type=NON_NEGATIVE,
    default=0.01,
    show_default=True,
    help="Gaussian error of each reading (σ, mm), before quantisation.",
)
@click.option(
    "--samples",
    type=click.IntRange(1, 1000),
    default=10,
    show_default=True,
    help="Counter readings averaged per point.",
)
@click.option(
    "--truth-out",
    type=click.Path(dir_okay=False),
    help="Where to write the truth [default: LOG with .truth.toml].",
)
@click.option(
    "--slip",
    callback=_slip,
    metavar="STEP:MM",
    help="Fault: the wire slips by MM during STEP (the next zero check sees it).",
)
@click.option(
    "--outliers",
    type=click.IntRange(min=0),
    default=0,
    help="Fault: this many points get a gross error of ±--outlier-mm.",
)
@click.option(
    "--outlier-mm",
    type=number(0.0, MAX_RANGE_MM),
    default=1.0,
    show_default=True,
    help="Size of each outlier's error (mm, random sign).",
)
@click.option(
    "--stop-after",
    type=click.IntRange(min=0),
    help="Fault: the run stops after this many readings (a partial log).",
)
@click.option(
    "--counter-start",
    type=number(),
    help="Counter value at the first reading [default: random]; just below "
    "2^(counter_bits-1) (8388607 at 24 bits) the counter wraps during the run.",
)
@click.option(
    "--controller",
    is_flag=True,
    help="Run the generated V+ programs (wc.mount, wc.run) in the digital twin: "
    "the log is written by the very program a user would load.",
)
@click.option(
    "--ideal-encoder",
    is_flag=True,
    help="A perfect encoder: the robot file's scale exactly, no temperature change.",
)
@click.option(
    "--encoder-scale-ppm",
    type=number(-MAX_SCALE_PPM, MAX_SCALE_PPM),
    help="The true encoder scale's error (ppm) [default: drawn within the robot file's "
    "scale_tolerance_ppm].",
)
@click.option(
    "--drift-mm-per-h",
    type=number(-MAX_DRIFT_MM_PER_H, MAX_DRIFT_MM_PER_H),
    default=0.0,
    show_default=True,
    help="Fault: every reading drifts by this much per hour from the start of the run.",
)
@click.option("--force", is_flag=True, help="Replace existing output files.")
@user_errors
def simulate(
    robot,
    plan,
    log_path,
    errors_file,
    scale,
    seed,
    noise_mm,
    samples,
    truth_out,
    slip,
    outliers,
    outlier_mm,
    stop_after,
    counter_start,
    controller,
    ideal_encoder,
    encoder_scale_ppm,
    drift_mm_per_h,
    force,
):
    """Simulate a measurement run of PLAN on a robot with known errors.

    The true robot is the nominal one plus error offsets (from --errors, or drawn with
    --random). Its wire lengths are read like the controller would: noise, quantisation at
    mm_per_count, averaged samples, and a wrapping counter. The encoder is realistic: its
    true scale is off within the robot file's scale_tolerance_ppm (--encoder-scale-ppm
    sets it), the temperature rises 0.5 K over the run (the drum and the arm expand), and
    the run starts with the reference step when the robot file gives a reference gauge;
    --ideal-encoder turns all of that off. The log goes to -o; the truth (and the true
    encoder) goes to its own file, never into the log.
    """
    rb = load_robot(robot)
    if rb.controller_problem():
        raise WirecalError(f"{rb.controller_problem()}; 'wirecal simulate' writes that log")
    pl = load_plan(plan, rb)
    if errors_file and scale is not None:
        raise WirecalError("give either --errors FILE or --random SCALE, not both")
    if slip is not None and not 1 <= slip[0] <= len(pl.steps):
        raise WirecalError(
            f"--slip {slip[0]}:{slip[1]:g}: {plan} has steps 1–{len(pl.steps)}; give one of them"
        )
    counter = rb.encoder.counter
    if counter_start is not None and not -counter.half <= counter_start < counter.half:
        raise WirecalError(
            f"--counter-start {counter_start:g}: the robot file's "
            f"{counter.bits}-bit counter holds {-counter.half}…{counter.half - 1}"
        )
    truth_path = Path(truth_out) if truth_out else Path(log_path).with_suffix(".truth.toml")
    inputs = [robot, plan, *([errors_file] if errors_file else [])]
    with Outputs([log_path, truth_path], force=force, inputs=inputs) as out:
        if errors_file:
            errors = load_errors(errors_file, rb)
        else:
            errors = random_errors(
                rb, 1.0 if scale is None else scale, np.random.default_rng([seed, 1])
            )
        if ideal_encoder and (encoder_scale_ppm is not None or drift_mm_per_h):
            raise WirecalError("--ideal-encoder excludes --encoder-scale-ppm and --drift-mm-per-h")
        true_encoder = (
            IDEAL_ENCODER
            if ideal_encoder
            else realistic_encoder(
                rb.encoder, np.random.default_rng([seed, 4]), encoder_scale_ppm, drift_mm_per_h
            )
        )
        stopped = None
        if controller:
            if outliers or stop_after is not None:
                raise WirecalError(
                    "--outliers and --stop-after apply to the direct simulation; "
                    "the twin injects its own faults (see the README)"
                )
            text, stopped = _twin_run(
                rb, pl, errors, seed, noise_mm, samples, slip, counter_start, true_encoder
            )
        else:
            text = simulate_log(
                rb,
                pl,
                errors,
                seed=seed,
                noise_mm=noise_mm,
                samples=samples,
                faults=Faults(
                    slip=slip, outliers=outliers, outlier_mm=outlier_mm, stop_after=stop_after
                ),
                counter_start=counter_start,
                encoder=true_encoder,
            )
        out.put(log_path, text)
        out.put(
            truth_path,
            truth_text(rb, errors, None if errors_file else seed) + _encoder_note(true_encoder),
        )
    click.echo(f"wrote {log_path} ({pl.n_points} points) and the truth to {truth_path}")
    if stopped:
        click.echo(f"the controller program stopped: {stopped}", err=True)
        sys.exit(1)


def _encoder_note(truth: EncoderTruth) -> str:
    """Return the truth file's comment on the true encoder (what solve should find)."""
    return (
        f"# true encoder: scale {truth.scale_ppm:+.1f} ppm, temperature rise "
        f"{truth.temperature_change_k:g} K over the run (drum {truth.drum_ppm_per_k:g} "
        f"ppm/K, arm {truth.arm_ppm_per_k:g} ppm/K), zero drift "
        f"{truth.zero_drift_mm_per_h:g} mm/h, gauge error {truth.gauge_error_mm:+.4f} mm\n"
    )


def _twin_run(rb, pl, errors, seed, noise_mm, samples, slip, counter_start, true_encoder):
    """Run the measurement programs in the twin; return the log text and why they stopped.

    The robot's language's programs in its twin adapter (:func:`wirecal.app.languages.registered`):
    a log file on the controller's disk, or sent over a loopback socket to wirecal receive
    (the journal of an incomplete run).
    """
    from wirecal.twin.run_moves import move_of_step, where_in_run
    from wirecal.twin.world import Faults as TwinFaults  # the twin only when asked for

    faults = TwinFaults()
    if slip is not None:
        faults = TwinFaults(slip_at_move=move_of_step(pl, slip[0]), slip_mm=slip[1])
    kw = dict(seed=seed, noise_mm=noise_mm, counter_start=counter_start, faults=faults)
    with tempfile.TemporaryDirectory() as tmp:
        from dataclasses import replace

        from wirecal.app.languages import registered
        from wirecal.gen.request import GenRequest

        reg = registered(rb)
        run = replace(reg.generator.default_run, readings=samples)  # as wirecal gen runs
        programs = reg.generator.programs(rb, pl, GenRequest(run=run))
        if reg.takes("encoder_truth"):
            kw["encoder_truth"] = true_encoder
        twin = reg.measure(rb, pl, errors, Path(tmp), programs, **kw)
        mount, outcome, world = twin.mount, twin.run, twin.world
        log, first = twin.log, mount.program
        text = log.read_text(encoding="ascii") if log.exists() else ""
    outcome = outcome or mount
    stopped = None
    if outcome.status != "completed":
        where = where_in_run(pl, world.moves) if outcome is not mount else first
        stopped = (
            f"{outcome.message} at {where} ({outcome.status} in {outcome.program} line "
            f"{outcome.line}): " + " / ".join(world.console[-4:])
        )
    return text, stopped


@click.command()
@ROBOT
@PLAN
@click.argument("log", type=click.Path(dir_okay=False))
@PATCH_OUTPUT
@click.option(
    "--method",
    type=click.Choice(["stepwise", "joint", "all", "controller"]),
    default="all",
    show_default=True,
    help="Which identification to run and show; 'controller' adds the generated "
    "V+ solver run in the digital twin beside the Python reference.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the result as JSON.")
@click.option(
    "--omega",
    type=POSITIVE,
    default=DEFAULT_OMEGA,
    show_default=True,
    help="Bound Ω of each step (deg or mm) where the plan gives none.",
)
@click.option(
    "--robust", is_flag=True, help="Joint method with a robust loss (soft L1) against outliers."
)
@click.option(
    "--partial", is_flag=True, help="Solve an incomplete log from the points that are there."
)
@click.option(
    "--refine-scale",
    is_flag=True,
    help="Refine the reference's encoder scale jointly with the parameters (the lengths "
    "tell it only through the lengths held at nominal, e.g. the tool point: use it when "
    "those are exact).",
)
@click.option(
    "--joint-tol",
    type=POSITIVE,
    default=Tolerances.joint_deg,
    show_default=True,
    help="Largest difference of logged joints from the plan (deg).",
)
@click.option(
    "--spread-tol",
    type=POSITIVE,
    default=Tolerances.spread_mm,
    show_default=True,
    help="Largest spread of a point's samples (mm).",
)
@click.option(
    "--zero-tol",
    type=POSITIVE,
    default=Tolerances.zero_mm,
    show_default=True,
    help="Largest step change of the zero readings (mm): a slip. With the log's times a "
    "slope (a drift) is fitted and removed instead; without, any drift from the first.",
)
@click.option(
    "--noise-mm",
    type=NON_NEGATIVE,
    default=READING_NOISE_MM,
    show_default=True,
    help="Reading noise σ (mm) the plausibility gate expects, before quantisation.",
)
@ACCEPT_IMPLAUSIBLE
@PATCH_FORCE
@click.option(
    "--accept-foreign",
    is_flag=True,
    help="Accept a log taken with another plan, robot file or encoder scale.",
)
@user_errors
def solve(
    robot,
    plan,
    log,
    patch_path,
    method,
    as_json,
    omega,
    robust,
    partial,
    refine_scale,
    joint_tol,
    spread_tol,
    zero_tol,
    noise_mm,
    accept_implausible,
    force,
    accept_foreign,
):
    """Identify the kinematic errors from a measurement LOG.

    LOG '-' reads standard input, e.g. the lines pasted from the controller's terminal.
    By default runs the paper's step-by-step method and the joint refinement and shows
    them side by side, with residuals and the predicted tool-point accuracy after
    calibration. With -o, writes the recommended method's patch (or the one --method
    names) and a table of values for the controller. A result that fails the plausibility
    gate (see the README) is refused with exit status 3 and nothing written.
    """
    rb = load_robot(robot)
    if rb.controller_problem():
        raise WirecalError(f"{rb.controller_problem()}; 'wirecal solve' reads that log")
    pl = load_plan(plan, rb)
    paths = [patch_path, *companion_paths(rb, patch_path)] if patch_path else []
    if log == STDIN and sys.stdin is not None and sys.stdin.isatty():
        click.echo("paste the log, then Ctrl-D (Windows: Ctrl-Z, Enter)", err=True)
    with Outputs(paths, force=force, inputs=[robot, plan, log]) as out:
        parsed = read_log(log)
        m = check_log(parsed, pl, rb, Tolerances(joint_tol, spread_tol, zero_tol), accept_foreign)
        methods = ("stepwise", "joint") if method in ("all", "controller") else (method,)
        result = solve_api(
            rb,
            pl,
            m,
            methods=methods,
            omega_default=omega,
            robust=robust,
            partial=partial,
            refine_scale=refine_scale,
        )
        chosen = result.recommended if method in ("all", "controller") else method
        verdict = gate(
            result, chosen, accept=accept_implausible, noise_mm=noise_mm, omega_default=omega
        )
        for finding in verdict.findings:
            click.echo(f"warning: implausible result accepted: {finding.message}", err=True)
        for warning in result.unchecked:
            click.echo(f"warning: {warning}", err=True)
        ctl = _controller(result) if method == "controller" else None
        if patch_path:
            put_patch(
                out,
                patch_path,
                rb,
                result.estimates[chosen],
                plan_fingerprint=pl.fingerprint(),
                log_path=m.source,
                log_sha256=m.sha256,
                version=__version__,
                plausibility=verdict.patch_field(),
                unchecked=result.unchecked,
            )
    if as_json:
        data = result.as_json()
        data["plausibility"] = verdict.as_json()
        if ctl:
            data["methods"]["controller"] = ctl.as_json()
        print_json(data)
    else:
        click.echo(_solve_text(result))
        click.echo(f"plausibility ({chosen}): {verdict.summary()}")
        if ctl:
            click.echo(_controller_text(ctl))
    if patch_path:
        others = " and ".join(str(p) for p in companion_paths(rb, patch_path))
        click.echo(f"wrote {patch_path} ({chosen}) and {others}", err=as_json)


def _controller(result) -> ControllerComparison:
    """Run the generated controller solver (wc.solve, wc.solve2) in the twin on the log."""
    from wirecal.app.compare import compare_controller  # the twin only when asked for

    with tempfile.TemporaryDirectory() as tmp:
        return compare_controller(result, Path(tmp))


def _controller_text(ctl: ControllerComparison) -> str:
    if ctl.polished is None:
        return _ur_controller_text(ctl)
    lines = [
        "",
        "Controller solver (the generated V+ run in the digital twin):",
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


def _ur_controller_text(ctl: ControllerComparison) -> str:
    run = ctl.stepwise
    lines = [
        "",
        "Controller solver (the generated URScript wc_solve run in the digital twin, "
        "32-bit floats):",
        f"{'parameter':<10}{'wc_solve':>12}",
    ]
    lines += [f"{name:<10}{value:12.6f}" for name, value in run.offsets.items()]
    lines.append(
        f"largest difference from the Python reference (stepwise): "
        f"{ctl.stepwise_max_difference:.2g} deg/mm; {run.total_operations:,} arithmetic "
        f"operations, {run.syncs:,} sync() (at most {run.most_between_syncs} operations "
        "between two)"
    )
    return "\n".join(lines)


def _sigma(std: float) -> str:
    """σ of the joint estimate, or that the points do not identify the parameter."""
    return f"{std:14.4f}" if np.isfinite(std) else f"{'unidentifiable':>16}"


def _mm(value: float) -> str:
    return f"{value:12.4f}" if np.isfinite(value) else f"{'unbounded':>12}"


def _encoder_text(result) -> list[str]:
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
    ):
        lines.append(
            f"{label:<15}" + "".join(f"{result.budgets[m].terms[term]:12.4f}" for m in methods)
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


def _solve_text(result) -> str:
    est = result.estimates
    names = result.plan.order
    methods = list(est)
    lines = [
        f"Robot {result.robot.name}; log {result.measurements.source}; "
        f"{int(result.measurements.present.sum())} points",
        f"wire exit: {describe(result.robot.encoder.exit)}",
    ]
    for note in result.measurements.notes:
        lines.append(f"note: {note}")
    if result.measurements.missing:
        lines.append(f"missing: {result.measurements.missing_text()}")
    if result.left_nominal:
        lines.append("left at nominal (no points): " + ", ".join(result.left_nominal))
    head = f"{'parameter':<10}{'unit':<5}" + "".join(f"{m:>12}" for m in methods)
    if "joint" in est:
        head += f"{'± σ (joint)':>14}"
    lines += ["", head]
    for name in names:
        if name in result.left_nominal:
            continue
        unit = "deg" if name.startswith(("th", "al")) else "mm"
        row = f"{name:<10}{unit:<5}" + "".join(f"{est[m].as_dict()[name]:12.4f}" for m in methods)
        if "joint" in est:
            row += _sigma(est["joint"].std[list(est["joint"].names).index(name)])
        lines.append(row)
    lines.append(
        f"{'residual RMS (mm)':<15}" + "".join(f"{est[m].residual_rms_mm:12.4f}" for m in methods)
    )
    lines.append(
        f"{'tool error (mm)':<15}"
        + "".join(_mm(result.predicted[m]["mean"]) for m in methods)
        + "   predicted mean over 1000 configurations"
    )
    lines.append(f"{'  worst':<15}" + "".join(_mm(result.predicted[m]["max"]) for m in methods))
    lines.append(
        f"{'  95 % bound':<15}"
        + "".join(
            _mm(result.budgets[m].bound if m in result.budgets else float("inf")) for m in methods
        )
        + "   the mean stays below it in 95 % of calibrations"
    )
    lines.append(
        f"noise σ from the joint residual: {result.sigma_mm:.4f} mm; "
        f"recommended: {result.recommended}"
    )
    lines += _encoder_text(result)
    if "stepwise" in est:
        lines += ["", "Step-by-step (paper): rms before → after, |Ψ_j|, leak of later parameters"]
        for j, s in enumerate(est["stepwise"].steps, 1):
            worst = s.worst_leak
            leak = f"{worst[0]} {worst[1]:+.3f}/unit" if worst and abs(worst[1]) >= 5e-4 else "none"
            bound = "  ON BOUND Ω" if s.on_bound else ""
            lines.append(
                f"{j:3d} {s.parameter:<5}{s.n_points:3d} pts  {s.rms_before_mm:8.4f} → "
                f"{s.rms_after_mm:7.4f} mm  |Ψ| {s.psi_strength:5.2f}  leak {leak}"
                f"{bound}"
            )
    return "\n".join(lines)
