"""Read the controller solver's result (``# wirecal-controller-result 1``).

The offsets wc.solve or wc.solve2 (V+) wrote to ``WCSOLVE.CSV``, or wc_solve (URScript)
sent after the log's rows, every line prefixed with :data:`IN_LOG_PREFIX` so that it is
a comment of the log; both read by the same CSV-with-header reader as every other log.
"""

from __future__ import annotations

from pathlib import Path

from wirecal.formats.csv_table import parse_table, read_source
from wirecal.solver.errors import WirecalError

IN_LOG_PREFIX = "# controller: "
"""What wc_solve puts before each line of its result, inside the log it sends."""


def read_result(path: Path) -> dict[str, float]:
    """Offsets from the controller solver's result file (``# wirecal-controller-result 1``)."""
    text, source, _ = read_source(path, "controller result")
    return parse_result(text, source)


def result_in_log(text: str) -> str | None:
    """Return the result lines a log carries (prefix removed), or None if it has none."""
    lines = [
        line[len(IN_LOG_PREFIX) :] for line in text.splitlines() if line.startswith(IN_LOG_PREFIX)
    ]
    return "\n".join(lines) + "\n" if lines else None


def parse_result(text: str, source: str) -> dict[str, float]:
    """Offsets from a controller result's text; ``source`` names it in messages."""
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
