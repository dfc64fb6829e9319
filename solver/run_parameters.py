"""How a calibration run moves and reads, in one place.

The program's speed and acceleration, the settle rule and the counter readings per stop
(written into the generated programs), and the time model of a run that the planner's
robot-time estimate, the simulated log's ``t_s`` and the digital twin's clock share.

**Moves.** A joint-interpolated move q(s) = a + s·(b − a), s from 0 to 1, cruises at
ṡ = speed % × min_j(v_max,j / |b_j − a_j|) (the slowest joint at the program speed) with
an acceleration and a deceleration ramp of ``MOVE_OVERHEAD_S`` each, linear in ṡ (a
trapezoid): it lasts 1/ṡ + ``MOVE_OVERHEAD_S``. The wire runs at dℓ/dt = (dℓ/ds)·ṡ with
dℓ/ds = ûᵀ J(q(s)) (b − a) (û the wire's direction from the mount at θ0, J the tool
point's Jacobian: the Ψ of the θ offsets) and accelerates at d²ℓ/dt² = (d²ℓ/ds²)·ṡ² +
(dℓ/ds)·s̈, s̈ = ṡ/``MOVE_OVERHEAD_S`` on a ramp. :func:`move_speeds_pct` chooses each
move's SPEED: the program's ``speed_pct`` unless the encoder's ``max_wire_speed_mm_s`` or
``max_wire_accel_mm_s2`` (robot file, ``[encoder]``) asks for less; the twin raises an
error on a move whose wire exceeds them.

**Settling.** After a move the tool point vibrates along the wire: x(t) = A e^(−t/τ)
cos(2π f t + φ) with A growing with the move's peak tool-point speed and length
(:func:`vibration_amplitude_mm`; the twin's model, an estimate: τ ``VIBRATION_TAU_S``,
f ``VIBRATION_HZ``). The program waits ``settle_s``, then reads the counter every
``READING_INTERVAL_S`` until the last ``SETTLE_WINDOW`` readings lie within
``SETTLE_SPREAD_COUNTS`` counts (the settle rule), at most ``settle_max_s``; then it takes
``readings`` readings. :func:`settle_time_s` predicts when the rule passes.
:func:`run_timeline` lays a plan's run out in time: the ``t_s`` of each reading of the log.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from wirecal.solver.kinematics import joint_jacobian, tool_position
from wirecal.solver.memo import Kept, digest
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot

MOVE_OVERHEAD_S = 0.5
"""Duration of a move's acceleration ramp (and of its deceleration ramp): a move lasts
its travel at cruise speed plus this (an estimate, not measured on a controller: at ACCEL
20 % the ramps of a joint move take a few tenths of a second)."""

READING_INTERVAL_S = 0.02
"""Wait between two counter readings (the generated program's ``WAIT.EVENT , 0.02`` in
templates/vplus/measure.v2.j2), while settling and while sampling."""

SETTLE_WINDOW = 5
"""Readings the settle rule looks at: 5 readings span 80 ms, one period of a 12.5 Hz
vibration (a small arm's first mode is 10–20 Hz), so a vibration cannot hide between
them."""

SETTLE_SPREAD_COUNTS = 2
"""The settle rule: the window's readings spread over at most this many counts. A still
encoder reads its count ±1 (the counter's jitter), a spread of up to 2: a still
encoder passes the first full window, and a vibration passes only once its peak-to-peak
is within the jitter band, about a count (0.025 mm), still decaying while sampling."""

SETTLE_QUIET_COUNTS = 0.55
"""The vibration's envelope (counts) at the last reading of the window that passes the
settle rule, as the twin's runs show it (80 readings × 4 seeds of the paper plan: the rule
passes when the envelope was about 1.5 counts at the window's first reading, e^-1 of that
at its last, τ being the window's length): :func:`settle_time_s` predicts with it."""

WIRE_LIMIT_MARGIN = 0.8
"""The program's moves keep the wire at this fraction of the encoder's limits: the path
is sampled at ``PATH_SAMPLES`` points and the true robot differs from nominal (with random
offsets within ±1 deg/mm the twin's wire ran 15 % faster than the nominal plan on one
move of the paper plan, seed 2: 0.9 was not enough; 0.8 held on seeds 1–8)."""

PATH_SAMPLES = 33
"""Points along each move at which the wire speed is evaluated."""

AT_MOUNT_MM = 1e-3
"""A tool point nearer the mount than this is at it (the wire leaves at the tool's speed):
beyond the rounding of a controller's single-precision joints (a URScript target of -62
deg is held as -61.999996 deg: 4e-5 mm at the UR5's tool), whose random direction
would otherwise read as a kink in the wire's rate, 19,000 mm of d²ℓ/ds² instead of 18."""

VIBRATION_TAU_S = 0.08
"""Decay time constant of the vibration after a stop (the twin's model; an estimate)."""

VIBRATION_HZ = 12.0
"""Frequency of the vibration after a stop (the twin's model; an estimate)."""

VIBRATION_GAIN_S = 2e-4
"""Vibration amplitude per tool-point speed (mm per mm/s): 0.1 mm after a long move at
500 mm/s (the twin's model; an estimate)."""

VIBRATION_LENGTH_MM = 50.0
"""Moves much shorter than this excite proportionally less vibration."""

JITTER_COUNTS_RMS = math.sqrt(0.4)
"""RMS of one reading's jitter (counts): the twin's ±1 count, −1, 0, 0, 0, +1 equally
likely. It averages over the readings of a stop; the pose noise does not."""

POINT_SIGMA_MM = 0.01
"""Per-point reading noise that does not average over a stop's readings (σ of the CRB)."""


def optimal_readings(mm_per_count: float, stop_s: float = 1.2) -> int:
    """Return the readings per stop that minimise error² × time per point.

    A point's variance is σ_p² + σ_j²/N (σ_p: :data:`POINT_SIGMA_MM` and the quantisation
    mpc²/12, which do not average; σ_j: :data:`JITTER_COUNTS_RMS`) and its time
    T + N·δ (T: the move and the settle, ``stop_s``; δ: :data:`READING_INTERVAL_S`). Their
    product is least at N = (σ_j/σ_p)·√(T/δ): fewer readings leave jitter, more cost time
    that more points would use better.
    """
    sigma_p2 = POINT_SIGMA_MM**2 + mm_per_count**2 / 12
    sigma_j2 = (JITTER_COUNTS_RMS * mm_per_count) ** 2
    return max(1, round(math.sqrt(sigma_j2 * stop_s / (sigma_p2 * READING_INTERVAL_S))))


def vibration_amplitude_mm(peak_speed_mm_s: float, length_mm: float) -> float:
    """Vibration amplitude (mm) after a move: grows with its peak tool-point speed and length."""
    return VIBRATION_GAIN_S * peak_speed_mm_s * (1 - math.exp(-length_mm / VIBRATION_LENGTH_MM))


@dataclass(frozen=True)
class RunParameters:
    """The run's motion and reading parameters (``wirecal gen`` options)."""

    speed_pct: float = 100.0  # highest program speed, % of full; the wire may ask for less
    accel_pct: float = 20.0  # % of full acceleration and deceleration (ACCEL)
    settle_s: float = 0.0  # fixed wait after each stop before the settle rule (paper: 3 s)
    settle_max_s: float = 2.0  # the settle rule's longest wait: then the point is unsettled
    readings: int = 10  # counter readings per point: optimal_readings for a 0.025 mm count

    def problems(self) -> list[str]:
        """Return what is out of range, as ``wirecal gen``'s options name it."""
        out = []
        if not 0 < self.speed_pct <= 100:
            out.append(f"--speed {self.speed_pct:g}: give a percentage in (0, 100]")
        if not 0 < self.accel_pct <= 100:
            out.append(f"--accel {self.accel_pct:g}: give a percentage in (0, 100]")
        if not 0 <= self.settle_s <= 60:
            out.append(f"--settle-s {self.settle_s:g}: give 0–60 s")
        if not SETTLE_WINDOW * READING_INTERVAL_S <= self.settle_max_s <= 60:
            out.append(
                f"--settle-max-s {self.settle_max_s:g}: give "
                f"{SETTLE_WINDOW * READING_INTERVAL_S:g}–60 s (the settle rule's window)"
            )
        if not 1 <= self.readings <= 1000:
            out.append(f"--samples {self.readings}: give 1–1000")
        return out


DEFAULT_RUN = RunParameters()
"""The defaults of ``wirecal gen`` and of the planner's robot-time estimate."""

SAFE_SPEED_PCT = 20.0
"""SPEED (%) of the moves that no wire plan covers (wc.mount to θ0, the validation
programs): the paper's program speed."""

PAPER_RUN = RunParameters(speed_pct=20.0, settle_s=3.0)
"""The paper's run: 20 % speed and a fixed 3 s settle before reading."""


@dataclass(frozen=True)
class Moves:
    """Per move of a run: what the program speed does to it (all arrays (M,))."""

    wire_rate_mm: np.ndarray  # max |dℓ/ds| along the move
    wire_curve_mm: np.ndarray  # max |d²ℓ/ds²| along the move
    tool_rate_mm: np.ndarray  # max |dp/ds| along the move
    tool_length_mm: np.ndarray  # the tool point's path length
    cruise_per_pct: np.ndarray  # ṡ (1/s) at 1 % program speed (inf: no travel)

    def cruise(self, speed_pct: np.ndarray) -> np.ndarray:
        """ṡ (1/s) of each move at ``speed_pct``."""
        return self.cruise_per_pct * np.asarray(speed_pct, dtype=float)

    def duration_s(self, speed_pct: np.ndarray) -> np.ndarray:
        """Duration (s) of each move at ``speed_pct``: travel at cruise plus one ramp."""
        return travel_duration_s(self.cruise_per_pct, speed_pct)

    def wire_speed_mm_s(self, speed_pct: np.ndarray) -> np.ndarray:
        """Peak wire speed (mm/s) of each move at ``speed_pct``."""
        with np.errstate(invalid="ignore"):
            return _finite(self.wire_rate_mm * self.cruise(speed_pct))

    def wire_accel_mm_s2(
        self, speed_pct: np.ndarray, ramp_s: float = MOVE_OVERHEAD_S
    ) -> np.ndarray:
        """Bound on the peak wire acceleration (mm/s²) of each move at ``speed_pct``.

        ``ramp_s``: the time the move takes to reach cruise (a language's own, when its
        move names an acceleration; else the model's :data:`MOVE_OVERHEAD_S`).
        """
        c = _finite(self.cruise(speed_pct))
        return self.wire_curve_mm * c**2 + self.wire_rate_mm * c / ramp_s

    def vibration_mm(self, speed_pct: np.ndarray) -> np.ndarray:
        """Vibration amplitude (mm) after each move at ``speed_pct``."""
        with np.errstate(invalid="ignore"):
            peak = _finite(self.tool_rate_mm * self.cruise(speed_pct))
        return np.array(
            [vibration_amplitude_mm(v, s) for v, s in zip(peak, self.tool_length_mm, strict=True)]
        )


def travel_duration_s(cruise_per_pct: np.ndarray, speed_pct: np.ndarray) -> np.ndarray:
    """Duration (s) of moves at ``speed_pct``, ṡ at 1 % ``cruise_per_pct``: travel plus one ramp.

    Needs no more of a move than its joints' travel (:func:`cruise_per_pct`).
    """
    with np.errstate(divide="ignore"):
        return 1.0 / (cruise_per_pct * np.asarray(speed_pct, dtype=float)) + MOVE_OVERHEAD_S


def one_travel_duration_s(
    robot: Robot, start_deg: np.ndarray, end_deg: np.ndarray, speed_pct: float
) -> float:
    """Return the duration (s) of one move at ``speed_pct``, on Python floats.

    :func:`travel_duration_s` of :func:`cruise_per_pct` for the single move start → end
    (deg), the same number: the arrays' element-wise quotients, their largest, the cruise
    and the duration in the same operations. A quotient that is not finite (a NaN, which
    numpy's largest keeps and Python's may not) leaves the move to the arrays.
    """
    dq = [b - a for a, b in zip(start_deg.tolist(), end_deg.tolist(), strict=True)]
    speeds = robot.joint_speed_deg_s.tolist()
    quotients = [abs(d) / v if v else math.inf for d, v in zip(dq, speeds, strict=True)]
    if not all(math.isfinite(x) for x in quotients):
        travel = cruise_per_pct(robot, np.array([dq]))
        return float(travel_duration_s(travel, np.asarray(speed_pct))[0])
    slowest = max(quotients)
    cruise = 0.01 / slowest if slowest > 0 else math.inf
    rate = cruise * float(speed_pct)
    return (1.0 / rate if rate else math.copysign(math.inf, rate)) + MOVE_OVERHEAD_S


def _finite(x: np.ndarray) -> np.ndarray:
    """``x`` with the values of moves without travel (∞·0) as 0."""
    return np.where(np.isfinite(x), x, 0.0)


KEPT_MOVES = 1024
"""How many evaluations of :func:`move_profiles` are kept: a run's moves (the paper plan's
run has about 100), asked for again by every consumer of a plan's timeline (the program's
SPEEDs, the simulated log's and the twin's t_s, the log's timer check) and by the twin's
every run of the same program."""

_KEPT_MOVES: Kept[Moves] = Kept(KEPT_MOVES)


def move_profiles(
    robot: Robot, model, p0_mm: np.ndarray, starts_deg: np.ndarray, ends_deg: np.ndarray
) -> Moves:
    """Evaluate moves from ``starts_deg`` to ``ends_deg`` (M, n) along their joint paths.

    ``model`` is the kinematic model (nominal for the program, the true one in the twin);
    ``p0_mm`` the wire's mount point (the tool point at θ0). dℓ/ds is analytic (the
    Jacobian); d²ℓ/ds² its difference along the ``PATH_SAMPLES`` samples. Kept by the
    contents of what they are computed from (:mod:`~wirecal.solver.memo`): the same moves
    of the same model are evaluated once, their arrays read-only.
    """
    a = np.atleast_2d(np.asarray(starts_deg, dtype=float))
    b = np.atleast_2d(np.asarray(ends_deg, dtype=float))
    p0 = np.asarray(p0_mm, dtype=float)
    key = digest(robot.joint_speed_deg_s, model, p0, a, b)
    return _KEPT_MOVES.get(key, lambda: _profiles(robot, model, p0, a, b))


def _profiles(robot: Robot, model, p0_mm: np.ndarray, a: np.ndarray, b: np.ndarray) -> Moves:
    """:func:`move_profiles` of the moves a → b (M, n), computed, its arrays read-only."""
    s = np.linspace(0.0, 1.0, PATH_SAMPLES)
    dq = b - a  # (M, n) deg
    q = a[:, None, :] + s[None, :, None] * dq[:, None, :]  # (M, S, n)
    p, J = joint_jacobian(model, np.radians(q.reshape(-1, q.shape[-1])))
    dp = np.einsum("kcj,kj->kc", J, np.radians(np.repeat(dq, len(s), axis=0)))  # dp/ds
    p, dp = p.reshape(*q.shape[:2], 3), dp.reshape(*q.shape[:2], 3)
    wire = p - np.asarray(p0_mm, dtype=float)
    length = np.linalg.norm(wire, axis=2)
    tool_rate = np.linalg.norm(dp, axis=2)
    with np.errstate(invalid="ignore", divide="ignore"):
        rate = np.einsum("msc,msc->ms", wire, dp) / length
    rate = np.where(length > AT_MOUNT_MM, rate, tool_rate)  # leaving the mount: tool's speed
    curve = np.gradient(rate, s, axis=1)
    seg = np.linalg.norm(np.diff(p, axis=1), axis=2).sum(axis=1)
    out = (
        np.abs(rate).max(axis=1),
        np.abs(curve).max(axis=1),
        tool_rate.max(axis=1),
        seg,
        cruise_per_pct(robot, dq),
    )
    for x in out:
        x.flags.writeable = False
    return Moves(*out)


def cruise_per_pct(robot: Robot, dq_deg: np.ndarray) -> np.ndarray:
    """ṡ (1/s) at 1 % program speed of moves by ``dq_deg`` (M, n): the slowest joint's.

    Infinite for a move without travel.
    """
    slowest = (np.abs(dq_deg) / robot.joint_speed_deg_s).max(axis=1)
    with np.errstate(divide="ignore"):
        return np.where(slowest > 0, 0.01 / slowest, np.inf)


def move_speeds_pct(robot: Robot, moves: Moves, speed_pct: float) -> np.ndarray:
    """Each move's SPEED (%): ``speed_pct`` unless the wire limits ask for less.

    The largest speed, in steps of 0.1 %, at which the move's peak wire speed and wire
    acceleration stay within :data:`WIRE_LIMIT_MARGIN` of the encoder's
    ``max_wire_speed_mm_s`` and ``max_wire_accel_mm_s2`` (each unlimited if not given).
    """
    enc = robot.encoder
    c_max = np.full(len(moves.cruise_per_pct), np.inf)  # the largest ṡ the wire allows
    with np.errstate(divide="ignore", invalid="ignore"):
        if enc.max_wire_speed_mm_s is not None:
            c_max = np.minimum(
                c_max, WIRE_LIMIT_MARGIN * enc.max_wire_speed_mm_s / moves.wire_rate_mm
            )
        if enc.max_wire_accel_mm_s2 is not None:
            # curve·c² + rate·c/T ≤ margin·a_max: the positive root of the quadratic
            A, B = moves.wire_curve_mm, moves.wire_rate_mm / MOVE_OVERHEAD_S
            C = WIRE_LIMIT_MARGIN * enc.max_wire_accel_mm_s2
            root = np.where(A > 0, 2 * C / (B + np.sqrt(B**2 + 4 * A * C)), C / B)
            c_max = np.minimum(c_max, root)
        pct = np.floor(10 * c_max / moves.cruise_per_pct) / 10
    pct = np.where(np.isfinite(pct), pct, speed_pct)
    return np.clip(pct, 0.1, speed_pct)


def move_durations_s(
    robot: Robot,
    run: RunParameters,
    starts_deg: np.ndarray,
    ends_deg: np.ndarray,
    model=None,
    p0_mm: np.ndarray | None = None,
) -> np.ndarray:
    """Duration (s) of each move, at the SPEED the wire allows (as the program moves).

    ``model`` defaults to the nominal one; ``p0_mm`` (the mount, the tool point at θ0) is
    needed when the encoder has wire limits.
    """
    model = robot.nominal if model is None else model
    p0 = np.zeros(3) if p0_mm is None else p0_mm
    moves = move_profiles(robot, model, p0, starts_deg, ends_deg)
    return moves.duration_s(move_speeds_pct(robot, moves, run.speed_pct))


def settle_time_s(amplitude_mm: np.ndarray, mm_per_count: float, run: RunParameters) -> np.ndarray:
    """Predicted wait (s) from the end of a move to the end of the settle rule.

    ``settle_s``, then readings every :data:`READING_INTERVAL_S` until the last reading of
    a full window of :data:`SETTLE_WINDOW` comes after the vibration's envelope fell to
    :data:`SETTLE_QUIET_COUNTS`, at most ``settle_max_s``.
    """
    a = np.asarray(amplitude_mm, dtype=float) / abs(mm_per_count)
    quiet_s = VIBRATION_TAU_S * np.log(np.maximum(a, 1e-12) / SETTLE_QUIET_COUNTS)
    last = np.ceil(np.maximum(0.0, quiet_s - run.settle_s) / READING_INTERVAL_S - 1e-9)
    waited = np.maximum(last, SETTLE_WINDOW - 1) * READING_INTERVAL_S
    return run.settle_s + np.minimum(waited, run.settle_max_s)


@dataclass(frozen=True)
class Timeline:
    """When a run of a plan reads: its time model, as the log's ``t_s`` column."""

    reading_s: np.ndarray  # s from the start of the run to the sampling of each reading
    settle_s: np.ndarray  # each reading's wait after its move (the log's settle_s)
    speed_pct: np.ndarray  # each move's SPEED, in the generated program's order
    total_s: float  # the whole run, to the end of the closing zero reading


def run_targets_deg(plan: Plan) -> tuple[np.ndarray, np.ndarray]:
    """Every move's target of a run of ``plan`` in order, and whether it reads there.

    Per step θ0 (its zero reading), the via points (no stop), the points; last θ0 for the
    closing zero reading.
    """
    targets: list[np.ndarray] = []
    reads: list[bool] = []
    for step in plan.steps:
        targets.append(plan.theta0_deg)
        reads.append(True)
        targets += list(step.via_deg)
        reads += [False] * len(step.via_deg)
        targets += list(step.points_deg)
        reads += [True] * len(step.points_deg)
    targets.append(plan.theta0_deg)
    reads.append(True)
    return np.asarray(targets, dtype=float), np.asarray(reads)


def plan_moves(robot: Robot, plan: Plan, model=None) -> Moves:
    """Return the moves of a run of ``plan`` (from θ0, where the run starts), nominal model."""
    model = robot.nominal if model is None else model
    targets, _ = run_targets_deg(plan)
    starts = np.vstack([plan.theta0_deg, targets[:-1]])
    p0 = tool_position(model, np.radians(plan.theta0_deg)[None])[0]
    return move_profiles(robot, model, p0, starts, targets)


def run_timeline(robot: Robot, plan: Plan, run: RunParameters) -> Timeline:
    """Lay out a run of ``plan`` in time, in the generated program's order.

    Each step moves to θ0 (zero reading), through its via points (blended, no stop) and to
    each point (settle, read); last a move to θ0 for the closing zero reading. Each move at
    its SPEED (:func:`move_speeds_pct`); each stop waits as :func:`settle_time_s` predicts
    and reads ``readings`` times, one :data:`READING_INTERVAL_S` apart. The run starts at
    θ0 with the timer at zero; a reading's time is when its sampling begins.
    """
    _, reads = run_targets_deg(plan)
    moves = plan_moves(robot, plan)
    speed = move_speeds_pct(robot, moves, run.speed_pct)
    duration = moves.duration_s(speed)
    settle = settle_time_s(moves.vibration_mm(speed), robot.encoder.mm_per_count, run)
    stop = np.where(reads, settle + READING_INTERVAL_S * (run.readings - 1), 0.0)
    end = np.cumsum(duration + stop)
    reading_s = (end - stop + settle)[reads]
    return Timeline(reading_s, settle[reads], speed, float(end[-1]))
