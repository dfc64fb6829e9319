"""The controller's encoder counter: a signed integer of ``bits`` that wraps.

A reading is the counter's value; a wire length is the difference of two readings, taken
modulo the counter's width so that a wrap between them does not matter (the counter must
not turn over by half its range or more between the two, which an encoder range of a few
metres never does at 24 bits or more). The robot file gives the width (8 to 64 bits).

Arithmetic is in IEEE double precision, as the readings are averaged counts: it is exact
while the counts are integers below 2^53 in magnitude. A counter wider than 53 bits is
therefore started within ±2^52 (:meth:`Counter.random_start`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EXACT_BITS = 53
"""Integers up to 2^53 in magnitude are exact in a double."""


@dataclass(frozen=True)
class Counter:
    """A signed ``bits``-wide counter: values in [−half, half), ``full`` = 2^bits."""

    bits: int

    def __post_init__(self) -> None:
        """Refuse a width outside 8–64 bits."""
        if not 8 <= self.bits <= 64:
            raise ValueError(f"counter of {self.bits} bits: give 8 to 64")

    @property
    def half(self) -> int:
        """2^(bits−1): the first value the counter cannot hold."""
        return 2 ** (self.bits - 1)

    @property
    def full(self) -> int:
        """2^bits: the counter's modulus."""
        return 2**self.bits

    def wrap(self, counts: np.ndarray | float) -> np.ndarray:
        """Return the counter's value for an unbounded count.

        ``counts`` brought into [−half, half) modulo 2^bits.
        """
        # x − k·2^bits rather than (x + half) mod 2^bits − half: adding half first would
        # round small counts away once half exceeds 2^53 (a counter wider than 53 bits)
        x, full = np.asarray(counts, dtype=float), float(self.full)
        return x - full * np.floor((x + float(self.half)) / full)

    def difference(self, a: np.ndarray | float, b: np.ndarray | float) -> np.ndarray:
        """Return the signed count a − b of two readings, modulo the counter's width."""
        return self.wrap(np.asarray(a, dtype=float) - b)

    def random_start(self, rng: np.random.Generator, within: float = 1.0) -> float:
        """Draw a start value where a real counter happens to be.

        A start value drawn uniformly among the integers of ``within`` × the counter's
        range (at most ±2^52, see the module doc): where a real counter happens to be.
        """
        span = int(2 ** (min(self.bits, EXACT_BITS) - 1) * within)
        return float(rng.integers(-span, span))
