"""Read the controller solver's result file (``WCSOLVE.CSV``).

The offsets wc.solve or wc.solve2 wrote, read by the same CSV-with-header reader as every
other log.
"""

from __future__ import annotations

from pathlib import Path

from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.csv_table import parse_table, read_source


def read_result(path: Path) -> dict[str, float]:
    """Offsets from the controller solver's result file (``# wirecal-controller-result 1``)."""
    text, source, _ = read_source(path, "controller result")
    table = parse_table(
        text,
        source,
        magic="# wirecal-controller-result",
        version=1,
        what="controller result",
        columns=("parameter", "unit", "offset"),
        keys=(),
    )
    problems = list(table.problems)
    out = {}
    for row in table.rows:
        try:
            out[row.cells[0]] = float(row.cells[2])
        except ValueError:
            problems.append(f"{source}:{row.line}: offset {row.cells[2]!r} is not a number")
    if problems:
        raise WirecalError(problems)
    return out
