"""Measurement logs: the CSV the controller program writes, and its strict reader.

Format (UTF-8)::

    # wirecal-log 2
    # robot: Adept Viper s650
    # plan: <sha256 fingerprint of the plan>
    # mm_per_count: 0.025488          (negative when counts fall as the wire extends)
    # payload_kg: 5                   (only with the plan's payload step: the mass mounted)
    # <free comments>
    kind,step,index,j1,j2,j3,j4,j5,j6,counts,samples,spread,t_s,settle_s
    zero,1,0,0.0000,-90.0000,...,8388000.5000,10,1,3.500,3.000
    point,1,1,...

``kind`` is ``zero`` (θ0 at the start of a step, index 0), ``point``, ``unsettled`` or
``reference``. An ``unsettled`` row is a reading of that zero or point that did not pass
the settle rule within its maximum wait (or whose samples spread too wide), logged for the
record and not used; the program then measured the same zero or point again. Step and
index are 1-based plan positions; j1..j6 the joints the controller reports (deg);
``counts`` the mean of ``samples`` raw counter readings, unwrapped relative to the first of
them; ``spread`` their max − min (counts); ``t_s`` the controller's timer when the sampling
began (s since the start of the run, 1 ms resolution); ``settle_s`` how long the program
waited after the move before sampling (s): the settle rule's wait. Version 1 logs (no
``t_s``, ``settle_s``) are still read: their readings carry no time.

``payload_kg`` (optional) marks a log taken with a plan's payload step: its points (the
plan's last step, after that step's zero reading at θ0) were measured with that mass at
the flange; it must match the plan's, and a plan with a payload step needs it
(:func:`~wirecal.solver.log.checks.payload_problems`). Logs without it read as before.

``reference`` rows (version 2, optional: when the robot file's ``[encoder]`` gives
``reference_length_mm``) come first: the wire tip seated by the operator in the nests of
a reference gauge, step 0, index 1, 2, 3, … alternating nest A (odd) and nest B (even),
one pair per seating (``reference_repeats``); the joints are where the robot stood. Each
pair's difference B − A, in counts, is the gauge's certified length read by the encoder:
it fixes the encoder's scale (:mod:`wirecal.solver.scale`). A log without them stays
valid.

A point's wire length is (counts − reference) × mm_per_count, the difference taken
modulo the counter width; the reference is the mean of the zero readings (each checked
against the first: a step change means the wire slipped, a slope in time is a drift).

The layout is read by :mod:`wirecal.formats.csv_table` (what it forgives: a BOM,
indentation, CRLF — a log pasted from a terminal), which takes a whole terminal capture:
the lines before ``# wirecal-log`` and the lines that are no row are set aside and counted,
rows the terminal broke are joined (:mod:`wirecal.formats.capture`). Counts that a
spreadsheet re-saved with too few significant digits are refused here, from the text of
the field.
"""

from __future__ import annotations

import hashlib
import math
import re
from functools import partial
from pathlib import Path

import numpy as np

from wirecal.formats.capture import RowTest
from wirecal.formats.csv_table import Row, parse_table, read_source
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import Measurements, check_log
from wirecal.solver.log.readings import Log, Reading
from wirecal.solver.log.rows import DEFAULT_TOLERANCES, Tolerances
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot

MAGIC = "# wirecal-log"
VERSION = 2
OLDER_VERSIONS = (1,)
JOINT_COLUMNS = tuple(f"j{i}" for i in range(1, 7))
TIME_COLUMNS = ("t_s", "settle_s")
COLUMNS_V1 = ("kind", "step", "index", *JOINT_COLUMNS, "counts", "samples", "spread")
COLUMNS = (*COLUMNS_V1, *TIME_COLUMNS)
HEADER_KEYS = ("robot", "plan", "mm_per_count")
OPTIONAL_KEYS = ("payload_kg",)
KINDS = ("zero", "point", "unsettled", "reference")
_Values = tuple[int, int, int, list[float]]
"""A row's step, index and samples, and its other numbers in column order (:func:`_values`)."""
REAL_COLUMNS = (*JOINT_COLUMNS, "counts", "spread", *TIME_COLUMNS)
"""A row's real numbers in column order (:func:`_values`); a version-1 row stops at spread."""
_COUNTS, _SPREAD, _T_S, _SETTLE_S = (
    REAL_COLUMNS.index(c) for c in ("counts", "spread", *TIME_COLUMNS)
)


def format_row(reading: Reading) -> str:
    """One data line, numbers written without loss at the log's resolution.

    The line of this version: a reading without its ``t_s`` and ``settle_s`` is refused.
    """
    r = reading
    if r.t_s is None or r.settle_s is None:
        raise WirecalError(
            f"a version {VERSION} log row needs t_s and settle_s: {r.kind} of step {r.step} "
            f"index {r.index} has t_s {r.t_s}, settle_s {r.settle_s}"
        )
    joints = ",".join(f"{x:.4f}" for x in r.joints_deg)
    return (
        f"{r.kind},{r.step},{r.index},{joints},{r.counts:.4f},{r.samples:d},{r.spread:g},"
        f"{r.t_s:.3f},{r.settle_s:.3f}"
    )


def format_header(
    robot: str,
    fingerprint: str,
    mm_per_count: float,
    comments: tuple[str, ...] = (),
    payload_kg: float | None = None,
) -> str:
    """Return a log's header: magic and version, header fields, comments, column names.

    ``payload_kg``: the payload step's mass (module docstring), for a plan with one.
    """
    lines = [
        f"{MAGIC} {VERSION}",
        f"# robot: {robot}",
        f"# plan: {fingerprint}",
        f"# mm_per_count: {mm_per_count!r}",
    ]
    if payload_kg is not None:
        lines.append(f"# payload_kg: {payload_kg:g}")
    lines += [f"# {c}" for c in comments]
    lines.append(",".join(COLUMNS))
    return "\n".join(lines) + "\n"


def read_log(path: str | Path) -> Log:
    """Parse a log (``-``: standard input); every format problem as ``file:line: problem``."""
    text, source, sha256 = read_source(path, "log")
    return parse_log(text, source, sha256)


def load_measurements(
    path: str | Path,
    plan: Plan,
    robot: Robot,
    tol: Tolerances = DEFAULT_TOLERANCES,
    accept_foreign: bool = False,
) -> Measurements:
    """Read a log file and check it against the plan.

    :func:`read_log`, then :func:`~wirecal.solver.log.measurements.check_log`.
    """
    return check_log(read_log(path), plan, robot, tol, accept_foreign)


def text_sha256(text: str) -> str:
    """Return the sha256 of ``text`` as wirecal writes it (UTF-8): a log's fingerprint."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def parse_log(text: str, source: str, sha256: str | None = None, *, terminal: bool = True) -> Log:
    """Parse a log's text.

    ``sha256`` of the bytes it was read from (default: of the text, UTF-8), so a patch
    always records which log it was solved from. ``terminal``: the text may be a terminal
    capture (module docstring); False for a log that a program sent itself
    (``wirecal receive``), where a line that is no row is an error.
    """
    sha256 = text_sha256(text) if sha256 is None else sha256
    seen: dict[tuple[str, ...], _Values] = {}  # each row's numbers, parsed once
    table = parse_table(
        text,
        source,
        magic=MAGIC,
        version=VERSION,
        older=OLDER_VERSIONS,
        what="log",
        columns=lambda _header, version: COLUMNS if version == VERSION else COLUMNS_V1,
        keys=(*HEADER_KEYS, *OPTIONAL_KEYS),
        capture=RowTest(KINDS, partial(_readable, seen)) if terminal else None,
    )
    problems = [*table.problems, *table.missing(HEADER_KEYS)]

    def bad(line: int, message: str) -> None:
        problems.append(f"{source}:{line}: {message}")

    mpc = math.nan
    if "mm_per_count" in table.header:
        value, line = table.header["mm_per_count"]
        try:
            mpc = float(value)
            if not math.isfinite(mpc) or mpc == 0:
                raise ValueError
        except ValueError:
            bad(line, f"mm_per_count {value!r} is not a non-zero number")
    payload = None
    if "payload_kg" in table.header:
        value, line = table.header["payload_kg"]
        try:
            payload = float(value)
            if not math.isfinite(payload) or payload <= 0:
                raise ValueError
        except ValueError:
            bad(line, f"payload_kg {value!r} is not a positive mass (kg)")
    parsed = (_parse_row(row.cells, row.line, bad, seen) for row in table.rows)
    readings = [r for r in parsed if r is not None]
    problems += lossy_counts(table.rows, source)
    if problems:
        raise WirecalError(problems)
    return Log(
        source=source,
        robot=table.header["robot"][0],
        plan=table.header["plan"][0],
        mm_per_count=mpc,
        readings=tuple(readings),
        sha256=sha256,
        notes=table.notes,
        version=table.version,
        payload_kg=payload,
    )


def _readable(seen: dict[tuple[str, ...], _Values], cells: tuple[str, ...]) -> bool:
    """Whether ``cells`` (of a version's field count) are a row whose values all parse.

    How a log's rows are told from the other text of a terminal capture; the numbers of
    each row that parse are kept in ``seen`` for :func:`_parse_row` (each row parsed once).
    """
    if cells[0].strip() not in KINDS:
        return False
    values = _values(cells)
    if values is None:
        return False
    seen[cells] = values
    return _range_problem(values[2], values[3]) is None


COUNTS = COLUMNS.index("counts")
ROUNDED_MIN_ROWS = 5
"""Integer counts that all end in zeros are taken as rounded only from this many rows on
(a true count ends in 0 one time in ten: five in a row by chance is 1 in 100 000)."""

_NUMBER = re.compile(r"[-+]?(\d*)(?:\.(\d*))?(?:[eE]([-+]?\d+))?")


def lossy_counts(rows: tuple[Row, ...], source: str) -> list[str]:
    """One problem when the counts carry fewer significant digits than a count needs.

    A spreadsheet that re-saves a log may write ``-4.4982E+05`` for -449823 (five
    significant digits) or round to tens or hundreds: the wire lengths are then off by
    up to half that many counts, silently. Detected from the text of the field: a
    mantissa shorter than the count's integer digits, or integers that all end in zeros.
    """
    short: list[tuple[int, str, int, int]] = []
    integers, rounded = 0, 0
    for row in rows:
        text = row.cells[COUNTS] if len(row.cells) > COUNTS else ""
        m = _NUMBER.fullmatch(text)
        if m is None:
            continue
        whole, frac, exp = m.group(1), m.group(2), m.group(3)
        digits = (whole + (frac or "")).lstrip("0")
        if exp is not None and digits:
            needed = len(whole.lstrip("0")) + int(exp)
            if len(digits) < needed:
                short.append((row.line, text, len(digits), needed))
        elif frac is None and whole.strip("0"):
            integers += 1
            rounded += whole.endswith("0")
    if short:
        line, text, have, needed = short[0]
        return [
            f"{source}:{line}: counts {text!r} keeps {have} significant digits of the {needed} the "
            f"count needs ({len(short)} such line(s)): the log was re-saved by a "
            "spreadsheet; use the file the controller wrote"
        ]
    if integers == len(rows) and rounded == integers and integers >= ROUNDED_MIN_ROWS:
        return [
            f"{source}:{rows[0].line}: every count ends in 0: the counts were rounded (a "
            "spreadsheet re-save with fewer significant digits?); use the file the "
            "controller wrote"
        ]
    return []


def _parse_row(
    cells: tuple[str, ...], line: int, bad, seen: dict[tuple[str, ...], _Values]
) -> Reading | None:
    """Return the row's reading, or None with each problem passed to ``bad``.

    ``seen``: the numbers of the rows the capture's row test parsed (:func:`_readable`).
    """
    kind = cells[0].strip()
    values = (seen.get(cells) or _values(cells)) if kind in KINDS else None
    if values is None:
        if kind not in KINDS:
            bad(line, f"kind {kind!r} is none of {', '.join(repr(k) for k in KINDS)}")
        _number_problems(cells, line, bad)
        return None
    step, index, samples, floats = values
    problem = _range_problem(samples, floats)
    if problem is not None:
        bad(line, problem)
        return None
    return Reading(
        kind,
        step,
        index,
        np.array(floats[:_COUNTS]),
        floats[_COUNTS],
        samples,
        floats[_SPREAD],
        line,
        floats[_T_S] if len(floats) > _T_S else None,
        floats[_SETTLE_S] if len(floats) > _SETTLE_S else None,
    )


def _values(cells: tuple[str, ...]) -> _Values | None:
    """Return the row's step, index, samples and its other numbers in column order.

    None when one is not a whole or finite number (:func:`_number_problems` says which).
    """
    try:
        ints = int(cells[1]), int(cells[2]), int(cells[10])
        floats = list(map(float, cells[3:10] + cells[11:]))
    except ValueError:
        return None
    return (*ints, floats) if all(map(math.isfinite, floats)) else None


def _range_problem(samples: int, floats: list[float]) -> str | None:
    """Return what is out of range in a row of parsed numbers (:func:`_values`), if anything."""
    if samples < 1:
        return f"samples {samples} must be at least 1"
    if min(floats[_SPREAD:]) >= 0:
        return None
    for name, value in zip(REAL_COLUMNS[_SPREAD:], floats[_SPREAD:], strict=False):
        if value < 0:
            return f"{name} {value:g} cannot be negative"
    return None


def _number_problems(cells: tuple[str, ...], line: int, bad) -> None:
    """Pass ``bad`` each field of the row that is not a whole or finite number."""
    for name, cell in (("step", cells[1]), ("index", cells[2]), ("samples", cells[10])):
        try:
            int(cell)
        except ValueError:
            bad(line, f"{name} {cell.strip()!r} is not a whole number")
    names = REAL_COLUMNS[: len(cells) - len(COLUMNS) + len(REAL_COLUMNS)]
    for name, cell in zip(names, [*cells[3:10], *cells[11:]], strict=True):
        try:
            if not math.isfinite(float(cell)):
                raise ValueError
        except ValueError:
            bad(line, f"{name} {cell.strip()!r} is not a number")
