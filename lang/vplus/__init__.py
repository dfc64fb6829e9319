"""Adept/Omron V+ and eV+: the front end (grammar, parser, checker, keyword table).

The declaration below is what the rest of wirecal knows of V+ (V+ Language User's Guide
v17, "UG"); the facts come from the generator's programs and the pages cited.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import ClassVar

from wirecal.lang.base import Capabilities, Example, Language
from wirecal.lang.registry import register
from wirecal.solver.errors import WirecalError


def _program(body: str) -> str:
    return ".PROGRAM t.main()\n" + body + "\n.END\n"


@register
class VPlus(Language):
    """V+/eV+: one module (``.v2``) with every program; the log is a file on the controller."""

    key = "vplus"
    title = "Adept/Omron V+ and eV+"
    suffix = ".v2"
    suffixes = (".v2", ".pg")  # .pg: a program file as V+ STOREP writes it (unconfirmed)
    live_check = "wc.check"
    default = True  # robot files written before [controller] existed are V+
    capabilities = Capabilities(
        int_bits=None,  # no integer type: reals, whole numbers exact within ±2^24 (UG p. 102)
        float_bits=64,  # DOUBLE where the programs need it (^D constants, UG p. 102)
        file_io=True,  # FOPEN/FCMND/FWRITE to the controller's disk
        sockets=False,  # the programs use none (V+ TCP: unconfirmed)
        encoder_interfaces=("belt", "device"),  # DEFBELT/BELT (UG pp. 35, 317), DEVICE
        counter_bits=24,  # the belt counter, signed 24 bits rolling over (UG p. 312)
        software_lines={},
    )
    interface_notes: ClassVar[Mapping[str, str]] = {"belt": "DEFBELT/BELT", "device": "DEVICE"}
    first_channel: ClassVar[Mapping[str, int]] = {"belt": 1}  # belt encoders count from 1
    valid_examples: ClassVar[tuple[Example, ...]] = (
        Example(_program("SET p = HERE\nAPPRO p, 50\nDEPARTS 30"), "unconfirmed"),
        Example(_program("65535 x = 16777215\ny = -16777216"), "UG pp. 35, 102"),
        Example(_program('$s = "' + "a" * 128 + '"'), "UG p. 100"),
        Example(_program("READY\nALIGN"), "unconfirmed: READY, ALIGN keyword pages not read"),
        Example(_program("stop = STATE(4) BAND 4"), "adept_experimental adept_ros.v2 l. 344"),
    )
    invalid_examples: ClassVar[tuple[Example, ...]] = (
        Example(_program("70000 x = 1"), "UG p. 35"),
        Example(_program('$s = "' + "b" * 130 + '"'), "UG p. 100"),
        Example(_program("x = 16777216"), "UG p. 102"),
        Example(_program("x = 1E+400"), "UG p. 102"),
        Example(_program("fine = 1"), "UG p. 99; FINE a keyword: unconfirmed"),
        Example(_program("ready = 1"), "UG p. 99; READY a keyword: unconfirmed"),
        Example(_program("SET dest = HERE"), "UG p. 99; DEST a keyword: unconfirmed"),
        Example(_program("AUTO align"), "UG p. 99; ALIGN a keyword: unconfirmed"),
    )

    def lint_files(
        self,
        texts: Mapping[str, str],
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check V+ files loaded together: a CALL may name a program of any of them."""
        from wirecal.lang.vplus.files import check_files

        return check_files(texts, external_calls=external_calls)

    def lint(
        self,
        text: str,
        source: str,
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check a module as LOAD would (:func:`~wirecal.lang.vplus.parser.parse_module`)."""
        from wirecal.lang.vplus.parser import parse_module

        try:
            parse_module(text, source, external_calls=external_calls)
        except WirecalError as exc:
            return list(exc.problems)
        return []
