"""The digital twin: a simulated cell that runs the generated V+ programs as written.

:class:`Cell` is the controller's outside world for :class:`~wirecal.twin.vplus.interp.Interpreter`:
a true robot (nominal model + error offsets) whose moves respect the joint limits, a
draw-wire encoder mounted at θ0 of the true robot (its wire over the exit as built, noise
per pose, quantisation, ±1-count jitter, a wrapping counter, a range limit, the wire's
speed and acceleration limits), a vibration of the tool point along the wire after each
move that decays (the settling model of :mod:`wirecal.solver.run_parameters`; the wire
limits are enforced in :func:`run_measurement`, where the wire is mounted at θ0 and every
move is planned for it; the validation programs move at 20 % without a wire plan), a disk
in a sandbox folder, a terminal with scripted answers, and a clock. Faults can be
injected: a wire slip, an encoder failure, a full disk, a vibration that does not decay
("still vibrating"), tighter joint limits than the plan assumed. A move that would take
the arm into itself, the floor or a keep-out volume of ``[cell]`` stops the run with the
colliding pair (:meth:`Cell.collision`), as a real protective stop would.

Error codes of the twin's own making (the V+ manual's codes are used where known:
−1013 encoder quadrature error, User's Guide p. 354) are listed in ``ERRORS``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from wirecal.lang.vplus.parser import parse_module
from wirecal.solver import ik
from wirecal.solver.cell_check import move_collision
from wirecal.solver.exit_geometry import physical_wire_mm
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import (
    DEFAULT_RUN,
    VIBRATION_HZ,
    VIBRATION_TAU_S,
    move_profiles,
    run_timeline,
)
from wirecal.solver.simulate import (
    IDEAL_ENCODER,
    OPERATOR_SEAT_S,
    RANGE_EXCEEDED,
    EncoderTruth,
    Unmodelled,
    reference_duration_s,
    reference_lengths,
)
from wirecal.twin.machine import Outcome, RunError, f32
from wirecal.twin.vplus.interp import UNMODELLED, Interpreter, Trans, VError

ERRORS = {
    1: "Success",
    -500: "*File already exists*",
    -501: "*File not found*",
    -514: "*File not open*",
    -522: "*Device full*",
    -526: "*No data received*",
    -1004: "*Joint out of range*",
    -1013: "*Encoder quadrature error*",
    -1100: RANGE_EXCEEDED,
    -1101: "*Wire overspeed*",
    -1102: "*Protective stop: collision*",
}
PROTECTIVE_STOP = -1102
"""The twin's code for a move that would collide (its own: V+'s own message for a
collision stop is not modelled)."""


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
    socket_drops_after_lines: int | None = None  # URScript: the connection to the PC drops
    no_conveyor_option: bool = False  # V+: ENABLE BELT leaves the BELT switch off


DEFAULT_UNMODELLED = Unmodelled()
"""The validation runs' unmodelled errors: the twin's repeatability and gravity sag."""


@dataclass(frozen=True)
class Plate:
    """A flat plate (granite) for the touch probe.

    A point on its top face and the face's outward normal, in the robot's base frame (mm).
    """

    point: tuple[float, float, float]
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)


@dataclass
class Cell:
    """The simulated robot, encoder, disk and terminal (see module docstring)."""

    robot: Robot
    truth: dict[str, float]
    mount_deg: np.ndarray
    disk: Path
    seed: int = 0
    noise_mm: float = 0.01
    counter_start: float = 0.0
    answers: list[str] = field(default_factory=lambda: ["1"])
    faults: Faults = Faults()
    proceed_on_pause: bool = False
    controller: dict[str, float] = field(default_factory=dict)  # the model the controller
    plate: Plate | None = None  # believes: nominal + these
    probe_mm: tuple[float, float, float] = (0.0, 0.0, 100.0)  # probe tip, flange frame
    probe_signal: int = 1001
    encoder_point_mm: tuple[float, float, float] | None = None  # fixed encoder (validation)
    unmodelled: Unmodelled | None = None
    wire_limits: bool = False  # the wire's speed and acceleration limits are enforced
    encoder_truth: EncoderTruth = IDEAL_ENCODER  # the true scale, temperature, drift
    run_s: float = 0.0  # the run's duration, for the temperature's time course

    def __post_init__(self):
        """Derive the true and believed models and start the cell's state."""
        self.rng = np.random.default_rng(self.seed)
        self.model = self.robot.model(self.truth)
        self.believed = self.robot.model(self.controller)
        self.requested: dict[int, str] = {}
        self.tool = "unknown"  # whatever a previous program left: TOOL sets it
        self.tools_at_cartesian: set[str] = set()  # the tool in force at each TRANS move
        self.p0 = tool_position(self.model, np.radians(self.mount_deg)[None])[0]
        self.joints = tuple(f32(x) for x in self.mount_deg)
        # the arm as the controller knows it: its own joint limits (a fault may make them
        # tighter than the plan assumed)
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
        self.speed_pct = 100.0
        self.pose_error = self.rng.normal(0, self.noise_mm)
        self.slip = 0.0
        self.belts: dict[str, int] = {}
        self.switches: set[str] = set()
        self.timers: dict[int, float] = {}  # timer number → the clock when it read zero
        self.luns: dict[int, dict] = {}
        self.status: dict[int, float] = {}
        if self.encoder_point_mm is not None:
            self.p0 = np.asarray(self.encoder_point_mm, dtype=float)
        self.actual = np.asarray(self.joints, dtype=float)
        self._wire_at: tuple[np.ndarray, float] | None = None  # (actual, its wire mm)
        self.vibration = (0.0, VIBRATION_TAU_S, 0.0, 0.0)  # amplitude mm, τ, phase, since
        self.nest: int | None = None  # the gauge nest the wire tip is seated in (0 A, 1 B)
        self.gauge_mm = reference_lengths(self.robot.encoder, self.encoder_truth)[:2]

    # ---- terminal ----
    def type_(self, text: str) -> None:
        """TYPE: append ``text`` to the console."""
        self.console.append(text)

    def prompt(self, text: str) -> str:
        """PROMPT: show ``text``; return the next scripted answer."""
        self.console.append(text)
        if not self.answers:
            raise VError(-526, "*No data received* (no scripted answer to the PROMPT)")
        answer = self.answers.pop(0)
        self.console.append(f"> {answer}")
        self._operator_seats(text, answer)
        return answer

    def _operator_seats(self, text: str, answer: str) -> None:
        """Do what the prompt asked the operator to do with the wire tip, if confirmed.

        "Seat the tip in nest A/B": the tip sits in that nest of the reference gauge; the
        prompt after "Reattach": back on the flange fixture.
        """
        if answer.strip() != "1" or not len(self.gauge_mm):
            return
        self.clock += OPERATOR_SEAT_S  # the operator's time
        self.pose_error = self.rng.normal(0, self.noise_mm)  # each seating anew
        if "nest A" in text:
            self.nest = 0
        elif "nest B" in text:
            self.nest = 1
        elif "reattached" in text:
            self.nest = None

    def on_pause(self) -> bool:
        """Return whether a PAUSE proceeds (as the operator would, who then steadies the arm)."""
        if self.proceed_on_pause:
            self.vibration = (0.0, VIBRATION_TAU_S, 0.0, self.clock)
        return self.proceed_on_pause

    # ---- motion ----
    def speed(self, pct: float) -> None:
        """SPEED: set the motion speed in percent."""
        self.speed_pct = pct

    def accel(self, *_args) -> None:
        """ACCEL: accepted; the twin's timing ignores it."""
        pass

    def configure(self, word: str) -> None:
        """ABOVE/BELOW, FLIP/NOFLIP, LEFTY/RIGHTY: a request for the next motion."""
        part = {"LEFTY": 0, "RIGHTY": 0, "ABOVE": 1, "BELOW": 1, "FLIP": 2, "NOFLIP": 2}[word]
        self.requested[part] = word.lower()

    def _joints_for(self, t: Trans) -> np.ndarray:
        """Solve the controller's inverse kinematics with its own model.

        The requested configuration where given, else the current one.
        """
        R, p = t.matrix()
        here = np.radians(self.joints)
        current = ik.configuration(self.believed, here)
        want = tuple(self.requested.get(k, current[k]) for k in range(3))
        if not self.requested:  # a step in the same configuration: follow it by Newton
            q, ok = ik.follow(self.believed, here, R, p)
            if ok and ik.configuration(self.believed, q) == current:
                return np.degrees(q)
        self.requested = {}
        for s in ik.solve(self.limits, R, p, model=self.believed):
            if s.config == want and s.within_limits:
                return np.degrees(s.q)
        raise VError(-931, f"*Location out of range* ({'/'.join(want)})")

    def tool_null(self) -> None:
        """TOOL NULL: the flange is the tool point (the cell models no other tool)."""
        self.tool = "null"

    def move(self, target, straight: bool = False) -> None:
        """MOVE/MOVES: go to joints, or to a pose through the controller's IK."""
        if isinstance(target, Trans):
            self.tools_at_cartesian.add(self.tool)
            target = self._joints_for(target)
        q = np.asarray(target, dtype=float)
        j = self.beyond_limits(q)
        if j is not None:
            raise VError(-1004, f"*Joint {j + 1} out of range* ({q[j]:g} deg)")
        hit = self.collision(q)
        if hit is not None:
            raise VError(PROTECTIVE_STOP, f"{ERRORS[PROTECTIVE_STOP]} {hit}")
        move = move_profiles(self.robot, self.model, self.p0, self.joints, q)
        if self.wire_limits:
            self._check_wire(move, q)
        self.arrive(q, float(move.duration_s(self.speed_pct)[0]))
        self._vibrate(float(move.vibration_mm(self.speed_pct)[0]))

    def collision(self, q_deg: np.ndarray) -> str | None:
        """Return where the true arm collides on the move to ``q_deg``, or None.

        The joint-interpolated move from the current joints, sampled as the planner
        samples moves (a straight-line MOVES is sampled in joint space too), against the
        arm's body and the robot file's ``[cell]``: where the true arm's capsules touch
        (the planner's margin aside), a real arm would stop (a protective stop), so the
        run stops with the move and the colliding pair.
        """
        start = np.asarray(self.joints, dtype=float)
        target = np.asarray(q_deg, float)
        hit = move_collision(self.robot, self.model, self.p0, start, target, contact=True)
        if hit is None:
            return None
        return f"move {self.moves + 1} to ({', '.join(f'{x:g}' for x in q_deg)}): {hit}"

    def beyond_limits(self, q_deg: np.ndarray) -> int | None:
        """Return the index of the first joint beyond the controller's limits, if any."""
        lo, hi = self.limits.joint_min_deg, self.limits.joint_max_deg
        out = np.flatnonzero((q_deg < lo) | (q_deg > hi))
        return int(out[0]) if out.size else None

    def arrive(self, q_deg: np.ndarray, seconds: float) -> None:
        """End a move at ``q_deg`` after ``seconds``: the clock, the true arm, the faults."""
        self.clock += seconds
        self.joints = tuple(f32(x) for x in q_deg)
        self.actual = q_deg + self._unmodelled(q_deg)
        self.moves += 1
        f = self.faults
        if f.slip_at_move is not None and self.moves == f.slip_at_move:
            self.slip += f.slip_mm
        self.pose_error = self.rng.normal(0, self.noise_mm)

    def _vibrate(self, amplitude_mm: float) -> None:
        """Start the vibration along the wire after a move.

        It decays, or with the fault "still vibrating" it does not, until the operator
        steadies the arm at a PAUSE.
        """
        f = self.faults
        phase = float(self.rng.uniform(0, 2 * math.pi))
        if f.vibration_at_move is not None and self.moves == f.vibration_at_move:
            amplitude = f.vibration_counts * abs(self.robot.encoder.mm_per_count)
            self.vibration = (amplitude, math.inf, phase, self.clock)
        else:
            self.vibration = (amplitude_mm, VIBRATION_TAU_S, phase, self.clock)

    def _check_wire(self, move, q: np.ndarray) -> None:
        """Refuse a move that would run the wire beyond the encoder's limits."""
        enc = self.robot.encoder
        speed = float(move.wire_speed_mm_s(self.speed_pct)[0])
        accel = float(move.wire_accel_mm_s2(self.speed_pct)[0])
        where = (
            f"move {self.moves + 1} to ({', '.join(f'{x:g}' for x in q)}) at SPEED "
            f"{self.speed_pct:g}"
        )
        if enc.max_wire_speed_mm_s is not None and speed > enc.max_wire_speed_mm_s:
            raise VError(
                -1101,
                f"{ERRORS[-1101]} {where}: the wire would run at {speed:.0f} mm/s, beyond "
                f"the encoder's max_wire_speed_mm_s {enc.max_wire_speed_mm_s:g}",
            )
        if enc.max_wire_accel_mm_s2 is not None and accel > enc.max_wire_accel_mm_s2:
            raise VError(
                -1101,
                f"{ERRORS[-1101]} {where}: the wire would accelerate at {accel:.0f} mm/s², "
                f"beyond the encoder's max_wire_accel_mm_s2 {enc.max_wire_accel_mm_s2:g}",
            )

    def _unmodelled(self, q_deg: np.ndarray) -> np.ndarray:
        """Where the arm really is, relative to the commanded joints (deg)."""
        u = self.unmodelled
        if u is None:
            return np.zeros_like(q_deg)
        return u.joint_errors_deg(self.model, q_deg, self.rng)

    def break_(self) -> None:
        """BREAK: nothing to wait for; the twin's motions end at once."""
        pass

    def here(self, transform: bool = False):
        """Return HERE: the joints, or the pose the controller computes from them (its model)."""
        if not transform:
            return self.joints
        return Trans.from_matrix(*ik.flange_pose(self.believed, np.radians(self.joints)))

    def sig(self, signal: int) -> float:
        """SIG: −1 (TRUE) while the touch probe's true tip is on or below the plate."""
        if signal != self.probe_signal or self.plate is None:
            return 0.0
        R, o = ik.flange_pose(self.model, np.radians(self.actual))
        tip = o + R @ np.asarray(self.probe_mm)
        depth = np.dot(tip - np.asarray(self.plate.point), np.asarray(self.plate.normal))
        return -1.0 if depth <= 0 else 0.0

    def wait(self, seconds: float) -> None:
        """WAIT.EVENT , seconds: advance the clock."""
        self.clock += seconds

    def set_timer(self, number: int, value: float) -> None:
        """TIMER n = value: timers 1 to 15 (V+ 12.4 Release Notes, TIMER instruction)."""
        if not 1 <= number <= 15:
            raise VError(-410, f"*Illegal value* TIMER {number}: timers 1 to 15 can be set")
        self.timers[number] = self.clock - value

    def timer(self, number: int) -> float:
        """TIMER(n): seconds, 1 ms resolution; timer 0 the time since the system started.

        Timers -3 to -1 (V+ 12.4 Release Notes, TIMER function) are not modelled.
        """
        if -3 <= number < 0:
            raise VError(UNMODELLED, f"*Not executed by the digital twin* TIMER({number})")
        if not 0 <= number <= 15:
            raise VError(-410, f"*Illegal value* TIMER({number}): timers are -3 to 15")
        return round((self.clock - self.timers.get(number, 0.0)) * 1000) / 1000

    # ---- encoder ----
    def enable(self, switch: str) -> None:
        """ENABLE a switch; BELT stays off on a controller without conveyor tracking."""
        if not (switch == "BELT" and self.faults.no_conveyor_option):
            self.switches.add(switch)

    def switch(self, name: str) -> float:
        """SWITCH(name): -1 (on) if the switch was enabled, else 0."""
        return -1.0 if name in self.switches else 0.0

    def defbelt(self, name: str, encoder: int, scale: float) -> None:
        """DEFBELT: name a belt on an encoder channel."""
        self.belts[name] = encoder

    def wire_counts(self) -> int:
        """Return the encoder's count for the true wire length now, before any wrap.

        Gaussian noise per pose, quantisation, ±1-count jitter, the vibration after the
        last move, a slip; a wire pulled beyond the encoder's range is an error.
        """
        if self.nest is not None:  # the tip in a nest of the reference gauge
            d = float(self.gauge_mm[self.nest]) + self.pose_error
        else:
            d = self._wire_mm() + self.pose_error + self.slip
        if d > self.robot.encoder.range_mm:
            raise RunError(
                -1100,
                f"{ERRORS[-1100]}: the wire would be {d:.1f} mm long, beyond the "
                f"encoder's range_mm {self.robot.encoder.range_mm:g}",
            )
        amplitude, tau, phase, since = self.vibration
        t = self.clock - since
        d += amplitude * math.exp(-t / tau) * math.cos(2 * math.pi * VIBRATION_HZ * t + phase)
        jitter = int(self.rng.choice((-1, 0, 0, 0, 1)))
        truth = self.encoder_truth  # what the encoder reads of it: scale, temperature, drift
        d = float(truth.read_factor(self.clock, self.run_s)) * d + float(truth.drift_mm(self.clock))
        return math.floor(self.counter_start + d / self.robot.encoder.mm_per_count + 0.5) + jitter

    def _wire_mm(self) -> float:
        """Return the true wire length where the arm stands.

        Kept while the arm stands: the settle rule reads the counter several times per point.
        """
        if self._wire_at is None or self._wire_at[0] is not self.actual:
            p = tool_position(self.model, np.radians(self.actual)[None])[0]
            wire = float(physical_wire_mm(self.robot.encoder.exit, p - self.p0))
            self._wire_at = (self.actual, wire)
        return self._wire_at[1]

    def _counts(self) -> float:
        """Return the belt counter: the wire's count on the robot file's wrapping counter."""
        self.reads += 1
        f = self.faults
        if f.encoder_fails_at_read is not None and self.reads >= f.encoder_fails_at_read:
            raise VError(-1013, ERRORS[-1013])
        return float(self.robot.encoder.counter.wrap(self.wire_counts()))

    def belt(self, name: str, mode: int) -> float:
        """BELT: the counts of a defined belt (the draw-wire encoder)."""
        if name not in self.belts:
            raise VError(-406, f"*Undefined value* {name}")
        return self._counts()

    def device(self, unit: int, select: int) -> tuple[float, float]:
        """DEVICE: the encoder counts and a status (a read error as its code)."""
        try:
            return self._counts(), 0.0
        except VError as e:
            if e.code == -1013:
                return 0.0, float(e.code)
            raise

    # ---- disk ----
    def attach(self, device: str) -> float:
        """ATTACH: a new logical unit for ``device``; its number."""
        lun = 1 + max(self.luns, default=0)
        self.luns[lun] = {"device": device, "file": None}
        self.status[lun] = 1
        return float(lun)

    def detach(self, lun: int) -> None:
        """DETACH a logical unit."""
        self.luns.pop(lun, None)

    def fopen(self, mode: str, lun: int, name: str) -> None:
        """FOPENR/FOPENW/FOPENA: open a file on the cell's disk; the status in IOSTAT."""
        path = self.disk / name.split(":")[-1].upper()
        if lun not in self.luns:
            self.status[lun] = -514
            return
        if mode == "FOPENW" and path.exists():
            self.status[lun] = -500
            return
        if mode == "FOPENR" and not path.exists():
            self.status[lun] = -501
            return
        if mode != "FOPENR":
            path.touch()
        self.luns[lun]["file"] = path
        self.status[lun] = 1

    def write(self, lun: int, text: str) -> None:
        """WRITE a line to an open file, written through; the status in IOSTAT."""
        unit = self.luns.get(lun)
        if unit is None or unit["file"] is None:
            self.status[lun] = -514
            return
        f = self.faults
        if f.disk_full_after_lines is not None and self.lines_written >= f.disk_full_after_lines:
            self.status[lun] = -522
            return
        with open(unit["file"], "a", encoding="ascii", newline="\n") as fh:
            fh.write(text + "\n")  # written through: a stopped run leaves its lines
        self.lines_written += 1
        self.status[lun] = 1

    def fclose(self, lun: int) -> None:
        """FCLOSE a unit's file; the status in IOSTAT."""
        unit = self.luns.get(lun)
        self.status[lun] = 1 if unit and unit["file"] is not None else -514
        if unit:
            unit["file"] = None

    def iostat(self, lun: int) -> float:
        """IOSTAT: the status of the last operation on ``lun``."""
        return float(self.status.get(lun, -514))

    def error_text(self, code: int) -> str:
        """$ERROR: the message of an error code."""
        return ERRORS.get(code, f"*Error {code}*")


@dataclass
class RunResult:
    """A measurement run in the twin: wc.mount's and wc.run's outcomes, the log, the cell."""

    mount: Outcome
    run: Outcome | None
    log: Path
    cell: Cell


def run_measurement(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    disk: Path,
    text: str,
    *,
    log_file: str,
    seed: int = 0,
    noise_mm: float = 0.01,
    counter_start: float | None = None,
    faults: Faults = Faults(),
    proceed_on_pause: bool = False,
    encoder_truth: EncoderTruth = IDEAL_ENCODER,
) -> RunResult:
    """Run a module's wc.mount (answered 1) and wc.run in the twin.

    The log is ``log_file`` on the cell's disk (the name the module was generated with).
    ``proceed_on_pause``: the operator continues after each PAUSE (having steadied the
    arm: a vibration stops), else the run ends there.
    The operator confirms every prompt of the reference step (1), seating the wire tip as
    asked; the encoder is ``encoder_truth``.
    """
    disk.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng([seed, 2])
    start = robot.encoder.counter.random_start(rng) if counter_start is None else counter_start
    cell = Cell(
        robot,
        truth,
        plan.theta0_deg,
        disk,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=start,
        faults=faults,
        proceed_on_pause=proceed_on_pause,
        wire_limits=True,
        answers=["1"] * (1 + _reference_prompts(robot)),
        encoder_truth=encoder_truth,
        run_s=run_timeline(robot, plan, DEFAULT_RUN).total_s + reference_duration_s(robot.encoder),
    )
    interp = Interpreter(parse_module(text, "WIRECAL.V2"), cell)
    mount = interp.execute("wc.mount")
    cell.moves = 0  # fault positions count the moves of wc.run (see move_of_step)
    run = interp.execute("wc.run") if mount.status == "completed" else None
    return RunResult(mount, run, disk / log_file, cell)


def _reference_prompts(robot: Robot) -> int:
    """Return the prompts of wc.ref: each seating and the reattachment (none without)."""
    enc = robot.encoder
    return 0 if enc.reference_length_mm is None else 2 * enc.reference_repeats + 1


def run_targets(plan: Plan) -> list[str]:
    """List what each move of wc.run reaches, in order (move k is entry k-1).

    Per step θ0 (its zero reading), the via points, the points; last θ0 for the closing
    zero reading.
    """
    out = []
    for j, s in enumerate(plan.steps, 1):
        out.append(f"step {j} zero reading at theta0")
        out += [f"step {j} via point {i}" for i in range(1, len(s.via_deg) + 1)]
        out += [f"step {j} point {i}" for i in range(1, len(s.points_deg) + 1)]
    out.append("the closing zero reading at theta0")
    return out


def move_of_step(plan: Plan, step: int, point: int = 1) -> int:
    """Return the 1-based number of the move of wc.run that reaches a step's point."""
    return run_targets(plan).index(f"step {step} point {point}") + 1


def where_in_run(plan: Plan, moves: int) -> str:
    """Where wc.run was after ``moves`` moves (the twin's cell counts them)."""
    targets = run_targets(plan)
    return targets[moves - 1] if 1 <= moves <= len(targets) else "the start of wc.run"


@dataclass
class ValidationRun:
    """Both validation programs' outcomes in the twin, their logs and the cell."""

    configuration: Outcome
    plane: Outcome
    configuration_log: Path
    plane_log: Path
    cell: Cell


def run_validation(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    setup,
    disk: Path,
    text: str,
    *,
    controller: dict[str, float],
    run: int,
    seed: int = 0,
    unmodelled: Unmodelled | None = DEFAULT_UNMODELLED,
    noise_mm: float = 0.01,
) -> ValidationRun:
    """Run both validation programs (wc.vcfg, wc.vpln) in the twin.

    ``controller`` is the model the controller believes: {} before calibration, the
    identified offsets after.
    """
    disk.mkdir(parents=True, exist_ok=True)
    cell = Cell(
        robot,
        truth,
        plan.theta0_deg,
        disk,
        seed=seed,
        noise_mm=noise_mm,
        counter_start=robot.encoder.counter.random_start(
            np.random.default_rng([seed, 5]), within=0.5
        ),
        answers=["1", str(run), "1", str(run)],
        controller=controller,
        plate=Plate(tuple(setup.plate_origin_mm)),
        probe_mm=tuple(setup.probe_mm),
        probe_signal=setup.signal,
        encoder_point_mm=tuple(setup.encoder_mm),
        unmodelled=unmodelled,
    )
    interp = Interpreter(parse_module(text, "WIRECAL.V2"), cell)
    cfg = interp.execute("wc.vcfg")
    pln = interp.execute("wc.vpln")
    return ValidationRun(cfg, pln, disk / f"WCVCFG{run}.CSV", disk / f"WCVPLN{run}.CSV", cell)
