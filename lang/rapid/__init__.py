"""ABB RAPID (IRC5, RobotWare 6): the front end and the language's declaration.

The grammar ``rapid.lark``, the parser (:mod:`.parser`), the checker (:mod:`.checker`) and
the tables of data types, instructions and functions with the page each was read on
(:mod:`.tables`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from wirecal.lang.base import Capabilities, Example, Language
from wirecal.lang.rapid import examples
from wirecal.lang.rapid.patch import SUFFIX, patch_section
from wirecal.lang.registry import register
from wirecal.solver.robot import Robot


@register
class Rapid(Language):
    """ABB RAPID: num is a 32-bit float (exact integers to 8388608), dnum a 64-bit one.

    The counter is read from a group input with GInputDnum; a group input carries up to
    32 signals (counter_bits 32: unconfirmed, no page read). Sockets need the
    "PC Interface"/"Socket Messaging" option (unconfirmed); wirecal writes the log to a file.
    """

    key: ClassVar[str] = "rapid"
    title: ClassVar[str] = "ABB RAPID (IRC5, RobotWare 6)"
    suffix: ClassVar[str] = ".mod"
    # program modules (.mod, .modx: RAPID overview, "Program modules": unconfirmed), system
    # modules (.sys, .sysx), a task's program file (.prg, older RobotWare: unconfirmed) and
    # the I/O configuration whose signals the modules read (EIO.cfg, lang/rapid/eio.py)
    suffixes: ClassVar[tuple[str, ...]] = (".mod", ".modx", ".sys", ".sysx", ".prg", ".cfg")
    live_check: ClassVar[str] = "wc_check"
    capabilities: ClassVar[Capabilities] = Capabilities(
        int_bits=None,
        float_bits=32,
        file_io=True,  # Open/Write/Close on HOME: (the log the PC fetches)
        sockets=False,  # the programs use none (Socket Messaging option: unconfirmed)
        encoder_interfaces=("group",),
        counter_bits=32,
        software_lines={6: "IRC5 RobotWare 6", 7: "OmniCore RobotWare 7"},
    )
    patch_companion: ClassVar[str | None] = SUFFIX
    interface_notes: ClassVar[Mapping[str, str]] = {
        "group": (
            "the counter mapped to a group input signal, read with GInputDnum as a dnum "
            "(up to 32 bits: unconfirmed)"
        ),
    }
    valid_examples: ClassVar[tuple[Example, ...]] = tuple(
        Example(text, name) for name, text in examples.VALID.items()
    )
    invalid_examples: ClassVar[tuple[Example, ...]] = tuple(
        Example(text, name) for name, (text, _) in examples.INVALID.items()
    )

    def lint(
        self,
        text: str,
        source: str,
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Return the module's problems, each 'SOURCE:LINE: what' ([] = clean)."""
        from wirecal.lang.rapid.checker import check  # the parser only when linting

        return check(text, source, software, external_calls=external_calls)

    def lint_files(
        self,
        texts: Mapping[str, str],
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check the modules of one task together: each sees the others' global names."""
        from wirecal.lang.rapid.checker import check_task

        return check_task(texts, software, external_calls=external_calls)

    def patch_section(self, robot: Robot, offsets: Mapping[str, float]) -> str:
        """Return the patch's companion: ABB fine calibration's joint offsets (TOML)."""
        return patch_section(robot, offsets)
