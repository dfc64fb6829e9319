r"""The IRC5 as the RAPID twin's interpreter sees it: :class:`IrcController` over the World.

It implements :class:`~wirecal.twin.rapid.controller_protocol.RapidController` on the
twin's physical world, :class:`~wirecal.twin.world.World` (the true robot, the draw-wire
encoder, the disk, the operator, the clock), calling it in the order its docstring gives:

* ``MoveAbsJ``: the joints go to the target in the time of the move's trapezoidal
  profile at the speed the speeddata asks for: its v_ori (deg/s) taken as the leading
  joint's speed, as a percentage of the slowest joint's maximum (how the real controller
  applies v_tcp and v_ori to a joint move is *unconfirmed*); the tool then vibrates along
  the wire and settles. A target beyond a joint limit, a move into the arm itself, the
  floor or a ``[cell]`` volume, or one that would run the wire beyond the encoder's speed
  or acceleration stops the program (the controller's own messages are not modelled);
  ``fine`` stops at the point;
* ``GInputDnum``: the group input ``wc_giCount<channel>`` holds the encoder's count on a
  32-bit counter that wraps (the counter module's behaviour: *unconfirmed*); any other
  signal name stops the program (an unknown signal). A failed encoder (the fault
  ``encoder_fails_at_read``) leaves the input at its last value: the count freezes;
* ``CJointT``: the commanded joints (the joints' own encoders do not see the errors
  the wire measures);
* ``Open "HOME:" \File:=…`` / ``Write`` / ``Close``: files in the world's disk folder,
  written through, a line at a time (``\NoNewLine`` keeps the line open); a full disk
  (``disk_full_after_lines``) stops the program at the Write (the controller's error
  number is not modelled);
* ``TPWrite`` / ``TPErase`` / ``TPReadNum``: the FlexPendant is the world's console; the
  operator answers from the world's scripted answers;
* ``GripLoad``: the payload the controller is told is recorded (:attr:`IrcController.load`);
  the twin models no dynamics, but a ``MoveAbsJ`` whose flange carries more than the
  controller is told stops the program (the unsafe direction: RAPID Reference Manual,
  loaddata, p. 183, "impaired path accuracy including running the risk of overshooting"):
  the flange carries the tool (the true robot's ``[gravity] payload_mass_kg``) and the
  mass mounted, the controller is told the move's tool load (its tooldata's tload) and
  the payload (the last GripLoad; the manual's tooldata page, pp. 225–227: the tool's
  load in tload, the payload connected with GripLoad);
* ``WaitTime`` and the clocks: the world's clock.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from wirecal.twin.machine import RunError
from wirecal.twin.world import BeyondLimit, Collision, EncoderFailure, WireOverspeed, World

GROUP_RANGE = 2**32
"""The group input's values: 32 bits, unsigned (GInputDnum reads up to 32 signals)."""

STOP_CODE = -2000
"""The twin's code for a program the controller stops (a RAPID error, a protective stop)."""


@dataclass
class IrcController:
    """The controller a RAPID module runs on, over the twin's world (module docstring)."""

    world: World
    signal: str  # the group input the encoder's counter is mapped to
    stopped: str | None = None  # why the program was stopped (None: it was not)
    files: dict[int, Path] = field(default_factory=dict)
    open_line: dict[int, str] = field(default_factory=dict)  # text after \NoNewLine
    flexpendant: list[str] = field(default_factory=list)
    last_count: int = 0  # the group input's value: it holds when the encoder fails
    load: tuple[float, tuple[float, float, float]] | None = None  # the last GripLoad (kg, mm)

    def _refuse(self, why: str) -> RunError:
        self.stopped = why
        return RunError(STOP_CODE, why)

    # ---- motion ----
    def move_abs_j(
        self, joints_deg: tuple[float, ...], speed: tuple[float, ...], zone: str, tool_kg: float
    ) -> None:
        """MoveAbsJ: to ``joints_deg`` at speeddata ``speed``; stop when it cannot.

        A joint limit, a collision, the wire's speed, or a load at the flange heavier than
        the tool's ``tool_kg`` with the payload GripLoad declared (the unsafe direction)
        stops the program.
        """
        world = self.world
        carried_kg = world.flange_load_kg()
        payload_kg = 0.0 if self.load is None else self.load[0]
        if carried_kg > tool_kg + payload_kg + 1e-9:
            raise self._refuse(
                f"MoveAbsJ with {carried_kg:g} kg at the flange and {tool_kg + payload_kg:g} "
                f"kg declared (the tool's tload {tool_kg:g} kg, GripLoad {payload_kg:g} kg): "
                "the controller would move a load lighter than the truth"
            )
        q = np.asarray(joints_deg, dtype=float)
        slowest = float(np.min(world.robot.joint_speed_deg_s))
        speed_pct = min(100.0, 100.0 * float(speed[1]) / slowest)
        match world.move(q, speed_pct):
            case BeyondLimit(joint=j):
                raise self._refuse(f"MoveAbsJ: joint {j + 1} out of range ({q[j]:g} deg)")
            case Collision(where=where):
                raise self._refuse(f"protective stop: {where}")
            case WireOverspeed(why=why):
                raise self._refuse(f"MoveAbsJ: {why}")

    def joints_deg(self) -> tuple[float, ...]:
        """CJointT: the commanded joints (deg, single precision)."""
        return tuple(self.world.joints)

    # ---- the encoder's group input ----
    def group_input(self, name: str) -> int:
        """GInputDnum: the counter's value, unsigned 32 bits; another signal stops."""
        if name != self.signal:
            raise self._refuse(f"GInputDnum: no group input signal named {name}")
        try:
            self.last_count = self.world.read_count() % GROUP_RANGE
        except EncoderFailure:
            pass  # the input holds its last value
        return self.last_count

    def has_group_input(self, name: str) -> bool:
        """AliasIO: only the counter's group input is configured."""
        return name == self.signal

    # ---- files ----
    def open_file(self, path: str, append: bool) -> int:
        """Open ``HOME:/name``: a file in the world's disk folder (emptied unless append)."""
        device, _, name = path.partition(":")
        if device.upper() != "HOME" or not name.strip("/"):
            raise self._refuse(f"Open: {path}: the twin's controller has HOME: only")
        file = self.world.disk / name.strip("/")
        if not append:
            file.write_text("", encoding="ascii")
        handle = 1 + max(self.files, default=0)
        self.files[handle] = file
        return handle

    def write_file(self, handle: int, text: str, newline: bool = True) -> None:
        r"""Write: append ``text``; a line ends unless ``newline`` is False (\NoNewLine)."""
        if handle not in self.files:
            raise self._refuse("Write: the file is not open")
        text = self.open_line.pop(handle, "") + text
        if not newline:
            self.open_line[handle] = text
            return
        if not self.world.append_line(self.files[handle], text):
            raise self._refuse(f"Write: {self.files[handle].name}: the disk is full")

    def close_file(self, handle: int) -> None:
        """Close: the file's open line is written."""
        if handle in self.open_line:
            self.write_file(handle, "")
        self.files.pop(handle, None)

    # ---- FlexPendant ----
    def tp_write(self, text: str) -> None:
        """TPWrite: one line on the FlexPendant (the world's console)."""
        self.flexpendant.append(text)
        self.world.show(text)

    def tp_erase(self) -> None:
        """TPErase: the operator window is cleared (the twin keeps the record)."""

    def tp_read_num(self, prompt: str) -> float:
        """TPReadNum: the operator's next scripted answer as a number (none: 0)."""
        answer = self.world.answer(prompt) or "0"  # the world's console shows both
        self.flexpendant += [prompt, f"> {answer}"]
        try:
            return float(answer)
        except ValueError:
            return 0.0

    def grip_load(self, mass_kg: float, cog_mm: tuple[float, float, float]) -> None:
        """GripLoad: the payload the controller is told, recorded (kg, centre in mm)."""
        self.load = (mass_kg, cog_mm)

    # ---- time and stopping ----
    def wait_time(self, seconds: float) -> None:
        """WaitTime: the clock runs on."""
        self.world.wait(seconds)

    def now_s(self) -> float:
        """Return the controller's time (s)."""
        return float(self.world.clock)

    def stop(self, why: str) -> None:
        """Stop the program: keep why."""
        self.stopped = why
