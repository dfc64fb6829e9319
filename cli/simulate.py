"""Provide ``wirecal simulate``: a measurement run on a simulated robot with known errors."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import click
import numpy as np

from wirecal.cli.main import user_errors
from wirecal.cli.options import NON_NEGATIVE, OUTPUT_FILE, PLAN, ROBOT, SEED, given, number
from wirecal.formats.capture import MIN_TERMINAL, fold
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import text_sha256
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import (
    MAX_DH_ANGLE_DEG,
    MAX_RANGE_MM,
    MAX_SCALE_PPM,
    load_robot,
)
from wirecal.formats.simulated_log import simulate_log
from wirecal.formats.truth import load_errors, random_errors, truth_text
from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    MAX_DRIFT_MM_PER_H,
    EncoderTruth,
    Faults,
    declared_unmodelled,
    realistic_encoder,
)


def _slip(
    ctx: click.Context, param: click.Parameter, value: str | None
) -> tuple[int, float] | None:
    """Return --slip STEP:MM as (step, mm), the size within the longest range."""
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
    type=OUTPUT_FILE,
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
    help="Run the generated programs of the robot file's language (V+, URScript or "
    "RAPID) in the digital twin: the log is written by the very program a user would load.",
)
@click.option(
    "--console",
    "console_path",
    type=OUTPUT_FILE,
    help="With --controller: also write the twin's console (the V+ terminal with "
    "--echo-log, URScript's log tab, RAPID's FlexPendant) as an operator would copy it, "
    "to rehearse pasting it into 'wirecal solve ROBOT PLAN -'.",
)
@click.option(
    "--width",
    type=click.IntRange(MIN_TERMINAL, 1000),
    default=80,
    show_default=True,
    help="The console's width in columns: longer lines are broken there, as a terminal does.",
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
    console_path,
    width,
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
    rb, pl = _load_checked(robot, plan, errors_file, scale, slip, counter_start)
    truth_path = Path(truth_out) if truth_out else Path(log_path).with_suffix(".truth.toml")
    inputs = [robot, plan, *([errors_file] if errors_file else [])]
    _check_twin_options(controller, console_path, outliers, stop_after)
    outputs = [log_path, truth_path, *([console_path] if console_path else [])]
    with Outputs(outputs, force=force, inputs=inputs) as out:
        errors = _true_errors(rb, errors_file, scale, seed)
        true_encoder = _true_encoder(rb, seed, ideal_encoder, encoder_scale_ppm, drift_mm_per_h)
        run = (seed, noise_mm, samples, counter_start, true_encoder)
        if controller:
            text, stopped = _twin_log(out, rb, pl, errors, run, slip, console_path, width)
        else:
            faults = Faults(
                slip=slip, outliers=outliers, outlier_mm=outlier_mm, stop_after=stop_after
            )
            text, stopped = _direct_log(rb, pl, errors, run, faults), None
        out.put(log_path, text)
        out.put(truth_path, _truth(rb, errors, None if errors_file else seed, text, true_encoder))
    points = sum(line.startswith("point,") for line in text.splitlines())  # as logged
    click.echo(f"wrote {log_path} ({points} points) and the truth to {truth_path}")
    if stopped:
        click.echo(f"the controller program stopped: {stopped}", err=True)
        sys.exit(1)


_Run = tuple[int, float, int, float | None, EncoderTruth]
"""The run's seed, noise (mm), samples per point, counter start and true encoder."""


def _load_checked(
    robot: str,
    plan: str,
    errors_file: str | None,
    scale: float | None,
    slip: tuple[int, float] | None,
    counter_start: float | None,
) -> tuple[Robot, Plan]:
    """Load ROBOT and PLAN, refusing options that contradict them or each other."""
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
    return rb, pl


def _true_errors(
    rb: Robot, errors_file: str | None, scale: float | None, seed: int
) -> dict[str, float]:
    """Return the true robot's offsets: the truth file's, or drawn within ±``scale``."""
    if errors_file:
        return load_errors(errors_file, rb)
    return random_errors(rb, 1.0 if scale is None else scale, np.random.default_rng([seed, 1]))


def _twin_log(
    out: Outputs,
    rb: Robot,
    pl: Plan,
    errors: dict[str, float],
    run: _Run,
    slip: tuple[int, float] | None,
    console_path: str | None,
    width: int,
) -> tuple[str, str | None]:
    """Return the log the robot file's programs write in the twin and why they stopped.

    The twin's console goes to ``console_path`` (folded at ``width``) when given.
    """
    from wirecal.app.twin_simulate import simulate_in_twin  # the twin only when asked for

    seed, noise_mm, samples, counter_start, true_encoder = run
    text, stopped, console = simulate_in_twin(
        rb,
        pl,
        errors,
        seed,
        noise_mm,
        samples,
        slip,
        counter_start,
        true_encoder,
        echo=bool(console_path),
    )
    if console_path:
        out.put(console_path, fold(console, width))
    return text, stopped


def _direct_log(rb: Robot, pl: Plan, errors: dict[str, float], run: _Run, faults: Faults) -> str:
    """Return the log of the direct simulation (no programs run), with ``faults``."""
    seed, noise_mm, samples, counter_start, true_encoder = run
    return simulate_log(
        rb,
        pl,
        errors,
        seed=seed,
        noise_mm=noise_mm,
        samples=samples,
        faults=faults,
        counter_start=counter_start,
        encoder=true_encoder,
        unmodelled=declared_unmodelled(rb),
    )


def _check_twin_options(
    controller: bool, console_path: str | None, outliers: int, stop_after: int | None
) -> None:
    """Refuse options that would be ignored.

    The direct simulation's with --controller; --console without --controller, --width
    without --console, --outlier-mm without --outliers.
    """
    if console_path and not controller:
        raise WirecalError("--console shows the twin's console: give --controller too")
    if given("width") and not console_path:
        raise WirecalError("--width folds the twin's console: give --console FILE too")
    if given("outlier_mm") and not outliers:
        raise WirecalError("--outlier-mm sizes the outliers: give --outliers N too")
    if controller and (outliers or stop_after is not None):
        raise WirecalError(
            "--outliers and --stop-after apply to the direct simulation; "
            "in the twin, give --slip STEP:MM (the fault the twin injects)"
        )


def _truth(
    rb: Robot, errors: dict[str, float], seed: int | None, log: str, encoder: EncoderTruth
) -> str:
    """Return the truth file of the run that wrote ``log``: its errors and its encoder."""
    return truth_text(rb, errors, seed, text_sha256(log)) + _encoder_note(encoder)


def _true_encoder(
    rb: Robot, seed: int, ideal: bool, scale_ppm: float | None, drift_mm_per_h: float
) -> EncoderTruth:
    """Return the simulated encoder: ideal, or realistic with the scale and drift given."""
    if ideal and (scale_ppm is not None or drift_mm_per_h):
        raise WirecalError("--ideal-encoder excludes --encoder-scale-ppm and --drift-mm-per-h")
    if ideal:
        return IDEAL_ENCODER
    return realistic_encoder(
        rb.encoder, np.random.default_rng([seed, 4]), scale_ppm, drift_mm_per_h
    )


def _encoder_note(truth: EncoderTruth) -> str:
    """Return the truth file's comment on the true encoder (what solve should find)."""
    return (
        f"# true encoder: scale {truth.scale_ppm:+.1f} ppm, temperature rise "
        f"{truth.temperature_change_k:g} K over the run (drum {truth.drum_ppm_per_k:g} "
        f"ppm/K, arm {truth.arm_ppm_per_k:g} ppm/K), zero drift "
        f"{truth.zero_drift_mm_per_h:g} mm/h, gauge error {truth.gauge_error_mm:+.4f} mm\n"
    )
