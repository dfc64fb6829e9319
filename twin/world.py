"""The physical world of the digital twin, whatever language the controller speaks.

:class:`World` is the cell a controller program acts on: a true robot (nominal model +
error offsets) within its joint limits, a draw-wire encoder mounted at θ0 of the true
robot (its wire over the exit as built, noise per pose, quantisation, ±1-count jitter, a
counter that starts anywhere, a range limit, the wire's speed and acceleration limits), a
vibration of the tool point along the wire after each move that decays (the settling
model of :mod:`wirecal.solver.run_parameters`), unmodelled joint errors, a touch probe
over a plate, a disk in a sandbox folder, an operator with scripted answers, the console
they read, and a clock. :class:`Faults` (one type for every language) injects a wire
slip, an encoder failure, a full disk, a vibration that does not decay, tighter joint
limits than the plan assumed, a dropped connection, a missing conveyor option. A move
that would take the arm into itself, the floor or a keep-out volume of ``[cell]`` is
reported with the colliding pair (:meth:`World.collision`), as a real protective stop.

A language's controller adapter (``twin/<key>/controller.py``) holds a World and maps its
instructions onto these methods, raising its own errors with its own codes:

* motion: :meth:`move`, the one move protocol: it refuses a target beyond the
  controller's joint limits (:class:`BeyondLimit`), a move into the arm itself, the floor
  or the cell (:class:`Collision`), a move that would run the wire beyond the encoder's
  speed or acceleration (:class:`WireOverspeed`), in that order, returning the
  :data:`Refusal` the controller maps to its own stop; else the arm arrives (after the
  profile's time, or the language's own) and vibrates along the wire. ``joints``
  (commanded, deg, single precision), ``actual`` (where the arm really is), ``moves``
  (counted; a run sets it to 0 after mounting);
* encoder: :meth:`read_count` (one read, the unwrapped count; wrap it with the counter the
  language reads; raises :class:`EncoderFailure`, :class:`~wirecal.twin.machine.RunError`
  −1100 beyond the wire's range);
* operator and console: :meth:`show`, :meth:`answer`, :meth:`steady`;
* probe: :meth:`probe_touching`; disk: ``disk``, :meth:`append_line`; time: ``clock``,
  :meth:`wait`.

A run's result is a :class:`TwinRun`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.solver.cell.sweep import Sweeps
from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import off_the_wire, physical_wire_mm
from wirecal.solver.ik.solutions import flange_pose
from wirecal.solver.kinematics import loaded, tool_position
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    MOVE_OVERHEAD_S,
    VIBRATION_HZ,
    VIBRATION_TAU_S,
    Moves,
    move_profiles,
    one_travel_duration_s,
)
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    OPERATOR_SEAT_S,
    RANGE_EXCEEDED,
    EncoderTruth,
    Unmodelled,
    reference_lengths,
)
from wirecal.twin.machine import Outcome, RunError, f32

JITTER_COUNTS = (-1, 0, 0, 0, 1)
"""A reading's ±1-count jitter, drawn uniformly from these (the same draw as
``rng.choice(JITTER_COUNTS)``, at an eighth of its cost: the twin reads the encoder thousands
of times per run)."""

IN_PLACE_DEG = 1e-3
"""A move shorter than this on every joint (deg) stays in place: a target equal to the
commanded joints up to a language's literals (URScript's radians, single precision)."""

RANGE_EXCEEDED_CODE = -1100
"""The twin's own code for a wire pulled beyond the encoder's range."""


@dataclass(frozen=True)
class Faults:
    """Faults to inject into a run (positions are 1-based counts of events)."""

    slip_at_move: int | None = None  # the wire slips when this move starts
    slip_mm: float = 0.5
    encoder_fails_at_read: int | None = None
    disk_full_after_lines: int | None = None
    vibration_at_move: int | None = None  # still vibrating: the stop after this move
    vibration_counts: int = 20  # vibrates ±this, undamped, until the operator steadies it
    joint_max_deg: tuple[float, ...] | None = None  # the controller's own limits
    socket_drops_after_lines: int | None = None  # the connection to the PC drops
    no_conveyor_option: bool = False  # the controller lacks its encoder option


DEFAULT_UNMODELLED = Unmodelled()
"""The validation runs' unmodelled errors: the twin's repeatability and gravity sag."""


class EncoderFailure(Exception):
    """The encoder stopped counting (the fault ``encoder_fails_at_read``)."""


@dataclass(frozen=True)
class BeyondLimit:
    """A move's target beyond the controller's joint limits (joint 0-based, deg)."""

    joint: int
    target_deg: float
    min_deg: float
    max_deg: float


@dataclass(frozen=True)
class Collision:
    """A move into the arm itself, the floor or the cell: the move and the colliding pair."""

    where: str  # "move N to (q…): <the pair> … at joints (…)"


@dataclass(frozen=True)
class WireOverspeed:
    """A move that would run the wire beyond the encoder's speed or acceleration."""

    move: str  # "move N to (q…)"
    why: str  # the speed or acceleration and the encoder's limit


Refusal = BeyondLimit | Collision | WireOverspeed
"""Why :meth:`World.move` refused a move (each controller maps it to its own stop)."""


@dataclass(frozen=True)
class Plate:
    """A flat plate (granite) for the touch probe.

    A point on its top face and the face's outward normal, in the robot's base frame (mm).
    """

    point: tuple[float, float, float]
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass
class World:
    """The simulated robot, encoder, disk, operator and clock (see module docstring)."""

    robot: Robot
    truth: dict[str, float]
    mount_deg: np.ndarray
    disk: Path
    seed: int = 0
    noise_mm: float = 0.01
    counter_start: float = 0.0
    answers: list[str] = field(default_factory=lambda: ["1"])
    faults: Faults = Faults()
    proceed_on_pause: bool = False  # the operator continues after a pause
    plate: Plate | None = None
    probe_mm: tuple[float, float, float] = (0.0, 0.0, 100.0)  # probe tip, flange frame
    encoder_point_mm: tuple[float, float, float] | None = None  # fixed encoder (validation)
    unmodelled: Unmodelled | None = None
    wire_limits: bool = False  # the wire's speed and acceleration limits are enforced
    encoder_truth: EncoderTruth = IDEAL_ENCODER  # the true scale, temperature, drift
    run_s: float = 0.0  # the run's duration, for the temperature's time course
    pull_mm: Callable[[float], float] | None = None  # the operator pulls the wire (clock, s)
    payload: tuple[float, tuple[float, float, float]] | None = None  # the plan's mass, centre

    def __post_init__(self) -> None:
        """Derive the true model and start the world's state."""
        self.rng = np.random.default_rng(self.seed)
        self.model = self.robot.model(self.truth)
        if self.unmodelled is not None:  # the arm repeats as the robot file declares
            self.unmodelled = self.unmodelled.for_robot(self.robot)
        self.p0 = tool_position(self.model, np.radians(self.mount_deg)[None])[0]
        if self.encoder_point_mm is not None:
            self.p0 = np.asarray(self.encoder_point_mm, dtype=float)
        self.joints = tuple(f32(x) for x in self.mount_deg)
        self.actual = np.asarray(self.joints, dtype=float)
        # the arm's limits as the controller enforces them (a fault may make them tighter)
        self.limits = (
            replace(self.robot, joint_max_deg=np.asarray(self.faults.joint_max_deg, dtype=float))
            if self.faults.joint_max_deg
            else self.robot
        )
        self.console: list[str] = []
        self.clock = 0.0
        self.moves = 0
        self.reads = 0
        self.lines_written = 0
        self.pose_error = self.rng.normal(0, self.noise_mm)
        self.slip = 0.0
        self._wire_at: tuple[np.ndarray, float] | None = None  # (actual, its wire mm)
        # amplitude (mm, or the move whose profile gives it when first read), τ, phase, since
        self.vibration: tuple[float | Callable[[], float], float, float, float] = (
            0.0,
            VIBRATION_TAU_S,
            0.0,
            0.0,
        )
        self.sweeps = Sweeps(self.robot, self.model, self.p0, contact=True)
        self.nest: int | None = None  # the gauge nest the wire tip is seated in (0 A, 1 B)
        self.gauge_mm = reference_lengths(self.robot.encoder, self.encoder_truth)[:2]
        self.mounted_kg = 0.0  # the mass the operator has mounted at the flange

    # ---- operator and console ----
    def show(self, text: str) -> None:
        """Show a line on the console the operator reads."""
        self.console.append(text)

    def answer(self, text: str) -> str | None:
        """Ask the operator ``text``; their scripted answer (None: nobody answers).

        A confirmed (1) "Seat the tip in nest A/B" seats the wire tip in that nest of the
        reference gauge, taking the operator's time; after "reattached" it is back on the
        flange fixture.
        """
        self.show(text)
        if not self.answers:
            return None
        answer = self.answers.pop(0)
        self.show(f"> {answer}")
        if answer.strip() == "1":
            self.handle_mass(text)
        if answer.strip() == "1" and len(self.gauge_mm):
            self.clock += OPERATOR_SEAT_S
            self.pose_error = self.rng.normal(0, self.noise_mm)  # each seating anew
            if "nest A" in text:
                self.nest = 0
            elif "nest B" in text:
                self.nest = 1
            elif "reattached" in text:
                self.nest = None
        return answer

    def handle_mass(self, text: str) -> None:
        """Mount or remove the plan's payload mass when a confirmed prompt asks for it.

        The programs' prompts say "when it is mounted" and "when it is removed" (V+ PROMPT
        answered 1, URScript popup continued); the operator holds the plan's mass
        (:attr:`payload`) and nothing else.
        """
        if self.payload is None:
            return
        if "when it is mounted" in text:
            self.mounted_kg = self.payload[0]
        elif "when it is removed" in text:
            self.mounted_kg = 0.0
        self._wire_at = None

    def flange_load_kg(self) -> float:
        """Return the load the flange truly carries (kg).

        The true robot's tool (its ``[gravity] payload_mass_kg``) and the mass mounted.
        """
        masses = self.robot.masses
        return self.mounted_kg + (0.0 if masses is None else masses.payload_mass_kg)

    def steady(self) -> bool:
        """At a pause: whether the operator continues (having steadied the arm)."""
        if self.proceed_on_pause:
            self.vibration = (0.0, VIBRATION_TAU_S, 0.0, self.clock)
        return self.proceed_on_pause

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` pass."""
        self.clock += seconds

    # ---- motion ----
    def move(
        self,
        q_deg: np.ndarray,
        speed_pct: float,
        duration_s: float | None = None,
        ramp_s: float = MOVE_OVERHEAD_S,
    ) -> Refusal | None:
        """Move the arm to ``q_deg`` at ``speed_pct``, or return why the cell refuses.

        Checks, in this order, the controller's joint limits (``limits``), a collision on
        the joint-interpolated move, the wire's speed and acceleration (when the run
        enforces them: ``wire_limits``; ``ramp_s`` the time to reach cruise, the
        language's own when its move names an acceleration); the arm then arrives after
        ``duration_s`` (the language's own move time) or the move profile's, and vibrates
        along the wire. A
        target within :data:`IN_PLACE_DEG` of the commanded joints is a move in place (no
        travel: the profile of a vanishing move is not resolved).
        """
        q = np.asarray(q_deg, dtype=float)
        lo, hi = self.limits.limits_deg(body=False)
        beyond = np.flatnonzero((q < lo) | (q > hi))
        if beyond.size:
            j = int(beyond[0])
            return BeyondLimit(j, float(q[j]), float(lo[j]), float(hi[j]))
        hit = self._collision(q)
        if hit is not None:
            return Collision(f"{self._move_name(q)}: {hit}")
        start = np.asarray(self.joints, dtype=float)
        end = start if float(np.abs(q - start).max()) < IN_PLACE_DEG else q
        move = self._profile(start, end) if self.wire_limits else None
        over = None if move is None else self._wire_overspeed(move, speed_pct, ramp_s)
        if over is not None:
            return WireOverspeed(self._move_name(q), over)
        speed = np.asarray(speed_pct)
        if duration_s is None:
            duration_s = one_travel_duration_s(self.robot, start, end, speed_pct)
        self._arrive(q, duration_s)
        self._vibrate(lambda: float((move or self._profile(start, end)).vibration_mm(speed)[0]))
        return None

    def _move_name(self, q_deg: np.ndarray) -> str:
        """Name the next move: its number and target (deg)."""
        return f"move {self.moves + 1} to ({', '.join(f'{x:g}' for x in q_deg)})"

    def _collision(self, q_deg: np.ndarray) -> str | None:
        """Return where the true arm collides on the move to ``q_deg``, or None.

        The joint-interpolated move from the current joints, sampled as the planner
        samples moves (a straight-line move is sampled in joint space too), against the
        arm's body and the robot file's ``[cell]``: where the true arm's capsules touch
        (the planner's margin aside), a real arm would stop (a protective stop).
        """
        return self.sweeps.collision(np.asarray(self.joints, dtype=float), q_deg)

    def _profile(self, start_deg: np.ndarray, end_deg: np.ndarray) -> Moves:
        """Return the move from ``start_deg`` to ``end_deg`` on the true arm."""
        return move_profiles(self.robot, self.model, self.p0, start_deg, end_deg)

    def _wire_overspeed(self, move: Moves, speed_pct: float, ramp_s: float) -> str | None:
        """Return why ``move`` at ``speed_pct`` would run the wire beyond the encoder's limits.

        None when within them, or when the run does not enforce them (``wire_limits``).
        """
        enc = self.robot.encoder
        if not self.wire_limits:
            return None
        speed = float(move.wire_speed_mm_s(np.asarray(speed_pct))[0])
        accel = float(move.wire_accel_mm_s2(np.asarray(speed_pct), ramp_s)[0])
        if enc.max_wire_speed_mm_s is not None and speed > enc.max_wire_speed_mm_s:
            return (
                f"the wire would run at {speed:.0f} mm/s, beyond the encoder's "
                f"max_wire_speed_mm_s {enc.max_wire_speed_mm_s:g}"
            )
        if enc.max_wire_accel_mm_s2 is not None and accel > enc.max_wire_accel_mm_s2:
            return (
                f"the wire would accelerate at {accel:.0f} mm/s², beyond the encoder's "
                f"max_wire_accel_mm_s2 {enc.max_wire_accel_mm_s2:g}"
            )
        return None

    def _arrive(self, q_deg: np.ndarray, seconds: float) -> None:
        """End a move at ``q_deg`` after ``seconds``: the clock, the true arm, the faults."""
        self.clock += seconds
        self.joints = tuple(f32(x) for x in q_deg)
        self.actual = q_deg + self._unmodelled(q_deg)
        self.moves += 1
        f = self.faults
        if f.slip_at_move is not None and self.moves == f.slip_at_move:
            self.slip += f.slip_mm
        self.pose_error = self.rng.normal(0, self.noise_mm)

    def _vibrate(self, amplitude_mm: Callable[[], float]) -> None:
        """Start the vibration along the wire after a move.

        It decays, or with the fault "still vibrating" it does not, until the operator
        steadies the arm at a pause. ``amplitude_mm`` is evaluated when the encoder is
        first read (a run that reads no count after a move skips the move's profile).
        """
        f = self.faults
        phase = float(self.rng.uniform(0, 2 * math.pi))
        if f.vibration_at_move is not None and self.moves == f.vibration_at_move:
            amplitude = f.vibration_counts * abs(self.robot.encoder.mm_per_count)
            self.vibration = (amplitude, math.inf, phase, self.clock)
        else:
            self.vibration = (amplitude_mm, VIBRATION_TAU_S, phase, self.clock)

    def _unmodelled(self, q_deg: np.ndarray) -> np.ndarray:
        """Where the arm really is, relative to the commanded joints (deg)."""
        u = self.unmodelled
        if u is None:
            return np.zeros_like(q_deg)
        return u.joint_errors_deg(self.model, q_deg, self.rng)

    def probe_touching(self) -> bool:
        """Tell whether the touch probe's true tip is on or below the plate."""
        if self.plate is None:
            return False
        R, o = flange_pose(self.model, np.radians(self.actual))
        tip = o + R @ np.asarray(self.probe_mm)
        depth = np.dot(tip - np.asarray(self.plate.point), np.asarray(self.plate.normal))
        return bool(depth <= 0)

    # ---- encoder ----
    def read_count(self) -> int:
        """Read the encoder once: the count of the wire now, unwrapped.

        Raises :class:`EncoderFailure` from the faulty read on.
        """
        self.reads += 1
        f = self.faults
        if f.encoder_fails_at_read is not None and self.reads >= f.encoder_fails_at_read:
            raise EncoderFailure(f"the encoder failed at read {self.reads}")
        return self._wire_counts()

    def _wire_counts(self) -> int:
        """Return the encoder's count for the true wire length now, before any wrap.

        Gaussian noise per pose, quantisation, ±1-count jitter, the vibration after the
        last move, a slip, the wire the operator pulls out; a wire pulled beyond the
        encoder's range is an error.
        """
        enc = self.robot.encoder
        if self.nest is not None:  # the tip in a nest of the reference gauge
            d = float(self.gauge_mm[self.nest]) + self.pose_error
        else:
            d = self._wire_mm() + self.pose_error + self.slip
        if d > enc.range_mm:
            raise RunError(
                RANGE_EXCEEDED_CODE,
                f"{RANGE_EXCEEDED}: the wire would be {d:.1f} mm long, beyond the "
                f"encoder's range_mm {enc.range_mm:g}",
            )
        amplitude, tau, phase, since = self.vibration
        if callable(amplitude):
            amplitude = amplitude()
            self.vibration = (amplitude, tau, phase, since)
        t = self.clock - since
        d += amplitude * math.exp(-t / tau) * math.cos(2 * math.pi * VIBRATION_HZ * t + phase)
        jitter = JITTER_COUNTS[int(self.rng.integers(0, len(JITTER_COUNTS)))]  # = rng.choice's draw
        truth = self.encoder_truth  # what the encoder reads of it: scale, temperature, drift
        now = np.asarray(self.clock)
        d = float(truth.read_factor(now, self.run_s)) * d + float(truth.drift_mm(now))
        count = math.floor(self.counter_start + d / enc.mm_per_count + 0.5) + jitter
        pulled = self.pull_mm(self.clock) if self.pull_mm is not None else 0.0
        return count + round(pulled / enc.mm_per_count)

    def _wire_mm(self) -> float:
        """Return the true wire length where the arm stands.

        Kept while the arm stands: the settle rule reads the counter several times per point.
        """
        if self._wire_at is None or self._wire_at[0] is not self.actual:
            model = self.model
            if self.mounted_kg and self.payload is not None:
                model = loaded(model, [self.mounted_kg], self.payload[1])
            p = tool_position(model, np.radians(self.actual)[None])[0]
            exit_ = self.robot.encoder.exit
            wire = float(physical_wire_mm(exit_, p - self.p0))
            if not math.isfinite(wire) and exit_ is not None:  # never a NaN count
                raise WirecalError(
                    f"the twin: the arm at joints {np.round(self.actual, 4).tolist()} deg "
                    f"puts the tool point {off_the_wire(exit_, p - self.p0)}: the exit is "
                    "modelled where the arm stood at θ0 when mounted, and the arm comes back "
                    "with its repeatability and gravity sag, which a guide pulley's or an "
                    "eyelet edge's circle leaves no wire for (not modelled yet: "
                    'docs/accuracy.md); simulate this arm with exit = "point"'
                )
            self._wire_at = (self.actual, wire)
        return self._wire_at[1]

    # ---- disk ----
    def append_line(self, path: Path, text: str) -> bool:
        """Append a line to a file on the disk, written through; False when the disk is full."""
        f = self.faults
        if f.disk_full_after_lines is not None and self.lines_written >= f.disk_full_after_lines:
            return False
        with open(path, "a", encoding="ascii", newline="\n") as fh:
            fh.write(text + "\n")  # written through: a stopped run leaves its lines
        self.lines_written += 1
        return True


@dataclass
class TwinRun:
    """A measurement run in the twin: the log the PC reads and how the programs ended."""

    log: Path  # the log the PC reads (an incomplete run's journal where there is one)
    complete: bool  # the log holds the whole run
    stopped: str | None  # why not complete (None when it is)
    world: World
    mount: Outcome  # the mounting program's outcome
    run: Outcome | None  # the measurement program's (None: not started)
    controller: Any = None  # the language's controller adapter, with its own state


def measurement_world(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    folder: Path,
    counter: Counter,
    *,
    seed: int = 0,
    noise_mm: float = 0.01,
    counter_start: float | None = None,
    faults: Faults | None = None,
    unmodelled: Unmodelled | None = None,
    wire_limits: bool = True,
    **world: Any,
) -> World:
    """Return the world of a measurement run, whatever the language: the one run factory.

    The arm at the plan's θ0 with offsets ``truth``, the disk ``folder`` (created), the
    count at zero wire length on the ``counter`` the language reads
    (:func:`counter_start_of`), the wire's speed and acceleration limits enforced unless
    ``wire_limits`` is False. ``world``: further :class:`World` fields (the operator's
    answers, the encoder's truth…).
    """
    folder.mkdir(parents=True, exist_ok=True)
    pay = plan.payload_step
    return World(
        robot,
        truth,
        plan.theta0_deg,
        folder,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=counter_start_of(counter, seed, counter_start),
        faults=faults or Faults(),
        unmodelled=unmodelled,
        wire_limits=wire_limits,
        payload=None if pay is None else (pay.payload_kg, pay.payload_com_mm),
        **world,
    )


def payload_prompts(plan: Plan) -> int:
    """Return the prompts of a plan's payload step: mount the mass, remove it (none without)."""
    return 0 if plan.payload_step is None else 2


def mount_then_run(
    world: World, mount: Callable[[], Outcome], run: Callable[[], Outcome]
) -> tuple[Outcome, Outcome | None]:
    """Run the mounting program, then (if it completed) the measurement program.

    The world's move count starts again for the run: fault positions count its moves
    (:func:`~wirecal.twin.run_moves.move_of_step`).
    """
    mounted = mount()
    world.moves = 0
    return mounted, run() if mounted.status == "completed" else None


def counter_start_of(counter: Counter, seed: int, counter_start: float | None) -> float:
    """Return a measurement run's count at zero wire length.

    ``counter_start`` when given, else drawn over the whole ``counter``'s range from the
    run's own random stream (``seed``, stream 2), so the run's counts may wrap.
    """
    if counter_start is not None:
        return float(counter_start)
    return float(counter.random_start(np.random.default_rng([seed, 2])))


def stop_reason(mount: Outcome, run: Outcome | None) -> str | None:
    """Why a mount-then-run pair did not complete (None when the run completed)."""
    last = run or mount
    if run is not None and run.status == "completed":
        return None
    return f"{last.program} {last.status} at line {last.line}: {last.message}"
