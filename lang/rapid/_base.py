"""A stand-in for ``wirecal.lang.base`` until the registry's branch is merged.

The same names and fields as the registry's declaration (Capabilities, Example, Language);
the integrator replaces ``from wirecal.lang.rapid._base import …`` with
``wirecal.lang.base`` and deletes this file.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar


@dataclass(frozen=True)
class Capabilities:
    """What a controller language can do, as far as wirecal's programs use it."""

    int_bits: int | None
    float_bits: int
    file_io: bool
    sockets: bool
    encoder_interfaces: tuple[str, ...]
    counter_bits: int
    software_lines: Mapping[int, str]


@dataclass(frozen=True)
class Example:
    """A snippet the checker must accept (valid) or refuse (invalid), and the page that says so."""

    text: str
    source: str
    software: str | None = None


class Language:
    """One controller language: its key, title, program suffix, live check and checker."""

    key: ClassVar[str]
    title: ClassVar[str]
    suffix: ClassVar[str]
    live_check: ClassVar[str]
    capabilities: ClassVar[Capabilities]
    interface_notes: ClassVar[Mapping[str, str]] = {}
    patch_companion: ClassVar[str | None] = None
    default: ClassVar[bool] = False
    valid_examples: ClassVar[tuple[Example, ...]] = ()
    invalid_examples: ClassVar[tuple[Example, ...]] = ()

    def lint(
        self,
        text: str,
        source: str,
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Return the checker's problems, each 'SOURCE:LINE: what' ([] = clean)."""
        raise NotImplementedError

    def patch_section(self, robot: Any, offsets: Mapping[str, float]) -> str | None:
        """Return the text of the language's own patch companion (None: it has none)."""
        return None
