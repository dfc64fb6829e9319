"""Read wirecal's CSV-with-header files.

The one reader of wirecal's CSV-with-header files: measurement logs, validation logs and
the controller solver's result file share its layout and its tolerance.

Layout::

    # wirecal-<kind> <version>       magic and version (first line)
    # key: value                     header fields the format knows
    # free text                      comments
    col1,col2,...                    the column line
    v1,v2,...                        one row per line; blank and '#' lines are skipped

What the reader forgives, because a log copied from a terminal, an editor or another
operating system carries it: a UTF-8 byte-order mark, blank lines before the first line,
indentation and trailing whitespace on every line, CRLF or CR line ends, spaces around
fields. A last row cut short by a run that
stopped while writing is a note, not an error. What it refuses with one message: fields in
double quotes (a spreadsheet's export), rows with the wrong number of fields (each as
``file:line: problem``). A reader that says how to tell its rows (the measurement log's
:func:`~wirecal.formats.log.parse_log`) also takes a whole terminal capture
(:mod:`wirecal.formats.capture`).
"""

from __future__ import annotations

import contextlib
import hashlib
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from wirecal.formats.capture import (
    MIN_TERMINAL,
    RowTest,
    aside_note,
    cells_of,
    clean_line,
    joined_note,
    take_rows,
    unfold_header,
)
from wirecal.formats.fileio import STDIN as STDIN  # the name callers know
from wirecal.formats.fileio import decode_text, read_input
from wirecal.solver.errors import WirecalError


@dataclass(frozen=True)
class Row:
    """One data row of a table, with its line number."""

    line: int  # 1-based line number in the file
    cells: tuple[str, ...]  # stripped fields


@dataclass(frozen=True)
class Table:
    """A CSV-with-header file, checked for layout only."""

    source: str
    header: dict[str, tuple[str, int]]  # known key → (value, line)
    comments: tuple[str, ...]
    column_line: int  # 1-based line of the column line
    rows: tuple[Row, ...]
    problems: tuple[str, ...]  # file:line: problem, for the caller to report with its own
    notes: tuple[str, ...]
    version: int  # the version on the first line

    def missing(self, keys: tuple[str, ...]) -> list[str]:
        """Return a problem for each header key that is absent."""
        return [
            f"{self.source}:{self.column_line - 1}: header '# {key}: …' is missing"
            for key in keys
            if key not in self.header
        ]


def read_source(path: str | Path, what: str) -> tuple[str, str, str]:
    """Return the text, its source name and the sha256 of its bytes; ``-`` reads standard input."""
    raw, source = read_input(path, what)
    return decode_text(raw, source, f"wirecal {what}"), source, hashlib.sha256(raw).hexdigest()


def parse_table(
    text: str,
    source: str,
    *,
    magic: str,
    version: int,
    what: str,
    columns: tuple[str, ...] | Callable[[dict[str, tuple[str, int]], int], tuple[str, ...]],
    keys: tuple[str, ...],
    older: tuple[int, ...] = (),
    capture: RowTest | None = None,
) -> Table:
    """Split a file into header, column line and rows.

    Raise on a wrong magic, version, column line or quoted fields, and collect row-length
    problems in ``Table.problems``.

    ``what`` names the format in messages ("log", "validation log", …); ``keys`` are the
    header fields it knows (any other ``#`` line is a comment). ``columns`` may depend on
    the header and the version: a function of both that returns them (or raises).
    ``older`` lists the earlier versions the caller still reads. With ``capture`` (how
    to tell a row), the text may be a whole terminal capture: the lines before the magic
    line and every line that is no row are set aside, rows the terminal broke are joined
    (:mod:`wirecal.formats.capture`), and the notes say so.
    """
    text = text.removeprefix("\ufeff")
    ends_with_newline = text.endswith(("\n", "\r"))
    tidy = str.strip if capture is None else clean_line
    lines = [tidy(line) for line in text.splitlines()]
    start, found = _check_first_line(
        lines, source, magic, (version, *older), what, anywhere=capture is not None
    )
    if capture is not None:  # a terminal narrower than the header broke its lines
        guess = columns({}, found) if callable(columns) else columns
        lines = unfold_header(lines, start + 1, ",".join(guess))
    header, comments, problems, n = _read_header(lines, start + 1, source, keys)
    line = lines[n] if n < len(lines) else ""
    hint = _other_version(line, columns, header, (version, *older), (found, magic))
    hint = hint or _narrow_terminal(lines, n)
    if callable(columns):
        columns = columns(header, found)
    kinds = capture.kinds if capture is not None else None
    _check_column_line(lines, n, source, columns, problems, kinds, hint)
    notes: list[str] = []
    if capture is None:
        rows = _read_rows(lines, n + 1)
    else:
        rows, notes = _capture_rows(
            lines, (start, n + 1), source, magic, len(columns), capture, problems
        )
    last_cut = len(lines) if not ends_with_newline else None
    rows = _check_widths(rows, source, len(columns), last_cut, problems, notes)
    return Table(
        source, header, tuple(comments), n + 1, tuple(rows), tuple(problems), tuple(notes), found
    )


def _check_first_line(
    lines: list[str],
    source: str,
    magic: str,
    versions: tuple[int, ...],
    what: str,
    anywhere: bool = False,
) -> tuple[int, int]:
    """Return the index of the first non-blank line and its version.

    Raise unless it is the magic and one of ``versions`` (the first is the current one).
    ``anywhere``: the first line that starts with the magic (a terminal capture), when one does.
    """
    start = next((k for k, line in enumerate(lines) if line), 0)  # blank lines of a paste
    if anywhere:
        start = next((k for k, line in enumerate(lines) if line.startswith(magic)), start)
    first = lines[start] if lines else ""
    if first.strip('"').startswith(magic) and first.startswith('"'):
        raise WirecalError(
            f"{source}:{start + 1}: the first line is {first!r}: lines and fields in double "
            "quotes (a spreadsheet's export); use the file as written, or save it as plain "
            "CSV without quotes"
        )
    if not first.startswith(magic):
        raise WirecalError(
            f"{source}:{start + 1}: not a wirecal {what}: the first line must be "
            f"'{magic} {versions[0]}'"
        )
    found = first[len(magic) :].strip()
    readable = {str(v): v for v in versions}
    if found not in readable:
        known = " or ".join(str(v) for v in sorted(versions))
        raise WirecalError(
            f"{source}:{start + 1}: {what} version {found!r}; this wirecal reads version {known}"
        )
    return start, readable[found]


def _read_header(
    lines: list[str], n: int, source: str, keys: tuple[str, ...]
) -> tuple[dict[str, tuple[str, int]], list[str], list[str], int]:
    """Read the ``#`` lines from index n: the known keys, the comments, the problems.

    Returns them and the index of the first line after them.
    """
    header: dict[str, tuple[str, int]] = {}
    comments: list[str] = []
    problems: list[str] = []
    while n < len(lines) and (not lines[n] or lines[n].startswith("#")):
        if not lines[n]:  # a blank line, or the rest of a line a terminal broke
            n += 1
            continue
        body = lines[n][1:].strip()
        key, sep, value = body.partition(":")
        key = key.strip()
        if sep and key in keys:
            if key in header:
                problems.append(f"{source}:{n + 1}: '{key}' is given twice")
            header[key] = (value.strip(), n + 1)
        else:
            comments.append(body)
        n += 1
    return header, comments, problems, n


def _other_version(
    line: str,
    columns: tuple[str, ...] | Callable[[dict[str, tuple[str, int]], int], tuple[str, ...]],
    header: dict[str, tuple[str, int]],
    versions: tuple[int, ...],
    first: tuple[int, str],
) -> str:
    """Say so when ``line`` is another version's column line ('' if not).

    ``first``: the version the first line gives and the magic it starts with.
    """
    if not callable(columns):
        return ""
    found, magic = first
    got = ",".join(c.strip() for c in line.split(","))
    for other in versions:
        with contextlib.suppress(WirecalError):  # columns that this header cannot have
            if other != found and ",".join(columns(header, other)) == got:
                return (
                    f": that is version {other}'s column line below a first line of version "
                    f"{found}; make them agree (the first line '{magic} {other}' if the rows "
                    f"are version {other}'s)"
                )
    return ""


def _narrow_terminal(lines: list[str], n: int) -> str:
    """Return the end of a wrong column line's message for a header a terminal broke.

    When line n looks like the rest of the ``#`` line before it, broken by a terminal
    narrower than those a capture is read from
    (:data:`~wirecal.formats.capture.MIN_TERMINAL`); else "".
    """
    line = lines[n] if n < len(lines) else ""
    before = lines[n - 1] if n > 0 else ""
    if not line or "," in line or not before.startswith("#") or len(before) >= MIN_TERMINAL:
        return ""
    if any(len(x) > len(before) for x in lines[: n + 1]):  # wider than that terminal
        return ""
    return (
        f": it looks like the rest of line {n} ({before!r}), broken by a terminal "
        f"{len(before)} columns wide; copy the log again from a terminal at least "
        f"{MIN_TERMINAL} columns wide"
    )


def _check_column_line(
    lines: list[str],
    n: int,
    source: str,
    columns: tuple[str, ...],
    problems: list[str],
    kinds: tuple[str, ...] | None = None,
    hint: str = "",
) -> None:
    """Raise unless line n is the column line and neither it nor a later line has double quotes.

    ``kinds`` (a terminal capture): only the lines that start with a row kind, quoted
    or not, count; other terminal text may quote. ``hint`` ends a wrong column line's
    message (another version's column line).
    """
    expected = ",".join(columns)
    if n >= len(lines):
        raise WirecalError(
            [*problems, f"{source}:{n}: the column line is missing: it must be '{expected}'"]
        )
    got = ",".join(c.strip() for c in lines[n].split(","))
    if got.replace('"', "") != expected:
        raise WirecalError(
            [
                *problems,
                f"{source}:{n + 1}: columns are {got!r}; the column line must be "
                f"'{expected}'{hint}",
            ]
        )
    quoted = [
        k + 1
        for k in range(n + 1, len(lines))
        if '"' in lines[k] and (kinds is None or lines[k].split(",")[0].strip('" ') in kinds)
    ]
    if got != expected:  # the column line itself is right but for its quotes
        quoted.insert(0, n + 1)
    if quoted:
        raise WirecalError(
            f"{source}:{quoted[0]}: fields are in double quotes on {len(quoted)} "
            "line(s): a spreadsheet re-saved the file; use the file as written, or save "
            "it as plain CSV without quotes"
        )


def _read_rows(lines: list[str], first: int) -> list[Row]:
    """Return every line from index ``first`` on that is neither blank nor ``#``, as a row."""
    return [
        Row(k + 1, cells_of(lines[k]))
        for k in range(first, len(lines))
        if lines[k] and not lines[k].startswith("#")
    ]


def _capture_rows(
    lines: list[str],
    span: tuple[int, int],
    source: str,
    magic: str,
    width: int,
    test: RowTest,
    problems: list[str],
) -> tuple[list[Row], list[str]]:
    """Return the rows of a terminal capture and its notes (set aside, joined).

    ``span``: the indices of the magic line and of the first line after the column line.
    """
    start, first = span
    taken = take_rows(lines, first, width, test, source)
    aside = [k for k in range(start) if lines[k]] + taken.aside
    problems += [
        f"{source}:{k + 1}: a second log begins here (the capture holds two runs): paste "
        "one run only"
        for k in range(first, len(lines))
        if lines[k].startswith(magic)
    ]
    notes = [aside_note(lines, aside, source)] if aside else []
    if taken.joined:
        notes.append(joined_note(taken.joined, source))
    problems += taken.problems
    return [Row(line, cells) for line, cells in taken.rows], notes


def _check_widths(
    rows: list[Row],
    source: str,
    width: int,
    last_cut: int | None,
    problems: list[str],
    notes: list[str],
) -> list[Row]:
    """Keep the rows of ``width`` fields; one short on line ``last_cut`` is a note.

    Most rows of one other width are one problem: the header does not match the rows.
    """
    kept, wrong = [], []
    for row in rows:
        if len(row.cells) == width:
            kept.append(row)
        elif row.line == last_cut and len(row.cells) < width:
            notes.append(
                f"{source}:{row.line}: incomplete last line ignored (the run stopped while "
                "writing it)"
            )
        else:
            wrong.append(row)
    widths = Counter(len(row.cells) for row in wrong)
    common, n = widths.most_common(1)[0] if widths else (0, 0)
    if n >= 3 and n > len(kept):
        first = next(row.line for row in wrong if len(row.cells) == common)
        problems.append(
            f"{source}:{first}: {n} rows have {common} fields where the column line names "
            f"{width}: the first line's version or the column line does not match the rows "
            "(e.g. a version 1 header above version 2 rows); use the file as written"
        )
        wrong = [row for row in wrong if len(row.cells) != common]
    problems += [
        f"{source}:{row.line}: has {len(row.cells)} fields; expected {width}" for row in wrong
    ]
    return kept
