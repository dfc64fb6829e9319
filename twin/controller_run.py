"""One run of a generated controller solver in the twin, whatever the language."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass


@dataclass(frozen=True)
class ControllerRun:
    """One run of the generated controller solver in the twin."""

    program: str  # "wc.solve", "wc.solve2" or "wc_solve"
    offsets: dict[str, float]  # identified offsets (deg, mm), read from its result
    operations: Counter[str]  # arithmetic executed: add (+ −), mul, div, sqrt
    console: tuple[str, ...]
    syncs: int = 0  # URScript: sync() calls (one 2 ms frame each)
    most_between_syncs: int = 0  # URScript: most operations between two sync() calls

    @property
    def total_operations(self) -> int:
        """Return the number of operations counted, all kinds together."""
        return sum(self.operations.values())
