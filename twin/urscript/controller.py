"""The Universal Robots controller the URScript interpreter talks to, over the twin's world.

:class:`URController` holds a :class:`~wirecal.twin.world.World` (the true robot within
its limits, the draw-wire encoder's physics, unmodelled errors, faults, the clock) and
offers the URScript functions the generated programs call:

* ``movej(q, a, v, t, r)``: q in rad, a rad/s², v rad/s of the leading axis (SD 14.22);
  the move takes the time of the leading joint's trapezoidal profile (``t`` > 0 sets it);
  the tool then vibrates along the wire and settles (the programs sleep for that). Through
  the world's one move protocol (:meth:`~wirecal.twin.world.World.move`): a target beyond
  a joint limit stops the program (the controller's own message was not read:
  *unconfirmed*), and so does a move through the arm itself, the floor or a ``[cell]``
  volume (a protective stop naming the colliding pair; the controller's own message is not
  modelled) or one that would run the wire beyond the encoder's speed or acceleration (v
  taken as a percentage of the slowest joint's maximum speed, the ramp to it lasting v/a
  as the trapezoid's; the twin's own stop, naming the limit);
* the payload: ``set_payload(m, cog)`` records the active payload (UR's payload article);
  until a program sets it, it is the Installation's, which the twin takes as the true
  robot's tool (``[gravity] payload_mass_kg`` at ``payload_com_mm``);
  ``get_target_payload()`` and ``get_target_payload_cog()`` read it (SD 15.20, 15.21). A
  ``movej`` while the flange carries more than the active payload (the tool and a mounted
  mass) stops the program: the unsafe direction; the controller's own behaviour is not
  modelled;
* ``get_actual_joint_positions()``: the commanded joints in rad (joint encoders do not see
  the unmodelled errors; the wire does);
* the encoder: ``encoder_enable_pulse_decode(i, 1, A, B)`` (SD 14.2: index 0 or 1,
  decoder types 0–4, inputs 8–11) starts quadrature decoding when A, B are the inputs the
  wire's encoder is wired to (``pulse_inputs``); otherwise the count never changes (it
  reads 0: *unconfirmed*). ``encoder_get_tick_count(i)`` is the filtered count, a float in
  [0; 65536[ that wraps, ``opt="raw"`` the int32 count (SW5.20); the filter's dynamics
  are not modelled. ``encoder_unwind_delta_tick_count`` unwinds a delta over half of 2^16
  (SW5.24) and is nil for an encoder not enabled (a third-party copy of the manual's
  text: *unconfirmed*). An encoder failure (a fault) stops the program (the controller's
  own behaviour is *unconfirmed*);
* sockets: ``socket_open`` opens a real TCP connection (2 s timeout) — the program's PC
  address (``pc``; None: any) is routed to ``receiver`` on loopback, where ``wirecal
  receive`` listens — and returns True or False (SD 17.55); ``socket_send_line`` sends the
  line and a newline and returns whether it was sent (SD 17.63); the controller closes a
  program's sockets when it ends (*unconfirmed*). A fault drops the connection after N lines;
* ``textmsg`` and ``popup`` write to the log tab (the console). A blocking popup suspends
  the program until Continue is pressed (SD 15.35); the twin's operator presses it, except
  at a warning or error popup, where they stop the program (``proceed_on_pause`` to
  continue instead). ``sleep`` advances the clock and ``time(0)`` reads it (SD 15.48,
  15.49); ``sync()`` advances it by one 2 ms frame (SW5.25.1, "Thread scheduling": sync
  and sleep use "physical" time and are recommended next to computationally heavy
  instructions, else "Lost communication with Controller" and a protective stop).

Every public method is a URScript function the interpreter may call (it looks them up
by name), apart from :meth:`URController.close_all`.

Sections of the e-Series Script Directory (SD) and Script Manual pages (SW…): see
:mod:`wirecal.gen.urscript.facts`.
"""

from __future__ import annotations

import math
import socket
from dataclasses import dataclass, field

import numpy as np

from wirecal.solver.counter import Counter
from wirecal.solver.run_parameters import MOVE_OVERHEAD_S
from wirecal.twin.machine import Stopped, f32
from wirecal.twin.urscript.interp import URError, number, to_float, to_str
from wirecal.twin.world import BeyondLimit, Collision, EncoderFailure, WireOverspeed, World

FILTERED_RANGE = 2**16
"""The filtered count's range [0; 65536[ (Script Manual SW5.20)."""
RAW = Counter(32)
"""The raw count: an int32 (SW5.20)."""
SOCKET_TIMEOUT_S = 2.0
PAYLOAD_TOL_KG = 1e-5
"""A declared payload lighter than the flange's load by more than this stops a move: a float
of the program (32 bits) holds a few kg to about 1e-6 kg."""
FRAME_S = 0.002
"""The controller's frame: every thread gets 2 ms of "physical" time per frame (SW5.25.1)."""


@dataclass
class URController:
    """The URScript functions over a world (module docstring)."""

    world: World
    pulse_inputs: tuple[int, int] = (8, 9)  # the digital inputs the encoder is wired to
    encoder_index: int = 0
    pc: tuple[str, int] | None = None  # the PC's address as the program names it (None: any)
    receiver: tuple[str, int] | None = None  # where the twin routes it (loopback)
    sockets: dict[str, socket.socket] = field(default_factory=dict)
    lines_sent: int = 0
    syncs: int = 0  # sync() calls (each a 2 ms frame)
    software: str | None = None  # the declared software: a call its pages lack is refused
    payload: tuple[float, object] | None = None  # the last set_payload (kg, CoG m)

    def __post_init__(self) -> None:
        """No encoder is decoded until a program enables it."""
        self.decoding: dict[int, tuple[int, int, int]] = {}

    @property
    def console(self) -> list[str]:
        """The log tab's lines (the world's console)."""
        return self.world.console

    # ---- motion ----
    def movej(self, q, a=1.4, v=1.05, t=0, r=0) -> None:
        """movej: go to joint positions q (rad) in joint space (module docstring)."""
        w = self.world
        if not isinstance(q, list) or len(q) != len(w.joints):
            raise URError(f"movej: q must be a list of {len(w.joints)} joint positions")
        q_deg = np.degrees([to_float(x) for x in q])
        a_rad_s2, v_rad_s = number(a, "movej a"), number(v, "movej v")
        self._check_payload()
        dist = float(np.max(np.abs(np.radians(q_deg - np.asarray(w.joints)))))
        slowest = math.radians(float(np.min(w.robot.joint_speed_deg_s)))
        speed_pct = min(100.0, 100.0 * v_rad_s / slowest)
        duration_s = _trapezoid_s(dist, a_rad_s2, v_rad_s, t)
        # the leading axis's ramp v/a (a > 0 and v > 0 unless t > 0 sets the time: then
        # the model's ramp, how the controller shapes such a move is not modelled)
        ramp_s = slowest * speed_pct / 100 / a_rad_s2 if t == 0 else MOVE_OVERHEAD_S
        match w.move(q_deg, speed_pct, duration_s, ramp_s):
            case BeyondLimit(joint=j, min_deg=lo, max_deg=hi):
                raise URError(
                    f"movej: joint {j + 1} target {q_deg[j]:.3f} deg is beyond its limit "
                    f"[{lo:g}, {hi:g}] deg"
                )
            case Collision(where=where):
                raise URError(f"protective stop: movej: {where}")
            case WireOverspeed(move=move, why=why):
                raise URError(f"movej: {move}: {why}")

    def get_actual_joint_positions(self) -> list[float]:
        """Return the joints in rad, base to wrist 3."""
        return [f32(math.radians(x)) for x in self.world.joints]

    def sleep(self, t) -> None:
        """sleep: advance the clock by t s."""
        self.world.wait(float(number(t, "sleep")))

    def sync(self) -> None:
        """sync: the rest of the 2 ms frame (Script Manual SW5.25.1, "Thread scheduling").

        The twin advances the clock by a whole frame (an upper bound) and counts the calls.
        """
        self.world.wait(FRAME_S)
        self.syncs += 1

    def time(self, mode=0) -> dict[str, int]:
        """time(0): the controller's clock as struct(sec, nanosec), ints (SD 15.49, as cited).

        The twin's clock starts at 0 when the cell is made; other modes are not modelled.
        """
        if mode != 0:
            raise URError(f"time({to_str(mode)}): the twin models time(0) only")
        clock = self.world.clock
        sec = math.floor(clock)
        return {"sec": sec, "nanosec": math.floor((clock - sec) * 1e9)}

    # ---- encoder ----
    def encoder_enable_pulse_decode(self, encoder_index, decoder_type, A, B) -> None:
        """Decode the pulses on inputs A, B as encoder ``encoder_index`` (SD 14.2)."""
        self._index(encoder_index)
        if decoder_type not in range(5) or isinstance(decoder_type, bool):
            raise URError(f"decoder_type {to_str(decoder_type)}: must be 0 to 4")
        for name, pin in (("A", A), ("B", B)):
            if pin not in range(8, 12) or isinstance(pin, bool):
                raise URError(f"encoder input {name} = {to_str(pin)}: must be 8 to 11")
        self.decoding[encoder_index] = (decoder_type, A, B)

    def _decoded(self, encoder_index) -> bool:
        """Tell whether the wire's encoder is decoded (quadrature, its inputs) as this index."""
        self._index(encoder_index)
        setup = self.decoding.get(encoder_index)
        return (
            encoder_index == self.encoder_index
            and setup is not None
            and setup[0] == 1
            and {setup[1], setup[2]} == set(self.pulse_inputs)
        )

    def encoder_get_tick_count(self, encoder_index, opt=""):
        """Return the filtered count (float, wraps at 2^16) or with opt="raw" the int32 count."""
        if not self._decoded(encoder_index):
            self.world.reads += 1
            count = 0
        else:
            try:
                count = self.world.read_count()
            except EncoderFailure as e:
                raise URError(f"encoder_get_tick_count: {e}") from None
        if opt == "raw":
            return int(RAW.wrap(count))
        return f32(float(count % FILTERED_RANGE))

    def encoder_unwind_delta_tick_count(self, encoder_index, delta_tick_count):
        """Unwind a delta of filtered counts over half their range; nil if not enabled."""
        if not self._decoded(encoder_index):
            return None
        d = number(delta_tick_count, "encoder_unwind_delta_tick_count")
        half = FILTERED_RANGE // 2
        if d > half:
            d -= FILTERED_RANGE
        elif d < -half:
            d += FILTERED_RANGE
        return f32(float(d)) if isinstance(d, float) else d

    @staticmethod
    def _index(encoder_index) -> None:
        if encoder_index not in (0, 1) or isinstance(encoder_index, bool):
            raise URError(f"encoder index {to_str(encoder_index)}: must be 0 or 1")

    # ---- log tab ----
    def textmsg(self, s1, s2="") -> None:
        """textmsg: a line in the log tab."""
        self.world.show(to_str(s1) + to_str(s2))

    def popup(self, s, title="Popup", warning=False, error=False, blocking=False) -> None:
        """popup: shown in the log tab; the operator stops at a blocking warning or error."""
        self.world.show(f"[popup {to_str(title)}] {to_str(s)}")
        if blocking and (warning or error) and not self.world.proceed_on_pause:
            raise Stopped(to_str(s))
        if blocking:  # the operator does what it asks, then presses Continue
            self.world.handle_mass(to_str(s))

    # ---- payload ----
    def set_payload(self, m, cog=None) -> None:
        """set_payload: the active payload the controller is told (kg, CoG in m), recorded."""
        self.payload = (number(m, "set_payload m"), cog)

    def get_target_payload(self) -> float:
        """get_target_payload: the active payload's mass (kg; SD 15.20)."""
        return to_float(self._active_payload()[0])

    def get_target_payload_cog(self) -> list:
        """get_target_payload_cog: the active payload's CoG (m, from the tool flange; SD 15.21)."""
        return [to_float(x) for x in self._active_payload()[1]]

    def _active_payload(self) -> tuple[float, list]:
        """Return the active payload: the last set_payload's, else the Installation's.

        The Installation's is the flange's true load, the tool of the twin's true robot
        (its ``[gravity] payload_mass_kg`` at ``payload_com_mm``): the operator set it as
        docs/urscript.md asks.
        """
        if self.payload is not None:
            m, cog = self.payload
            cog_m = cog if isinstance(cog, list) else [0, 0, 0]
            return m, [number(x, "set_payload cog") for x in cog_m]
        masses = self.world.robot.masses
        if masses is None:
            return 0.0, [0.0, 0.0, 0.0]
        return masses.payload_mass_kg, [float(x) / 1000 for x in masses.payload_com_mm]

    def _check_payload(self) -> None:
        """Stop a move whose flange carries more than the active payload declares.

        The flange carries the true robot's tool and the mass mounted. The twin models no
        dynamics; UR's payload article says wrong settings "can lead to incorrect movements
        which then lead to protective stops" (the controller's own behaviour with too light
        a payload is not modelled: the twin stops, naming both masses).
        """
        carried_kg = self.world.flange_load_kg()
        declared_kg = self._active_payload()[0]
        if carried_kg > declared_kg + PAYLOAD_TOL_KG:
            raise URError(
                f"protective stop: movej with {carried_kg:g} kg at the flange and "
                f"{declared_kg:g} kg declared (the active payload): the controller would move a "
                "load lighter than the truth"
            )

    # ---- sockets ----
    def socket_open(self, address, port, socket_name="socket_0") -> bool:
        """Open a TCP connection to the PC (routed to the receiver); True when connected."""
        where = (to_str(address), int(number(port, "socket_open port")))
        if (self.pc is not None and where != self.pc) or self.receiver is None:
            return False  # nobody listens there in the twin's network
        self.socket_close(socket_name)
        try:
            self.sockets[socket_name] = socket.create_connection(
                self.receiver, timeout=SOCKET_TIMEOUT_S
            )
        except OSError:
            return False
        return True

    def socket_send_line(self, str, socket_name="socket_0") -> bool:
        """Send a line and a newline; False when the connection is gone."""
        sock = self.sockets.get(socket_name)
        if sock is None:
            return False
        drop = self.world.faults.socket_drops_after_lines
        if drop is not None and self.lines_sent >= drop:
            self.socket_close(socket_name)
            return False
        try:
            sock.sendall((to_str(str) + "\n").encode("utf-8"))
        except OSError:
            self.socket_close(socket_name)
            return False
        self.lines_sent += 1
        return True

    def socket_close(self, socket_name="socket_0") -> None:
        """Close a connection (nothing happens if it is not open)."""
        sock = self.sockets.pop(socket_name, None)
        if sock is not None:
            sock.close()

    def close_all(self) -> None:
        """Close every socket, as the controller does when a program ends."""
        for name in list(self.sockets):
            self.socket_close(name)


def _trapezoid_s(distance_rad: float, a_rad_s2: float, v_rad_s: float, t_s) -> float:
    """Return a movej's duration: the leading joint's trapezoidal profile (or t if > 0)."""
    if number(t_s, "movej t") > 0:
        return float(t_s)
    if a_rad_s2 <= 0 or v_rad_s <= 0:
        raise URError("movej: a and v must be positive")
    if distance_rad >= v_rad_s**2 / a_rad_s2:
        return distance_rad / v_rad_s + v_rad_s / a_rad_s2
    return 2.0 * math.sqrt(distance_rad / a_rad_s2)
