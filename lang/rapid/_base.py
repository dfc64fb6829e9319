"""A stand-in for ``wirecal.lang.base`` until the registry's branch is merged.

The same names and fields as the agreed declaration (Capabilities, Language); the
integrator replaces ``from wirecal.lang.rapid._base import …`` with ``wirecal.lang.base``
and deletes this file.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar


@dataclass(frozen=True)
class Capabilities:
    """What a controller language can do (see the registry's declaration)."""

    int_bits: int | None
    float_bits: int
    file_io: bool
    sockets: bool
    encoder_interfaces: tuple[str, ...]
    counter_bits: int
    software_lines: Mapping[int, str]


class Language:
    """A controller language: its key, title, program suffix, live check and checker."""

    key: ClassVar[str]
    title: ClassVar[str]
    suffix: ClassVar[str]
    live_check: ClassVar[str]
    capabilities: ClassVar[Capabilities]

    def lint(self, text: str, source: str, software: str | None = None) -> list[str]:
        """Return the checker's problems, each 'SOURCE:LINE: what' ([] = clean)."""
        raise NotImplementedError
