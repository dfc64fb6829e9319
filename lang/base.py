"""What a controller language declares: its capabilities, its checker and its conformance cases.

Each ``lang/<key>/__init__.py`` subclasses :class:`Language` and registers it
(:func:`wirecal.lang.registry.register`); everything else asks the registry instead of naming
a language.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar


@dataclass(frozen=True)
class Capabilities:
    """What a controller language can do, as far as wirecal's programs use it."""

    int_bits: int | None  # width of its integers (None: no integer type)
    float_bits: int  # width of the reals the programs use
    file_io: bool  # can write the log to a file on the controller
    sockets: bool  # can send the log to the PC over TCP
    encoder_interfaces: tuple[str, ...]  # [encoder] interface values; the first is the default
    counter_bits: int  # the counter width the generated programs read
    software_lines: Mapping[int, str]  # major version → product line ({} when not versioned)


@dataclass(frozen=True)
class Example:
    """A snippet the checker must accept (valid) or refuse (invalid), and the page that says so."""

    text: str
    source: str  # the manual page the rule comes from ("User's Guide p. 99")
    software: str | None = None  # the controller software to check against, if it matters


class Language:
    """One controller language: the robot file's ``[controller] language`` value and its facts."""

    key: ClassVar[str]  # the robot file's [controller] language value
    title: ClassVar[str]  # its name in messages
    suffix: ClassVar[str]  # the suffix of the program files wirecal writes
    suffixes: ClassVar[tuple[str, ...]] = ()  # every suffix its program files take (lint)
    live_check: ClassVar[str]  # the generated program that shows the live counts
    capabilities: ClassVar[Capabilities]
    interface_notes: ClassVar[Mapping[str, str]] = {}  # encoder interface → how it is read
    first_channel: ClassVar[Mapping[str, int]] = {}  # interface → its first channel (default 0)
    patch_companion: ClassVar[str | None] = None  # suffix of its file beside a patch, if any
    # the companion's per-joint vectors, where it holds them: (table, keys); None: not read back
    companion_vectors: ClassVar[tuple[str, tuple[str, ...]] | None] = None
    default: ClassVar[bool] = False  # the language of a robot file without [controller]
    valid_examples: ClassVar[tuple[Example, ...]] = ()  # conformance: snippets lint accepts
    invalid_examples: ClassVar[tuple[Example, ...]] = ()  # conformance: snippets lint refuses

    def lint(
        self,
        text: str,
        source: str,
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Return the checker's problems, each 'SOURCE:LINE: what' ([] = clean).

        ``software``: the controller software version to check calls against (languages
        without versions ignore it); ``external_calls``: calls to programs not in ``text``
        are allowed (loaded from another file).
        """
        raise NotImplementedError

    def lint_files(
        self,
        texts: Mapping[str, str],
        software: str | None = None,
        *,
        external_calls: bool = False,
    ) -> list[str]:
        """Check files a controller loads together as one program (file name → text).

        One RAPID task's modules, V+ files sharing programs, a URScript program with the
        files it includes: a language that knows how they share names overrides this;
        by default each file is checked alone. Problems are 'SOURCE:LINE: what', each
        naming the file it is in ([] = clean).
        """
        return [
            problem
            for source, text in texts.items()
            for problem in self.lint(text, source, software, external_calls=external_calls)
        ]

    def knows_software(self, software: str) -> bool:
        """Whether declared ``software`` ("major.minor…") is of one of the language's lines.

        Any software is, for a language not versioned (no ``software_lines``).
        """
        lines = self.capabilities.software_lines
        return not lines or int(software.split(".")[0]) in lines

    def software_lines_text(self) -> str:
        """Name the language's product lines: "CB3 3.x, e-Series 5.x, PolyScope X 10.x"."""
        lines = self.capabilities.software_lines
        return ", ".join(f"{name} {major}.x" for major, name in lines.items())

    def all_suffixes(self) -> tuple[str, ...]:
        """Return every suffix of the language's program files, :attr:`suffix` first."""
        return (self.suffix, *(s for s in self.suffixes if s != self.suffix))

    def patch_section(self, robot: Any, offsets: Mapping[str, float]) -> str | None:
        """Return the text of the language's own patch companion (None: it has none).

        The patch ``<name>.toml`` gets it beside it as ``<name>`` + :attr:`patch_companion`;
        ``offsets`` are the identified ones by parameter name (deg, mm).
        """
        return None
