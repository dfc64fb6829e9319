"""The V+ controller the interpreter talks to, over the twin's physical world.

:class:`VplusController` is what :class:`~wirecal.twin.vplus.interp.Interpreter` calls for
V+'s instructions and functions — TYPE/PROMPT/PAUSE, SPEED/MOVE/MOVES and the
configuration words, HERE, SIG, TIMER, ENABLE/SWITCH, DEFBELT/BELT/DEVICE,
ATTACH/FOPEN/WRITE/FCLOSE/IOSTAT, $ERROR — mapped onto a
:class:`~wirecal.twin.world.World`. It holds what the controller itself keeps: its
kinematic model (nominal + ``offsets``, used by its inverse kinematics and HERE), the
requested configuration, the tool, the speed, belts, switches, timers and logical units.

Error codes of the twin's own making (the V+ manual's codes are used where known:
−1013 encoder quadrature error, User's Guide p. 354) are listed in ``ERRORS``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wirecal.solver.ik import solutions as ik
from wirecal.solver.simulate import RANGE_EXCEEDED
from wirecal.twin.vplus.interp import UNMODELLED, Trans, VError
from wirecal.twin.world import BeyondLimit, Collision, EncoderFailure, WireOverspeed, World

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
QUADRATURE_ERROR = -1013


@dataclass
class VplusController:
    """The V+ controller's API over a world (see module docstring)."""

    world: World
    offsets: dict[str, float] = field(default_factory=dict)  # the model it believes
    probe_signal: int = 1001  # the input the touch probe is wired to

    def __post_init__(self) -> None:
        """Derive the believed model and start the controller's state."""
        self.believed = self.world.robot.model(self.offsets)
        self.requested: dict[int, str] = {}
        self.tool = "unknown"  # whatever a previous program left: TOOL sets it
        self.tools_at_cartesian: set[str] = set()  # the tool in force at each TRANS move
        self.speed_pct = 100.0
        self.belts: dict[str, int] = {}
        self.switches: set[str] = set()
        self.timers: dict[int, float] = {}  # timer number → the clock when it read zero
        self.luns: dict[int, dict] = {}
        self.status: dict[int, float] = {}
        self.written: list[Path] = []  # the files opened for writing, in order

    @property
    def console(self) -> list[str]:
        """The terminal's lines (the world's console)."""
        return self.world.console

    # ---- terminal ----
    def type_(self, text: str) -> None:
        """TYPE: append ``text`` to the console."""
        self.world.show(text)

    def prompt(self, text: str) -> str:
        """PROMPT: show ``text``; return the operator's answer."""
        answer = self.world.answer(text)
        if answer is None:
            raise VError(-526, "*No data received* (no scripted answer to the PROMPT)")
        return answer

    def on_pause(self) -> bool:
        """Return whether a PAUSE proceeds (as the operator would, who then steadies the arm)."""
        return self.world.steady()

    # ---- motion ----
    def speed(self, pct: float) -> None:
        """SPEED: set the motion speed in percent."""
        self.speed_pct = pct

    def accel(self, *_args) -> None:
        """ACCEL: accepted; the twin's timing ignores it."""

    def configure(self, word: str) -> None:
        """ABOVE/BELOW, FLIP/NOFLIP, LEFTY/RIGHTY: a request for the next motion."""
        part = {"LEFTY": 0, "RIGHTY": 0, "ABOVE": 1, "BELOW": 1, "FLIP": 2, "NOFLIP": 2}[word]
        self.requested[part] = word.lower()

    def _joints_for(self, t: Trans) -> np.ndarray:
        """Solve the controller's inverse kinematics with its own model.

        The requested configuration where given, else the current one.
        """
        R, p = t.matrix()
        here = np.radians(self.world.joints)
        current = ik.configuration(self.believed, here)
        want = tuple(self.requested.get(k, current[k]) for k in range(3))
        if not self.requested:  # a step in the same configuration: follow it by Newton
            q, ok = ik.follow(self.believed, here, R, p)
            if ok and ik.configuration(self.believed, q) == current:
                return np.degrees(q)
        self.requested = {}
        for s in ik.each_solution(self.world.limits, R, p, model=self.believed):
            if s.config == want and s.within_limits:
                return np.degrees(s.q)
        raise VError(-931, f"*Location out of range* ({'/'.join(want)})")

    def tool_null(self) -> None:
        """TOOL NULL: the flange is the tool point (the cell models no other tool)."""
        self.tool = "null"

    def move(self, target, straight: bool = False) -> None:
        """MOVE/MOVES: go to joints, or to a pose through the controller's IK."""
        w = self.world
        if isinstance(target, Trans):
            self.tools_at_cartesian.add(self.tool)
            target = self._joints_for(target)
        q = np.asarray(target, dtype=float)
        match w.move(q, self.speed_pct):
            case BeyondLimit(joint=j):
                raise VError(-1004, f"*Joint {j + 1} out of range* ({q[j]:g} deg)")
            case Collision(where=where):
                raise VError(PROTECTIVE_STOP, f"{ERRORS[PROTECTIVE_STOP]} {where}")
            case WireOverspeed(move=move, why=why):
                raise VError(-1101, f"{ERRORS[-1101]} {move} at SPEED {self.speed_pct:g}: {why}")

    def break_(self) -> None:
        """BREAK: nothing to wait for; the twin's motions end at once."""

    def here(self, transform: bool = False):
        """Return HERE: the joints, or the pose the controller computes from them (its model)."""
        joints = self.world.joints
        if not transform:
            return joints
        return Trans.from_matrix(*ik.flange_pose(self.believed, np.radians(joints)))

    def sig(self, signal: int) -> float:
        """SIG: −1 (TRUE) while the touch probe's true tip is on or below the plate."""
        if signal != self.probe_signal:
            return 0.0
        return -1.0 if self.world.probe_touching() else 0.0

    def wait(self, seconds: float) -> None:
        """WAIT.EVENT , seconds: advance the clock."""
        self.world.wait(seconds)

    def set_timer(self, number: int, value: float) -> None:
        """TIMER n = value: timers 1 to 15 (V+ 12.4 Release Notes, TIMER instruction)."""
        if not 1 <= number <= 15:
            raise VError(-410, f"*Illegal value* TIMER {number}: timers 1 to 15 can be set")
        self.timers[number] = self.world.clock - value

    def timer(self, number: int) -> float:
        """TIMER(n): seconds, 1 ms resolution; timer 0 the time since the system started.

        Timers -3 to -1 (V+ 12.4 Release Notes, TIMER function) are not modelled.
        """
        if -3 <= number < 0:
            raise VError(UNMODELLED, f"*Not executed by the digital twin* TIMER({number})")
        if not 0 <= number <= 15:
            raise VError(-410, f"*Illegal value* TIMER({number}): timers are -3 to 15")
        return round((self.world.clock - self.timers.get(number, 0.0)) * 1000) / 1000

    # ---- encoder ----
    def enable(self, switch: str) -> None:
        """ENABLE a switch; BELT stays off on a controller without conveyor tracking."""
        if not (switch == "BELT" and self.world.faults.no_conveyor_option):
            self.switches.add(switch)

    def switch(self, name: str) -> float:
        """SWITCH(name): -1 (on) if the switch was enabled, else 0."""
        return -1.0 if name in self.switches else 0.0

    def defbelt(self, name: str, encoder: int, scale: float) -> None:
        """DEFBELT: name a belt on an encoder channel."""
        self.belts[name] = encoder

    def _counts(self) -> float:
        """Return the belt counter: the wire's count on the robot file's wrapping counter."""
        try:
            count = self.world.read_count()
        except EncoderFailure:
            raise VError(QUADRATURE_ERROR, ERRORS[QUADRATURE_ERROR]) from None
        return float(self.world.robot.encoder.counter.wrap(count))

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
            if e.code == QUADRATURE_ERROR:
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
        """FOPENR/FOPENW/FOPENA: open a file on the world's disk; the status in IOSTAT."""
        path = self.world.disk / name.split(":")[-1].upper()
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
            self.written.append(path)
        self.luns[lun]["file"] = path
        self.status[lun] = 1

    def write(self, lun: int, text: str) -> None:
        """WRITE a line to an open file, written through; the status in IOSTAT."""
        unit = self.luns.get(lun)
        if unit is None or unit["file"] is None:
            self.status[lun] = -514
            return
        self.status[lun] = 1 if self.world.append_line(unit["file"], text) else -522

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
