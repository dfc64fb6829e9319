"""Universal Robots URScript: the front end (grammar, parser, checker, function table).

The declaration below is what the rest of wirecal knows of URScript (Script Manual "SD"
§ numbers, the SW5.20 pages, and the UR user manuals cited).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from wirecal.lang.base import Capabilities, Example, Language
from wirecal.lang.registry import register
from wirecal.lang.urscript.calibration import KEYS, SUFFIX, calibration_text
from wirecal.lang.urscript.versions import LINES
from wirecal.solver.robot import Robot

_TYPES = "UR16e User Manual p. 181; UR5 CB3 User Manual 3.4.5 p. II-69"
_TICKS = "SW5.20 encoder_get_tick_count page"
_MOTION = "Script Manual SW10.13, Module motion (q: 6 floats; a pose: 6 floats)"
_RPC = "Script Manual SW5.20, Remote Procedure Call (RPC)"
_ASCII = "Script Manual SW10.6, Connecting to URControl (extended ASCII only)"
_GUIDE = "UR's conveyor tracking guide (CB3 >= 3.8, e-Series >= 5.2)"
_RTDE = "ur_rtde src/script_client.cpp: the register offset injected after the comment"


def _program(*body: str) -> str:
    return "\n".join(["def p():", *(f"  {line}" for line in body), "end", ""])


@register
class URScript(Language):
    """URScript: one ``.script`` per program; the log goes to the PC over a socket."""

    key = "urscript"
    title = "Universal Robots URScript"
    suffix = ".script"
    suffixes = (".script", ".urscript")
    live_check = "wc_check"
    capabilities = Capabilities(
        int_bits=32,  # int32 (the manuals above)
        float_bits=32,  # float32 (the manuals above)
        file_io=False,  # no file output: the log is sent to 'wirecal receive'
        sockets=True,  # socket_open/socket_send_line (SD)
        encoder_interfaces=("pulse",),  # the controller's pulse decoder (SD §14.4)
        counter_bits=32,  # the raw count, an int32 (SD §14.4)
        software_lines=LINES,  # the product lines by major version (versions.LINES)
    )
    interface_notes: ClassVar[Mapping[str, str]] = {"pulse": "the controller's pulse decoder"}
    valid_examples: ClassVar[tuple[Example, ...]] = (
        Example(_program("x = p[0.4, -0.1, 0.3, 0, 3.1416, 0]", "y = x[2]"), _TYPES),
        Example(_program("lo = -2147483648", "hi = 2147483647"), _TYPES),
        Example(_program('c = encoder_get_tick_count(1, opt="raw")'), _TICKS, "5.20"),
        Example(
            "def p():\n  global off = # register offset\n24  global k = 2\n  x = off + k\nend\n",
            _RTDE,
        ),
        Example(
            _program(
                'camera = rpc_factory("xmlrpc", "http://127.0.0.1/RPC2")',
                'if (! camera.initialize("RGB")):',
                '  popup("Camera was not initialized")',
                "end",
                "target = camera.getTarget()",
            ),
            _RPC,
        ),
        Example(
            _program("movej([0, -1.57, 0, -1.57, 0, 0.5])", "x = p[0.4, 0, 0.3, 0, 3.14, 0]"),
            _MOTION,
        ),
        Example(_program('textmsg("25 \u00b0C")'), _ASCII),
        Example(
            _program("encoder_enable_pulse_decode(0, 1, 8, 9)", "c = encoder_get_tick_count(0)"),
            _GUIDE,
            "3.15",
        ),
    )
    invalid_examples: ClassVar[tuple[Example, ...]] = (
        Example(_program("x = 2147483648"), _TYPES),
        Example(_program("x = 2147483647 + 1"), _TYPES),
        Example(_program("c = encoder_get_tick_count(2)"), _TICKS),
        Example(_program('c = encoder_get_tick_count(0, opt="rawx")'), _TICKS),
        Example(_program("q = [1, 2, 3]", "x = q[3]"), _TYPES),
        Example(_program('c = encoder_get_tick_count(0, opt="raw")'), _TICKS, "3.15"),
        Example(_program("movej([0, -1.57, 0, -1.57, 0, 0.5, 0])"), _MOTION),
        Example(_program("q = [0, 0, 0, 0, 0]", "movej(q)"), _MOTION),
        Example(_program("x = p[0.4, 0, 0.3, 0, 3.14]"), _MOTION),
        Example(_program('textmsg("25 \u2192 30")'), _ASCII),
        Example(_program('x = [1, "a", 2]'), "unconfirmed: a list holds one type"),
        Example(_program("c = encoder_get_tick_count(0)"), _GUIDE, "3.7"),
        Example(
            _program("c = encoder_get_tick_count(0)"), _GUIDE + "; 10.x pages not read", "10.7"
        ),
    )

    patch_companion = SUFFIX  # Universal Robots' standard-DH deltas (calibration.py)
    companion_vectors = ("mounting", KEYS)

    def patch_section(self, robot: Robot, offsets: Mapping[str, float]) -> str:
        """Return UR's standard-DH deltas of ``offsets`` in calibration.conf's layout."""
        return calibration_text(robot, offsets)

    def lint_files(
        self,
        texts: Mapping[str, str],
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check a program with the script files included in it (:mod:`.files`)."""
        from wirecal.lang.urscript.files import check_files

        return check_files(texts, software)

    def lint(
        self,
        text: str,
        source: str,
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check a script as sent to the controller (``external_calls`` does not apply)."""
        from wirecal.lang.urscript.parser import program_problems

        return program_problems(text, source, software)
