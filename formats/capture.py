"""The rows of a table inside a terminal capture: what the operator copies and pastes.

A controller without a disk (V+ ``gen --echo-log``) or whose socket dropped (URScript's log
tab) shows its log rows on a terminal, between the program's own lines (``# Step 1 of 10``
in the programs wirecal generates, plain progress text in older ones), the operator's
answers to prompts, blank lines, and — on a narrow terminal — rows broken across two or
more lines. The reader takes the whole capture and keeps only the rows:

* a line whose first field is a row kind (``zero``, ``point``, …) is a row: read whole, or
  refused as damaged when its field count is wrong (never set aside: a damaged row is a
  lost reading);
* a row broken by the terminal is joined again only when the joined text is a readable row
  and no piece is one on its own; every piece after the first holds only the characters
  of a row's numbers (digits, ``.``, ``,``, signs). A readable row followed by such a piece
  that would also make a readable row (the break fell inside the last field) is joined only
  when the row's last piece is as long as the pieces of at least one other broken row
  (the terminal's width); otherwise it is refused, naming both lines;
* every other line is set aside and counted, the first few shown in a note.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

MAX_PIECES = 8
"""A row broken into more pieces than this is not joined (a terminal narrower than ~12)."""
SHOWN = 3
"""How many set-aside lines a note quotes."""
_CONTINUATION = re.compile(r"[0-9.,+\-eE]+")
MIN_TERMINAL = 40
"""The narrowest terminal whose captures are read (its broken header lines joined)."""
_ESCAPE = re.compile(r"\x1b\[[0-?]*[ -/]*[@-~]|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)?|\x1b[@-_]")
_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")
_TIMESTAMP = re.compile(
    r"\[?(?:\d{4}-\d{2}-\d{2}[T ])?\d{1,2}:\d{2}(?::\d{2}(?:[.,]\d+)?)?"
    r"(?:Z|[+-]\d{2}:?\d{2})?\]?(?:\s*[:|>-])?\s+"
)
_TAB = re.compile(r"\s*\t\s*")


@dataclass(frozen=True)
class RowTest:
    """How a table tells its rows from the other text of a terminal capture."""

    kinds: tuple[str, ...]  # a row's first field
    readable: Callable[[tuple[str, ...]], bool]  # fields of the right count, values that parse


@dataclass
class Taken:
    """The rows found in a capture, with line numbers (1-based) and what was not a row."""

    rows: list[tuple[int, tuple[str, ...]]]
    problems: list[str]
    aside: list[int]  # 0-based indices of the lines set aside
    joined: list[int]  # 0-based indices of the first pieces of joined rows


def clean_line(line: str) -> str:
    """Return a captured line as the terminal showed it, stripped.

    What terminal loggers add is removed: colour and other escape codes, control
    characters, a timestamp before the line (``[2026-11-27 05:18:38]``, ``05:18:38.123``,
    ISO 8601); tabs between fields become commas in a line without one.
    """
    if not line.isprintable():  # (a printable line has no escape or control character)
        line = _CONTROL.sub("", _ESCAPE.sub("", line))
    line = line.strip()
    stamp = _TIMESTAMP.match(line)
    line = line[stamp.end() :] if stamp else line
    if "\t" in line and "," not in line:
        line = _TAB.sub(",", line)
    return line.replace("\t", " ").strip()


def unfold_header(lines: list[str], first: int, column_line: str) -> list[str]:
    """Return ``lines`` with the header lines and the column line a terminal broke joined.

    From index ``first`` to the column line: a line without ``#`` or ``,`` after a ``#``
    line of at least :data:`MIN_TERMINAL` characters continues it (the terminal broke it:
    ``# plan: <64 hex digits>`` is 72); pieces that make the column line
    together are that line. Each join is put on its first line and the other pieces left
    blank, so line numbers stay those of the capture.
    """
    out = list(lines)
    head: int | None = None  # the header line being continued
    for k in range(first, len(out)):
        end = _column_end(out, k, column_line)
        if end is not None:
            out[k:end] = [column_line, *[""] * (end - k - 1)]
            return out
        line = out[k]
        if line.startswith("#"):
            head = k
        elif line and "," not in line and head is not None and len(lines[k - 1]) >= MIN_TERMINAL:
            out[head], out[k] = out[head] + line, ""
        elif line:
            return out
    return out


def _column_end(lines: list[str], k: int, column_line: str) -> int | None:
    """Return the end of the pieces from line k that make ``column_line``; None if they do not."""
    text = ""
    for j in range(k, min(len(lines), k + MAX_PIECES)):
        text += lines[j]
        if text == column_line:
            return j + 1
        if not text or not column_line.startswith(text):
            return None
    return None


def fold(lines: list[str], width: int) -> str:
    """Return ``lines`` as a terminal ``width`` columns wide shows them: longer ones broken."""
    out = []
    for line in lines:
        out += [line[k : k + width] for k in range(0, len(line), width)] or [""]
    return "\n".join(out) + "\n"


def cells_of(text: str) -> tuple[str, ...]:
    """Return the stripped fields of a CSV line (no quoting: refused before)."""
    return tuple(map(str.strip, text.split(",")))


class _Lines:
    """The capture's lines with the tests the join needs."""

    def __init__(self, lines: list[str], width: int, test: RowTest) -> None:
        self.lines = lines
        self.width = width
        self.test = test
        self._readable: dict[str, bool] = {}  # each text parsed once, however often asked
        self._cells: dict[str, tuple[str, ...]] = {}

    def cells(self, text: str) -> tuple[str, ...]:
        """Return :func:`cells_of` ``text``, the same tuple each time it is asked."""
        if text not in self._cells:
            self._cells[text] = cells_of(text)
        return self._cells[text]

    def readable(self, text: str) -> bool:
        if text not in self._readable:
            cells = self.cells(text)
            self._readable[text] = len(cells) == self.width and self.test.readable(cells)
        return self._readable[text]

    def row_like(self, k: int) -> bool:
        return self.lines[k].split(",", 1)[0].strip().strip('"') in self.test.kinds

    def piece(self, k: int) -> bool:
        """Whether line k can continue a broken row (and is no row of its own)."""
        line = self.lines[k] if k < len(self.lines) else ""
        return bool(_CONTINUATION.fullmatch(line)) and not self.readable(line)

    def join(self, k: int) -> int | None:
        """Return the end of the row starting at row-like line k, joining broken pieces."""
        text, j = self.lines[k], k + 1
        while not self.readable(text):
            if j - k >= MAX_PIECES or not self.piece(j):
                return None
            text, j = text + self.lines[j], j + 1
        return j


def take_rows(lines: list[str], first: int, width: int, test: RowTest, source: str) -> Taken:
    """Return the rows of ``lines[first:]`` (module docstring); '#' and blank lines skipped.

    A row-like line with the wrong field count is a problem, except the last line of the
    text (the caller decides whether it was cut short).
    """
    at = _Lines(lines, width, test)
    terminal = _terminal_width(at, first)
    taken = Taken([], [], [], [])
    k = first
    while k < len(lines):
        line = lines[k]
        if not line or line.startswith("#"):
            k += 1
            continue
        end = at.join(k) if at.row_like(k) else None
        if end is None:
            _not_joined(at, k, taken)
            k += 1
            continue
        end = _tail(at, k, end, terminal, taken, source)
        if end > k + 1:
            taken.joined.append(k)
        taken.rows.append((k + 1, at.cells("".join(lines[k:end]))))
        k = end
    return taken


def _not_joined(at: _Lines, k: int, taken: Taken) -> None:
    """Keep line k as a row (the reader reports what is wrong) or set it aside."""
    if at.row_like(k):
        taken.rows.append((k + 1, cells_of(at.lines[k])))
    else:
        taken.aside.append(k)


def _tail(at: _Lines, k: int, end: int, terminal: int | None, taken: Taken, source: str) -> int:
    """Extend the row k..end over a piece that also continues it, when the width says so."""
    text = "".join(at.lines[k:end])
    while at.piece(end) and at.readable(text + at.lines[end]):
        if terminal is None or len(at.lines[end - 1]) != terminal:
            taken.problems.append(
                f"{source}:{end + 1}: {at.lines[end]!r} may be the end of the row on line "
                f"{k + 1}, broken by the terminal: join the two lines or delete this one"
            )
            return end + 1
        text, end = text + at.lines[end], end + 1
    return end


def _terminal_width(at: _Lines, first: int) -> int | None:
    """Return the terminal's width: the length shared by broken rows' pieces (but the last).

    From the rows that need a join, and from readable rows followed by a piece that
    continues them; a length seen once only is no evidence (a lone number after a row).
    """
    lengths: Counter[int] = Counter()
    for k in range(first, len(at.lines)):
        if not at.lines[k] or not at.row_like(k):
            continue
        end = at.join(k)
        if end is None:
            continue
        text = "".join(at.lines[k:end])
        while at.piece(end) and at.readable(text + at.lines[end]):
            text, end = text + at.lines[end], end + 1
        lengths.update(len(at.lines[j]) for j in range(k, end - 1))
    width, seen = lengths.most_common(1)[0] if lengths else (None, 0)
    return width if seen >= 2 else None


def aside_note(lines: list[str], aside: list[int], source: str) -> str:
    """Say how many lines were set aside and quote the first few."""
    shown = ", ".join(f"line {k + 1} {_short(lines[k])!r}" for k in aside[:SHOWN])
    more = ", …" if len(aside) > SHOWN else ""
    return (
        f"{source}: set aside {len(aside)} line(s) that are not log rows (terminal text): "
        f"{shown}{more}"
    )


def joined_note(joined: list[int], source: str) -> str:
    """Say how many rows broken by the terminal were joined again."""
    return (
        f"{source}: joined {len(joined)} row(s) the terminal had broken across lines "
        f"(the first on line {joined[0] + 1})"
    )


def _short(line: str, n: int = 40) -> str:
    return line if len(line) <= n else line[: n - 1] + "…"
