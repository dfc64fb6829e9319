"""The plausibility gate as ``solve``, ``report`` and the demo apply it.

:func:`wirecal.solver.plausibility.gate`, its findings naming the robot's live-check program
(the language's, from the registry). A module of its own so that ``wirecal solve`` loads the
registry's declarations only, not the generators and the twin (start-up, docs/benchmarks.md).
"""

from __future__ import annotations

from typing import Any

from wirecal.lang.registry import language
from wirecal.solver.plausibility import gate as _gate
from wirecal.solver.solve import SolveResult
from wirecal.solver.verdict import Plausibility


def gate(result: SolveResult, method: str, **options: Any) -> Plausibility:
    """:func:`wirecal.solver.plausibility.gate`, its findings naming the robot's live-check."""
    live_check = language(result.robot.controller.language).live_check
    return _gate(result, method, live_check=live_check, **options)
