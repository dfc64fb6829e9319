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


def warnings(result: SolveResult, verdict: Plausibility) -> list[str]:
    """Return what the user must know of a result that is written or shown.

    The gate's findings accepted, the checks left undone and a drift to heed: ``solve``
    and ``report`` state the same.
    """
    lines = [f"implausible result accepted: {f.message}" for f in verdict.findings]
    lines += list(result.unchecked)
    if result.drift is not None and result.drift.warning:
        lines.append(f"{result.measurements.source}: {result.drift.warning}")
    return lines
