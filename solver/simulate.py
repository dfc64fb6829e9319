"""Simulated measurement runs: a true robot, a draw-wire encoder, the controller's counter.

The true robot is the nominal model plus error offsets. The encoder is mounted where the
true tool point is at θ0, so the true wire length at θ_i is ‖p_true(θ_i) − p_true(θ0)‖,
or the path over the encoder's exit as built: a pulley's arc, or an eyelet's edge wrap
that the model leaves out (:func:`~wirecal.solver.exit_geometry.physical_wire_mm`).
Each reading adds one Gaussian error per point (σ, default 0.01 mm: it does not average
out over samples, like repeatability), is quantised at mm_per_count, sampled N times with
±1-count electrical jitter, and counted by a signed counter of ``counter_bits`` that wraps.
Each reading's ``t_s`` is its time in the run's time model (:func:`run_timeline`, the
program's default speed and settle time). A run is returned as data (:class:`SimulatedRun`,
:func:`simulate_run`); the log format writes its text
(:func:`~wirecal.formats.simulated_log.simulate_log`).

The encoder itself is :class:`EncoderTruth`: ideal by default in the Python API (the
figures of the tests and the Monte Carlo of the noise alone), realistic in ``wirecal
simulate``, the twin and the demo (:func:`realistic_encoder`). A realistic encoder's true
mm per count is the robot file's × (1 + scale), the scale drawn uniform within
``scale_tolerance_ppm``; the temperature rises by :data:`TEMPERATURE_CHANGE_K` linearly over
the run, so the drum's mm per count grows by ``temperature_coefficient_ppm_per_k`` per kelvin
and the arm (every length of it: the wire length is homogeneous in them) by
:data:`ARM_PPM_PER_K`, both about the run's mean temperature (the truth file's arm is the
arm at that temperature). A zero drift (mm/h) can be added to every reading. When the robot
file gives ``reference_length_mm``, the run starts with the reference step: the wire tip
seated in nest A (a wire length of :data:`NEST_A_MM`) and nest B, ``reference_repeats``
pairs, one every :data:`OPERATOR_SEAT_S`; the gauge's true length is its certified length
plus an error of its certified uncertainty.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.counter import Counter
from wirecal.solver.distance import wire_vectors
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import Exit, off_the_wire, physical_wire_mm
from wirecal.solver.gravity import gravity_torques_floats, gravity_torques_nm, wrist_weight
from wirecal.solver.kinematics import Model, loaded, one_chain, rigid_frames, tool_position
from wirecal.solver.log.readings import REFERENCE_STEP, Reading
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import DEFAULT_GRAVITY_SAG_DEG_PER_M, Encoder, Robot
from wirecal.solver.run_parameters import DEFAULT_RUN, RunParameters, run_timeline
from wirecal.solver.scale import ARM_PPM_PER_K, PPM
from wirecal.solver.zero_reading import joint_sigma_rad

RANGE_EXCEEDED = "*Draw-wire range exceeded*"  # the twin's error text for the same cause


@dataclass(frozen=True)
class Faults:
    """Injectable faults of a run."""

    slip: tuple[int, float] | None = None  # (step, mm): the wire slips by mm during step
    outliers: int = 0  # points with a gross error
    outlier_mm: float = 1.0  # size of that error (random sign)
    stop_after: int | None = None  # readings written before the run stops
    truncate_last: bool = False  # the last line is cut mid-write


NO_FAULTS = Faults()
"""A run without faults (the default)."""


TEMPERATURE_CHANGE_K = 0.5
"""Temperature rise over a realistic simulated run (K): a workshop warming in the morning."""

NEST_A_MM = 50.0
"""Wire length (mm) with the tip in the reference gauge's nest A, close to the exit."""

OPERATOR_SEAT_S = 20.0
"""Time (s) the operator takes per seating of the wire tip in a nest, and to reattach it."""


MAX_DRIFT_MM_PER_H = 1000.0
"""Largest zero drift a simulation injects (mm/h): 2000 times what the drift check accepts
(:data:`~wirecal.solver.scale.DRIFT_TOLERANCE_MM_PER_H`), enough for any fault study."""


@dataclass(frozen=True)
class EncoderTruth:
    """The true encoder of a simulated run (the robot file only approximates it)."""

    scale_ppm: float = 0.0  # true mm per count = the robot file's × (1 + scale_ppm·10⁻⁶)
    temperature_change_k: float = 0.0  # rise over the run, linear in time
    drum_ppm_per_k: float = 0.0
    arm_ppm_per_k: float = 0.0
    zero_drift_mm_per_h: float = 0.0  # added to every reading, from the start of the run
    gauge_error_mm: float = 0.0  # true gauge length − certified

    def read_factor(self, t_s: np.ndarray, total_s: float) -> np.ndarray:
        """Return the reading of a wire length over its length at the mean temperature.

        (1 + α_arm·ΔT) / ((1 + scale)(1 + α_drum·ΔT)), ΔT = rise × (t/total − ½).
        """
        t = np.asarray(t_s, dtype=float)
        dT = self.temperature_change_k * (t / total_s - 0.5) if total_s > 0 else 0.0 * t
        return (1 + self.arm_ppm_per_k * PPM * dT) / (
            (1 + self.scale_ppm * PPM) * (1 + self.drum_ppm_per_k * PPM * dT)
        )

    def drift_mm(self, t_s: np.ndarray) -> np.ndarray:
        """Return the zero drift added to readings at ``t_s``."""
        return self.zero_drift_mm_per_h * np.asarray(t_s, dtype=float) / 3600


IDEAL_ENCODER = EncoderTruth()


DEFAULT_REPEATABILITY_MM = 0.02
"""The twin's arm repeatability (mm) when the robot file declares none: the value the twin
has always used (an assumption, no datasheet's)."""


def declared_unmodelled(robot: Robot) -> Unmodelled | None:
    """Return the errors ``wirecal simulate`` gives the true arm: the declared repeatability.

    A robot file with ``[calibration] repeatability_mm`` gets an arm that lands within it
    (no assumed sag: the file's compliances or none); without the key the arm lands exactly,
    as before the key existed.
    """
    if robot.repeatability_mm is None:
        return None
    return Unmodelled(robot.repeatability_mm, 0.0)


@dataclass(frozen=True)
class Unmodelled:
    """Physical effects no kinematic parameter can absorb.

    So that validation figures are not trivially perfect. Joint encoders do not see them:
    HERE reports the commanded joints, while the encoder wire and the probe see where the arm
    really is.

    * repeatability: each move lands with independent joint errors of σ chosen so that the
      tool point scatters by about ``repeatability_mm``/2 (1σ) at 600 mm
      (:func:`~wirecal.solver.zero_reading.joint_sigma_rad`); None (the default): the
      robot file's ``[calibration] repeatability_mm``, else
      :data:`DEFAULT_REPEATABILITY_MM` (:meth:`for_robot`), so the true arm repeats as the
      file says the solver should assume;
    * compliance under gravity: joints 2 and 3 sag by ``compliance_deg_per_m`` per metre of
      lever arm from their axis to the wrist centre, in the direction gravity pulls (the
      weight of the forearm, wrist and tool; 0.01 deg/m gives ≈ 0.05 mm at full reach): the
      assumed instance of the compliance model, δθ_j = c_j·τ_j(q) with a weight of 1 N at
      the wrist centre (:func:`~wirecal.solver.gravity.wrist_weight`) and c2 = c3 =
      ``compliance_deg_per_m`` per N·m. A model that carries compliances bends by them
      instead: no assumed sag.
    """

    repeatability_mm: float | None = None
    compliance_deg_per_m: float = DEFAULT_GRAVITY_SAG_DEG_PER_M

    def for_robot(self, robot: Robot) -> Unmodelled:
        """Return these errors with the repeatability resolved for ``robot`` (class docstring)."""
        if self.repeatability_mm is not None:
            return self
        declared = robot.repeatability_mm
        return replace(
            self, repeatability_mm=DEFAULT_REPEATABILITY_MM if declared is None else declared
        )

    def joint_errors_deg(
        self, model: Model, q_deg: np.ndarray, rng: np.random.Generator
    ) -> np.ndarray:
        """Return where the arm really is relative to commanded joints ``q_deg`` (deg).

        One configuration (n,) or many (N, n); the repeatability's draws come first.
        """
        r = DEFAULT_REPEATABILITY_MM if self.repeatability_mm is None else self.repeatability_mm
        sigma = np.degrees(joint_sigma_rad(r))
        dq = rng.normal(0.0, sigma, np.shape(q_deg))
        if self.compliance_deg_per_m == 0.0 and np.isfinite(q_deg).all():
            return dq  # no sag: dq − (±0.0) is dq, a draw 0.0 + σz never −0.0
        return dq - self.sag_deg(model, q_deg).reshape(dq.shape)

    def sag_deg(self, model: Model, q_deg: np.ndarray) -> np.ndarray:
        """Return how far joints 2 and 3 sag under gravity at ``q_deg`` (deg, (N, n)).

        The joints are at ``q_deg`` − sag: the sag is −c·τ(q) (class docstring). Zero for a
        model with compliances: its frames bend by them.
        """
        q = np.atleast_2d(q_deg)
        if model.compliance is not None:
            return np.zeros(q.shape)
        c = np.zeros(q.shape[1])
        c[1:3] = self.compliance_deg_per_m  # deg/(N·m) under a 1 N weight: deg/m of lever
        weight = wrist_weight(q.shape[1])
        chain = one_chain(model, np.radians(q[0])) if len(q) == 1 else None
        if chain is not None:  # one configuration (the twin's every move): on floats
            x, z, o = zip(*chain[0], strict=True)
            tau = gravity_torques_floats(weight, list(x), list(z), list(o))
            if tau is not None:
                return -c * np.array([tau])
        f = rigid_frames(model, np.radians(q))
        return -c * gravity_torques_nm(weight, f.x, f.z, f.o)


def sagged_tool_points(
    robot: Robot, model: Model, q_deg: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Return ``model``'s tool points at ``q_deg`` (N, 3) as commanded and as sagged (mm).

    The sag is the robot file's ``gravity_sag_deg_per_m`` (:class:`Unmodelled`'s sag of
    joints 2 and 3), the rule every error budget's sag term is computed by.
    """
    unmodelled = Unmodelled(0.0, robot.gravity_sag_deg_per_m)
    p = tool_position(model, np.radians(q_deg))
    sagged = tool_position(model, np.radians(q_deg - unmodelled.sag_deg(model, q_deg)))
    return p, sagged


def sag_lengths_mm(robot: Robot, plan: Plan) -> np.ndarray:
    """Return what the gravity sag adds to each plan point's measured wire length (mm).

    The sag (:func:`sagged_tool_points`) at the nominal model, the wire from the tool point
    at θ0 (as the twin mounts it): the length to the sagged tool point less the commanded
    one's, less the zero reading's (θ0 sagged), which every length is measured from. Plan
    order.
    """
    q, _, _ = plan.all_points()
    p, sagged = sagged_tool_points(robot, robot.nominal, np.vstack([plan.theta0_deg, q]))
    exit_ = robot.encoder.exit
    extra = physical_wire_mm(exit_, sagged - p[0]) - physical_wire_mm(exit_, p - p[0])
    if not np.all(np.isfinite(extra)):
        raise WirecalError(_sag_off_the_wire(robot, sagged[0] - p[0], not np.isfinite(extra[0])))
    return np.asarray(extra[1:] - extra[0], dtype=float)


def _sag_off_the_wire(robot: Robot, sag0_mm: np.ndarray, at_theta0: bool) -> str:
    """Return why :func:`sag_lengths_mm` has no value: a sagged point lies off the wire.

    The exit is mounted where the unsagged arm stands at θ0 (as the twin mounts it); a guide
    pulley or an eyelet's rounded edge bends the wire over a circle touching the exit, and
    no wire reaches a point inside it. ``at_theta0``: the point is the sagged θ0
    (``sag0_mm`` from the exit), which every reading is measured from.
    """
    exit_ = robot.encoder.exit
    where = "a plan point inside the circle the wire bends over at the exit"
    if at_theta0 and exit_ is not None:
        where = "the tool point at θ0 " + off_the_wire(exit_, sag0_mm)
    return (
        f"robot file: [calibration] gravity_sag_deg_per_m = {robot.gravity_sag_deg_per_m:g}: "
        f"the assumed gravity sag puts {where}: the error budget's sag term has no value. "
        "The exit is modelled where the unsagged arm stands at θ0, a real one is mounted "
        "where the arm sags (not modelled yet: docs/accuracy.md). Set "
        "gravity_sag_deg_per_m = 0 (the budget then leaves the sag out) or declare the arm's "
        "compliances (the model then carries the sag)"
    )


def realistic_encoder(
    encoder: Encoder,
    rng: np.random.Generator,
    scale_ppm: float | None = None,
    zero_drift_mm_per_h: float = 0.0,
) -> EncoderTruth:
    """Return a realistic true encoder for the robot file's ``encoder`` (module docstring).

    ``scale_ppm`` sets the scale exactly; by default it is drawn within the tolerance.
    """
    tol = encoder.scale_tolerance_ppm
    scale = float(rng.uniform(-tol, tol)) if scale_ppm is None else scale_ppm
    return EncoderTruth(
        scale_ppm=scale,
        temperature_change_k=TEMPERATURE_CHANGE_K,
        drum_ppm_per_k=encoder.temperature_coefficient_ppm_per_k,
        arm_ppm_per_k=ARM_PPM_PER_K,
        zero_drift_mm_per_h=zero_drift_mm_per_h,
        gauge_error_mm=float(rng.normal(0.0, encoder.reference_uncertainty_mm)),
    )


def reference_lengths(encoder: Encoder, truth: EncoderTruth) -> np.ndarray:
    """Return the true wire lengths of the reference step: nest A, nest B, … (mm)."""
    if encoder.reference_length_mm is None:
        return np.zeros(0)
    pair = [NEST_A_MM, NEST_A_MM + encoder.reference_length_mm + truth.gauge_error_mm]
    return np.tile(pair, encoder.reference_repeats)


def reference_duration_s(encoder: Encoder) -> float:
    """Return how long the reference step takes: each seating and the reattachment."""
    if encoder.reference_length_mm is None:
        return 0.0
    return OPERATOR_SEAT_S * (2 * encoder.reference_repeats + 1)


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
    loads = plan.loads()  # a payload step's points: the mass at the flange
    model = model if loads is None else loaded(model, *loads)
    v = wire_vectors(model, np.radians(q), np.radians(plan.theta0_deg))
    return physical_wire_mm(model.pulley if exit_ is None else exit_, v)


def measured_lengths(
    model: Model,
    plan: Plan,
    mm_per_count: float,
    noise_mm: float,
    rng: np.random.Generator,
    encoder: EncoderTruth = IDEAL_ENCODER,
    times: tuple[np.ndarray, np.ndarray, float] | None = None,
) -> np.ndarray:
    """Return the wire lengths as a checked log gives them.

    Wire lengths as a checked log gives them: per-point noise, counts quantised, each
    measured from the mean of the steps' zero readings. Vectorised over a batched model
    (Monte Carlo); the same reading model as :func:`simulate_run` without the counter.
    ``times`` (the steps' zero times, the points' times, the run's total, s) is needed for
    an encoder with temperature or drift.
    """
    d = true_lengths(model, plan)
    n_zero = len(plan.steps)
    noisy = np.concatenate([np.zeros((*d.shape[:-1], n_zero)), d], axis=-1)
    if times is not None:
        t = np.concatenate([times[0], times[1]])
        noisy = noisy * encoder.read_factor(t, times[2]) + encoder.drift_mm(t)
    elif encoder != IDEAL_ENCODER:
        noisy = noisy * encoder.read_factor(np.zeros(1), 0.0)
    noisy = noisy + rng.normal(0.0, noise_mm, noisy.shape)
    counts = np.floor(noisy / mm_per_count + 0.5)
    return (counts[..., n_zero:] - counts[..., :n_zero].mean(axis=-1, keepdims=True)) * mm_per_count


@dataclass(frozen=True)
class SimulatedRun:
    """A simulated run as its log records it: the header's facts and the readings.

    ``readings`` in run order, those of a run that stops (:attr:`Faults.stop_after`) cut;
    ``truncate_last``: the log's last line is cut mid-write (:attr:`Faults.truncate_last`).
    Each reading's ``line`` is 0: it is not read from a file.
    """

    robot: str  # the robot file's name
    plan: str  # the plan's fingerprint
    mm_per_count: float  # the robot file's (or the one given), as the controller logs it
    readings: tuple[Reading, ...]
    truncate_last: bool = False
    payload_kg: float | None = None  # the payload step's mass, as the log's header says


def simulate_run(
    robot: Robot,
    plan: Plan,
    errors: dict[str, float],
    *,
    seed: int,
    noise_mm: float = 0.01,
    samples: int = 10,
    faults: Faults = NO_FAULTS,
    counter_start: float | None = None,
    mm_per_count: float | None = None,
    encoder: EncoderTruth = IDEAL_ENCODER,
    run: RunParameters = DEFAULT_RUN,
    unmodelled: Unmodelled | None = None,
) -> SimulatedRun:
    """Return what the log of a run of ``plan`` on the true robot would record.

    ``run``: the program's speed and settle settings, which set each reading's ``t_s``
    (``samples`` is its readings per point). ``unmodelled``: the arm lands where the
    twin's arm would (:class:`Unmodelled`, drawn from a generator of their own), every
    reading's wire measured from the tool point at θ0 of the true robot, as the twin does.

    ``encoder`` is the true encoder (ideal by default; :func:`realistic_encoder`); the
    reference step comes first when the robot file asks for one. ``faults``: the wire's
    slip and outliers change the readings; a stop cuts them; a cut last line is recorded.
    """
    rng = np.random.default_rng(seed)
    enc = robot.encoder
    mpc = enc.mm_per_count if mm_per_count is None else mm_per_count
    start = enc.counter.random_start(rng) if counter_start is None else counter_start
    d_points = true_lengths(robot.model(errors), plan, enc.exit)
    kinds, steps, indices, joints, points = _run_order(plan)
    lengths = _row_lengths(
        robot, errors, plan, np.array(joints), points, d_points, unmodelled, seed
    )
    # The closing zero draws from its own generator, so a seed gives the same readings as
    # before the closing zero existed, with one row added.
    closing_rng = np.random.default_rng([seed, 3])
    lengths[:-1] += rng.normal(0.0, noise_mm, len(lengths) - 1)
    _add_faults(lengths, np.asarray(steps), np.asarray(kinds) == "point", faults, rng)
    lengths[-1] += closing_rng.normal(0.0, noise_mm)

    _check_finite(lengths, "true wire length", steps, indices, f"the true errors on {robot.source}")
    _check_range(lengths, enc.range_mm, steps, indices)
    times, total, settle_s = _reading_times(robot, plan, replace(run, readings=samples))
    # What the encoder reads of those wire lengths (scale, temperature, drift).
    reading = lengths * encoder.read_factor(times, total) + encoder.drift_mm(times)
    _check_finite(reading, "encoder's reading", steps, indices, "the true encoder")
    head = sample_counts(reading[:-1], mpc, start, enc.counter, samples, rng)
    tail = sample_counts(reading[-1:], mpc, start, enc.counter, samples, closing_rng)
    mean, spread = np.concatenate([head[0], tail[0]]), np.concatenate([head[1], tail[1]])
    rows = _reference_rows(enc, encoder, plan, noise_mm, samples, start, seed, total)
    readings = zip(kinds, steps, indices, joints, mean, strict=True)
    rows += _reading_rows(readings, spread, times, settle_s, samples)
    cut = _stopped(rows, faults.stop_after)
    kg = None if plan.payload_step is None else plan.payload_step.payload_kg
    return SimulatedRun(robot.name, plan.fingerprint(), mpc, cut, faults.truncate_last, kg)


def _reading_rows(
    readings: Iterable[tuple[str, int, int, np.ndarray, float]],
    spread: np.ndarray,
    times: np.ndarray,
    settle_s: np.ndarray,
    samples: int,
) -> list[Reading]:
    """Return the log's rows of ``readings`` (kind, step, index, joints, mean count)."""
    return [
        _reading(*args, samples, sp, t, settle)
        for args, sp, t, settle in zip(readings, spread, times, settle_s, strict=True)
    ]


def _reading(
    kind: str,
    step: int,
    index: int,
    joints_deg: np.ndarray,
    counts: float,
    samples: int,
    spread: float,
    t_s: float,
    settle_s: float,
) -> Reading:
    """Return one row of a simulated run (not read from a file: its line is 0)."""
    return Reading(
        kind,
        step,
        index,
        joints_deg,
        float(counts),
        samples,
        float(spread),
        line=0,
        t_s=float(t_s),
        settle_s=float(settle_s),
    )


def _run_order(
    plan: Plan,
) -> tuple[list[str], list[int], list[int], list[np.ndarray], list[int | None]]:
    """Return every reading's kind, step, index, joints and point (None: a zero) in run order.

    Each step's zero at θ0, then its points; last the closing zero at θ0 (logged as the
    zero of step N+1), which sees a slip in step N.
    """
    q, step_no, index_no = plan.all_points()
    n_steps = len(plan.steps)
    order = [
        (j, k)
        for j in range(1, n_steps + 1)
        for k in (None, *(int(i) for i in np.flatnonzero(step_no == j)))
    ] + [(n_steps + 1, None)]
    kinds = ["zero" if k is None else "point" for _, k in order]
    indices = [0 if k is None else int(index_no[k]) for _, k in order]
    joints = [plan.theta0_deg if k is None else q[k] for _, k in order]
    return kinds, [j for j, _ in order], indices, joints, [k for _, k in order]


def _reading_times(
    robot: Robot, plan: Plan, run: RunParameters
) -> tuple[np.ndarray, float, np.ndarray]:
    """Return each reading's time, the run's duration and each reading's settle time in s.

    The times count from the reference step's start (its duration comes first).
    """
    timeline = run_timeline(robot, plan, run)
    offset = reference_duration_s(robot.encoder)
    return timeline.reading_s + offset, timeline.total_s + offset, timeline.settle_s


def _add_faults(
    lengths: np.ndarray,
    steps: np.ndarray,
    is_point: np.ndarray,
    faults: Faults,
    rng: np.random.Generator,
) -> None:
    """Add the wire's slip and the outliers of ``faults`` to the rows' ``lengths`` in place."""
    if faults.slip is not None:
        slip_step, slip_mm = faults.slip
        after = (steps > slip_step) | ((steps == slip_step) & is_point)
        lengths[after] += slip_mm
    if faults.outliers:
        pts = np.flatnonzero(is_point)
        if faults.outliers > len(pts):
            raise WirecalError(
                f"--outliers {faults.outliers}: the plan has {len(pts)} points; give at "
                f"most {len(pts)}"
            )
        chosen = rng.choice(pts, size=faults.outliers, replace=False)
        lengths[chosen] += faults.outlier_mm * rng.choice((-1.0, 1.0), size=len(chosen))


def _stopped(rows: list, stop_after: int | None) -> tuple:
    """Return the rows a run writes before it stops after ``stop_after`` (None: all)."""
    if stop_after is not None and stop_after >= len(rows):
        raise WirecalError(
            f"--stop-after {stop_after}: the run writes {len(rows)} readings, so it would "
            f"not stop; give fewer than {len(rows)}"
        )
    return tuple(rows[:stop_after])


def _check_range(
    lengths: np.ndarray, range_mm: float, steps: list[int], indices: list[int]
) -> None:
    """Refuse a wire length beyond the encoder's range either way.

    A fault shortening the wire by more than it can be long, say: the encoder stops
    counting, the twin's error, with its cause.
    """
    beyond = np.flatnonzero(np.abs(lengths) > range_mm)
    if len(beyond):
        i = int(beyond[0])
        raise WirecalError(
            f"{RANGE_EXCEEDED}: step {steps[i]} point {indices[i]}: the wire would be "
            f"{lengths[i]:.1f} mm long, beyond the encoder's range_mm {range_mm:g}"
        )


def _row_lengths(
    robot: Robot,
    errors: dict[str, float],
    plan: Plan,
    joints_deg: np.ndarray,
    points: list[int | None],
    d_points: np.ndarray,
    unmodelled: Unmodelled | None,
    seed: int,
) -> np.ndarray:
    """Return the true wire length of every row in run order (a zero row's: 0 mm).

    With ``unmodelled`` errors where the arm really is, from the tool point at θ0.
    """
    if unmodelled is None:
        return np.array([0.0 if k is None else d_points[k] for k in points])
    model = robot.model(errors)
    rng = np.random.default_rng([seed, 6])
    actual = joints_deg + unmodelled.for_robot(robot).joint_errors_deg(model, joints_deg, rng)
    p0 = tool_position(model, np.radians(plan.theta0_deg)[None])[0]
    loads = plan.loads()  # the payload step's points carry its mass, its zero none
    if loads is not None:
        model = loaded(model, [0.0 if k is None else loads[0][k] for k in points], loads[1])
    p = tool_position(model, np.radians(actual))
    return np.asarray(physical_wire_mm(robot.encoder.exit, p - p0), dtype=float)


def _check_finite(
    values: np.ndarray, what: str, steps: list[int], indices: list[int], cause: str
) -> None:
    """Refuse a run whose ``values`` (one per reading, run order) are not all finite.

    A NaN or infinite length would be written as a count: a log with exit status 0 that
    nothing can read.
    """
    bad = np.flatnonzero(~np.isfinite(values))
    if len(bad):
        i = int(bad[0])
        raise WirecalError(
            f"the {what} of step {steps[i]} "
            + ("zero reading" if indices[i] == 0 else f"point {indices[i]}")
            + f" is {values[i]} ({len(bad)} reading(s) in all): check {cause} "
            "(sizes in mm and deg; the true errors, scale and drift within their bounds)"
        )


def _reference_rows(
    enc: Encoder,
    truth: EncoderTruth,
    plan: Plan,
    noise_mm: float,
    samples: int,
    start: float,
    seed: int,
    total_s: float,
) -> list[Reading]:
    """Return the log rows of the reference step (none when the robot file asks for none).

    Drawn from a generator of their own, so the plan's readings of a seed stay the same.
    """
    lengths = reference_lengths(enc, truth)
    if not len(lengths):
        return []
    rng = np.random.default_rng([seed, 5])
    times = OPERATOR_SEAT_S * np.arange(len(lengths))
    physical = lengths + rng.normal(0.0, noise_mm, len(lengths))
    reading = physical * truth.read_factor(times, total_s) + truth.drift_mm(times)
    mean, spread = sample_counts(reading, enc.mm_per_count, start, enc.counter, samples, rng)
    return [
        _reading("reference", REFERENCE_STEP, i + 1, plan.theta0_deg, c, samples, sp, t, 0.0)
        for i, (c, sp, t) in enumerate(zip(mean, spread, times, strict=True))
    ]
