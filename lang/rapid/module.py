"""What the generated RAPID module and the twin that runs it agree on.

The module's file name, where its log goes, the group input it reads the counter from
and how its numbers are written (the generator writes them, the twin's adapter writes its
own readings the same way): one place, below both ``gen/`` and ``twin/``.
"""

from __future__ import annotations

import numpy as np

from wirecal.solver.robot import Robot

MODULE_FILE = "WIRECAL.mod"
"""The one program file: the module WIRECAL."""

LOG_DIR = "HOME:"
"""The controller's directory the log is written to (Open's device)."""

LOG_FILE = "WIRECAL.LOG"
"""The log's default file name in :data:`LOG_DIR`."""

GROUP_COUNTER_BITS = 32
"""The counter width the module reads: a 32-bit group input through GInputDnum."""


def signal_name(robot: Robot) -> str:
    """Return the group input signal the module reads: ``wc_giCount<channel>``."""
    return f"wc_giCount{robot.encoder.channel}"


def num_literal(x: float) -> str:
    """Write ``x`` as the nearest 32-bit float (num), with the fewest digits that give it."""
    return str(np.format_float_positional(np.float32(x), unique=True, trim="0"))


def dnum_literal(x: float) -> str:
    """Write ``x`` as a 64-bit float (dnum), with the fewest digits that give it back."""
    return str(np.format_float_positional(np.float64(x), unique=True, trim="0"))
