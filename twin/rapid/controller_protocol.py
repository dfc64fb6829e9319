"""What a RAPID program asks of the controller: the interface the twin's adapter implements.

The interpreter (:mod:`wirecal.twin.rapid.interp`) evaluates the language itself (data,
expressions, routines, clocks); every instruction or function that touches the robot, the
encoder's group input, the controller's files or the FlexPendant calls one method here.
"""

from __future__ import annotations

from typing import Protocol


class RapidController(Protocol):
    """The robot controller as a RAPID program sees it (implemented over the twin's World)."""

    def move_abs_j(
        self, joints_deg: tuple[float, ...], speed: tuple[float, ...], zone: str, tool_kg: float
    ) -> None:
        """MoveAbsJ to the six robot axes ``joints_deg`` (jointtarget robax, degrees).

        ``speed`` is the speeddata (v_tcp mm/s, v_ori deg/s, v_leax mm/s, v_reax deg/s),
        ``zone`` the predefined zonedata's name ("fine" stops at the point), ``tool_kg``
        the Tool argument's tload mass (the tool's own load, kg). A refusal
        (:class:`~wirecal.twin.machine.RunError`) names what stopped, not the line: the
        interpreter's outcome carries that.
        """

    def joints_deg(self) -> tuple[float, ...]:
        """Return the six robot axes' current angles in degrees (CJointT)."""

    def group_input(self, name: str) -> int:
        """Return the group input signal ``name``'s value, unsigned (GInputDnum, GInput)."""

    def has_group_input(self, name: str) -> bool:
        """Return whether the I/O configuration defines the group input ``name`` (AliasIO)."""

    def open_file(self, path: str, append: bool) -> int:
        r"""Open ``path`` for writing; return a handle for :meth:`write_file`.

        ``path`` is the directory and \File joined by "/" ("HOME:/wirecal.log");
        ``append`` is Open's \Append switch.
        """

    def write_file(self, handle: int, text: str, newline: bool = True) -> None:
        r"""Write ``text`` (formatted by the interpreter), then a line end unless \NoNewLine."""

    def close_file(self, handle: int) -> None:
        """Close the file ``handle``."""

    def tp_write(self, text: str) -> None:
        """TPWrite: one line on the FlexPendant (formatted, at most 80 characters)."""

    def tp_erase(self) -> None:
        """TPErase: clear the FlexPendant's operator window."""

    def tp_read_num(self, prompt: str) -> float:
        """TPReadNum: the number the operator answers to ``prompt``."""

    def grip_load(self, mass_kg: float, cog_mm: tuple[float, float, float]) -> None:
        """GripLoad: the payload the controller is told (mass, centre in the tool frame)."""

    def wait_time(self, seconds: float) -> None:
        """WaitTime: let ``seconds`` pass (the robot at rest)."""

    def now_s(self) -> float:
        """Return the controller's time in seconds (the interpreter's clocks read it)."""

    def stop(self, why: str) -> None:
        """Stop the program (Stop, EXIT, or a run-time error): ``why`` says which."""
