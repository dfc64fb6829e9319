"""Simulated measurement runs: a true robot, a draw-wire encoder, the controller's counter.

The true robot is the nominal model plus error offsets. The encoder is mounted where the
true tool point is at θ0, so the true wire length at θ_i is ‖p_true(θ_i) − p_true(θ0)‖,
or the path over the encoder's exit as built: a pulley's arc, or an eyelet's edge wrap
that the model leaves out (:func:`~wirecal.solver.exit_geometry.physical_wire_mm`).
Each reading adds one Gaussian error per point (σ, default 0.01 mm: it does not average
out over samples, like repeatability), is quantised at mm_per_count, sampled N times with
±1-count electrical jitter, and counted by a signed counter of ``counter_bits`` that wraps.
Each reading's ``t_s`` is its time in the run's time model (:func:`run_timeline`, the
program's default speed and settle time).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.counter import Counter
from wirecal.solver.distance import wire_vectors
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import Exit, physical_wire_mm
from wirecal.solver.formats.log import format_header, format_row
from wirecal.solver.kinematics import Model
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, run_timeline

RANGE_EXCEEDED = "*Draw-wire range exceeded*"  # the twin's error text for the same cause


@dataclass(frozen=True)
class Faults:
    """Injectable faults of a run."""

    slip: tuple[int, float] | None = None  # (step, mm): the wire slips by mm during step
    outliers: int = 0  # points with a gross error
    outlier_mm: float = 1.0  # size of that error (random sign)
    stop_after: int | None = None  # readings written before the run stops
    truncate_last: bool = False  # the last line is cut mid-write


def sample_counts(
    length_mm: np.ndarray,
    mm_per_count: float,
    start: float,
    counter: Counter,
    samples: int,
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray]:
    """Return what the controller logs for wire lengths ``length_mm``.

    The mean of ``samples`` counter readings, unwrapped relative to the first, and their
    spread (counts).
    """
    exact = start + np.asarray(length_mm, dtype=float) / mm_per_count
    jitter = rng.choice((-1.0, 0.0, 0.0, 0.0, 1.0), size=(*exact.shape, samples))
    raw = counter.wrap(np.floor(exact[..., None] + 0.5) + jitter)
    unwrapped = raw[..., :1] + counter.difference(raw, raw[..., :1])
    return unwrapped.mean(axis=-1), unwrapped.max(axis=-1) - unwrapped.min(axis=-1)


def true_lengths(model: Model, plan: Plan, exit_: Exit | None = None) -> np.ndarray:
    """Return the true wire length of every plan point, plan order; a batched model gives (T, N).

    ``exit_`` is the encoder's exit as built (an eyelet adds its edge wrap); by default
    the model's own (its pulley, or a point).
    """
    q, _, _ = plan.all_points()
    v = wire_vectors(model, np.radians(q), np.radians(plan.theta0_deg))
    return physical_wire_mm(model.pulley if exit_ is None else exit_, v)


def measured_lengths(
    model: Model, plan: Plan, mm_per_count: float, noise_mm: float, rng: np.random.Generator
) -> np.ndarray:
    """Return the wire lengths as a checked log gives them.

    Wire lengths as a checked log gives them: per-point noise, counts quantised, each
    measured from the mean of the steps' zero readings. Vectorised over a batched model
    (Monte Carlo); the same reading model as :func:`simulate_log` without the counter.
    """
    d = true_lengths(model, plan)
    n_zero = len(plan.steps)
    noisy = np.concatenate([np.zeros((*d.shape[:-1], n_zero)), d], axis=-1)
    noisy = noisy + rng.normal(0.0, noise_mm, noisy.shape)
    counts = np.floor(noisy / mm_per_count + 0.5)
    return (counts[..., n_zero:] - counts[..., :n_zero].mean(axis=-1, keepdims=True)) * mm_per_count


def simulate_log(
    robot: Robot,
    plan: Plan,
    errors: dict[str, float],
    *,
    seed: int,
    noise_mm: float = 0.01,
    samples: int = 10,
    faults: Faults = Faults(),
    counter_start: float | None = None,
    mm_per_count: float | None = None,
) -> str:
    """Return the text of the log a run of ``plan`` on the true robot would write."""
    rng = np.random.default_rng(seed)
    enc = robot.encoder
    mpc = enc.mm_per_count if mm_per_count is None else mm_per_count
    start = enc.counter.random_start(rng) if counter_start is None else counter_start
    d_points = true_lengths(robot.model(errors), plan, enc.exit)
    q, step_no, index_no = plan.all_points()

    # One entry per reading in run order: each step's zero at θ0, then its points; last
    # the closing zero at θ0 (logged as the zero of step N+1), which sees a slip in step N.
    n_steps = len(plan.steps)
    order = [
        (j, k)
        for j in range(1, n_steps + 1)
        for k in (None, *(int(i) for i in np.flatnonzero(step_no == j)))
    ] + [(n_steps + 1, None)]
    kinds = ["zero" if k is None else "point" for _, k in order]
    steps = [j for j, _ in order]
    indices = [0 if k is None else int(index_no[k]) for _, k in order]
    joints = [plan.theta0_deg if k is None else q[k] for _, k in order]
    lengths = np.array([0.0 if k is None else d_points[k] for _, k in order])
    # The closing zero draws from its own generator, so a seed gives the same readings as
    # before the closing zero existed, with one row added.
    closing_rng = np.random.default_rng([seed, 3])
    lengths[:-1] += rng.normal(0.0, noise_mm, len(lengths) - 1)
    steps_arr = np.asarray(steps)
    if faults.slip is not None:
        slip_step, slip_mm = faults.slip
        after = (steps_arr > slip_step) | (
            (steps_arr == slip_step) & (np.asarray(kinds) == "point")
        )
        lengths[after] += slip_mm
    if faults.outliers:
        pts = np.flatnonzero(np.asarray(kinds) == "point")
        chosen = rng.choice(pts, size=min(faults.outliers, len(pts)), replace=False)
        lengths[chosen] += faults.outlier_mm * rng.choice((-1.0, 1.0), size=len(chosen))
    lengths[-1] += closing_rng.normal(0.0, noise_mm)

    beyond = np.flatnonzero(lengths > enc.range_mm)
    if len(beyond):  # the encoder stops counting there: the twin's error, with its cause
        i = int(beyond[0])
        raise WirecalError(
            f"{RANGE_EXCEEDED}: step {steps[i]} point {indices[i]}: the wire would be "
            f"{lengths[i]:.1f} mm long, beyond the encoder's range_mm {enc.range_mm:g}"
        )
    head = sample_counts(lengths[:-1], mpc, start, enc.counter, samples, rng)
    tail = sample_counts(lengths[-1:], mpc, start, enc.counter, samples, closing_rng)
    mean, spread = np.concatenate([head[0], tail[0]]), np.concatenate([head[1], tail[1]])
    run = replace(DEFAULT_RUN, readings=samples)
    timeline = run_timeline(robot, plan, run)
    rows = [
        format_row(*args, samples, sp, t, settle)
        for args, sp, t, settle in zip(
            zip(kinds, steps, indices, joints, mean, strict=True),
            spread,
            timeline.reading_s,
            timeline.settle_s,
            strict=True,
        )
    ]
    if faults.stop_after is not None:
        rows = rows[: faults.stop_after]
    text = format_header(
        robot.name,
        plan.fingerprint(),
        mpc,
        ("simulated by wirecal; the truth is kept in a separate file",),
    )
    text += "\n".join(rows) + ("\n" if rows else "")
    if faults.truncate_last and rows:
        text = text[: -(len(rows[-1]) // 2) - 1]
    return text
