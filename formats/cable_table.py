"""Read a table of joint angles and cable lengths taken without wirecal (``wirecal fit``).

A CSV or TSV file with a header line, or a sheet of an ``.xlsx`` workbook (the optional
extra ``wirecal[xlsx]``: openpyxl). Every data row holds the joint angles (degrees), the
absolute cable length (mm) and, optionally, the controller's own nominal x, y, z (mm).
Which column is which comes from a column map ``"j1=q1,…,j6=q6,length=L[,x=X,y=Y,z=Z]"``;
without one the columns must be named ``j1``…``j6`` and ``length`` (and ``x``, ``y``, ``z``
when present). Blank lines and lines starting with ``#`` are skipped; the delimiter of a
text file is the header line's (tab, semicolon or comma).

The resolution of the joints and of the length (what the quantisation floor of ``fit`` is
propagated from) is read off the values: the number of decimals that nine rows in ten need
at most (a mistyped row with an extra digit does not change it).

The table and its column map are the solver's types (:mod:`~wirecal.solver.fit.cable_data`);
this module reads files into them.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import zipfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from wirecal.formats.csv_table import read_source
from wirecal.formats.fileio import read_input
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.cable_data import AXES, CableTable, ColumnMap

RESOLUTION_QUANTILE = 0.9
"""Share of the values whose decimals fix a column's resolution (the rest may be typos)."""

MAX_DECIMALS = 6

MAX_XLSX_PARTS = 1000
MAX_XLSX_UNPACKED_BYTES = 128 * 2**20
"""Bounds of a workbook before it is read (:func:`check_workbook`): a sheet of 100,000 rows
of ten numbers unpacks to about 40 MB of XML."""


def default_map(n_joints: int, header: tuple[str, ...] = ()) -> ColumnMap:
    """Return the map of columns named j1…jn and length (and x, y, z if the header has them)."""
    xyz = ("x", "y", "z") if all(a in header for a in AXES) else None
    return ColumnMap(tuple(f"j{i + 1}" for i in range(n_joints)), "length", xyz)


def parse_map(text: str | None, n_joints: int, header: tuple[str, ...] = ()) -> ColumnMap:
    """Parse ``--map "j1=q1,…,j6=q6,length=L[,x=X,y=Y,z=Z]"``; raise naming what is wrong."""
    if text is None:
        return default_map(n_joints, header)
    keys = [f"j{i + 1}" for i in range(n_joints)] + ["length", *AXES]
    given: dict[str, str] = {}
    problems = []
    for item in filter(None, (s.strip() for s in text.split(","))):
        key, sep, column = (s.strip() for s in item.partition("="))
        if not sep or not column:
            problems.append(f"--map: {item!r} is not KEY=COLUMN")
        elif key not in keys:
            problems.append(f"--map: unknown key {key!r}; the keys are {', '.join(keys)}")
        elif key in given:
            problems.append(f"--map: {key} is given twice")
        else:
            given[key] = column
    missing = [k for k in keys[: n_joints + 1] if k not in given]
    if missing:
        problems.append(f"--map: {', '.join(missing)} missing; map every joint and the length")
    problems += _shared_columns(given)
    axes = [a for a in AXES if a in given]
    if axes and len(axes) != 3:
        problems.append("--map: give x, y and z together, or none of them")
    if problems:
        raise WirecalError(problems)
    xyz = (given["x"], given["y"], given["z"]) if axes else None
    return ColumnMap(tuple(given[k] for k in keys[:n_joints]), given["length"], xyz)


def _shared_columns(given: dict[str, str]) -> list[str]:
    """Return a problem for each column the map gives two keys (one column, one meaning)."""
    roles = {c: [k for k, col in given.items() if col == c] for c in given.values()}
    return [
        f"--map: column {c!r} is given for {' and '.join(keys)}; each key needs its own column"
        for c, keys in roles.items()
        if len(keys) > 1
    ]


def read_cable_table(
    path: str | Path, column_map: str | None = None, *, sheet: str | None = None, n_joints: int = 6
) -> CableTable:
    """Read a CSV/TSV or ``.xlsx`` cable-length table (module docstring)."""
    sheets, empty = "", ""
    if str(path).lower().endswith((".xlsx", ".xlsm")):
        header, rows, source, digest, sheets = _xlsx_cells(path, sheet)
        empty = (
            " (an empty cell: if it shows a value in Excel it is a formula never calculated; "
            "open and save the workbook in Excel or LibreOffice)"
        )
    else:
        if sheet is not None:
            raise WirecalError(f"{path}: --sheet is for .xlsx workbooks; this is a text table")
        text, source, digest = read_source(path, "table")
        header, rows = _text_cells(text, source)
    cmap = parse_map(column_map, n_joints, header)
    advice = f': name the columns with --map "j1=…,…,j6=…,length=…"{sheets}'
    index = column_index(cmap.columns, header, source, advice)
    lines, values = column_numbers(rows, cmap.columns, index, source, empty=empty)
    q, length = values[:, :n_joints], values[:, n_joints]
    return CableTable(
        source=source,
        sha256=digest,
        columns=cmap,
        lines=lines,
        q_deg=q,
        length_mm=length,
        xyz_mm=values[:, n_joints + 1 :] if cmap.xyz else None,
        joint_resolution_deg=resolution(q),
        length_resolution_mm=resolution(length),
        xyz_resolution_mm=resolution(values[:, n_joints + 1 :]) if cmap.xyz else None,
    )


Cells = list[tuple[int, tuple[Any, ...]]]


def _text_cells(text: str, source: str) -> tuple[tuple[str, ...], Cells]:
    """Return the header and the data rows (line, cells) of a CSV/TSV text."""
    lines = text.removeprefix("\ufeff").splitlines()
    body = [(k + 1, s) for k, s in enumerate(lines) if s.strip() and not s.lstrip().startswith("#")]
    if not body:
        raise WirecalError(f"{source}: no header line: the table is empty")
    first = body[0][1]
    delimiter = "\t" if "\t" in first else ";" if ";" in first and "," not in first else ","
    try:
        parsed = [(n, next(csv.reader(io.StringIO(s), delimiter=delimiter))) for n, s in body]
    except csv.Error as exc:
        raise WirecalError(f"{source}: not a readable table: {exc}") from None
    header = tuple(c.strip() for c in parsed[0][1])
    rows = [(n, tuple(c.strip() for c in cells)) for n, cells in parsed[1:]]
    return header, rows


def _xlsx_cells(
    path: str | Path, sheet: str | None
) -> tuple[tuple[str, ...], Cells, str, str, str]:
    """Return a workbook sheet's header, data rows (row number, cells), source and sha256.

    And, for messages, which sheet was read and the others (empty for a single sheet).
    """
    try:
        import openpyxl  # an optional extra, imported only for a workbook
    except ImportError:
        raise WirecalError(
            f"{path}: reading .xlsx needs openpyxl: pip install 'wirecal[xlsx]' (or save the "
            "sheet as CSV)"
        ) from None
    raw, source, digest = _bytes_digest(path)
    check_workbook(raw, source)
    try:
        book = openpyxl.load_workbook(io.BytesIO(raw), read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many types for a damaged file
        raise WirecalError(f"{source}: not a readable .xlsx workbook: {exc}") from None
    names = book.sheetnames
    if sheet is not None and sheet not in names:
        raise WirecalError(f"{source}: no sheet {sheet!r}; the sheets are {', '.join(names)}")
    ws = book[sheet or names[0]]
    rows = [
        (k + 1, tuple("" if c is None else c for c in r))
        for k, r in enumerate(ws.iter_rows(values_only=True))
        if any(c not in (None, "") for c in r)
    ]
    book.close()
    if not rows:
        raise WirecalError(f"{source}: sheet {ws.title!r} is empty")
    header = tuple(str(c).strip() for c in rows[0][1])
    others = [n for n in names if n != ws.title]
    sheets = (
        f" of sheet {ws.title!r}, or read another sheet with --sheet ("
        + ", ".join(repr(n) for n in others)
        + ")"
        if others
        else ""
    )
    return header, rows[1:], source, digest, sheets


def _bytes_digest(path: str | Path) -> tuple[bytes, str, str]:
    raw, source = read_input(path, "table")
    return raw, source, hashlib.sha256(raw).hexdigest()


def check_workbook(raw: bytes, source: str) -> None:
    """Refuse a workbook that unpacks beyond the bounds, before openpyxl reads it.

    An ``.xlsx`` is a zip of XML parts: at most :data:`MAX_XLSX_PARTS` of them, together at
    most :data:`MAX_XLSX_UNPACKED_BYTES` when unpacked — counted while unpacking, not taken
    from the sizes the archive declares (a zip bomb declares small ones).
    """
    try:
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            parts = archive.infolist()
            if len(parts) > MAX_XLSX_PARTS:
                raise WirecalError(
                    f"{source}: {len(parts)} parts in the workbook, more than "
                    f"{MAX_XLSX_PARTS}: not a table's workbook; save the sheet as CSV"
                )
            total = 0
            for part in parts:
                with archive.open(part) as stream:
                    while chunk := stream.read(2**20):
                        total += len(chunk)
                        if total > MAX_XLSX_UNPACKED_BYTES:
                            raise WirecalError(
                                f"{source}: the workbook unpacks to more than "
                                f"{MAX_XLSX_UNPACKED_BYTES // 2**20} MiB (at part "
                                f"{part.filename!r}): not a table's workbook (a zip bomb?); "
                                "save the sheet as CSV"
                            )
    except (zipfile.BadZipFile, zlib.error, EOFError, NotImplementedError) as exc:
        raise WirecalError(f"{source}: not a readable .xlsx workbook: {exc}") from None


def column_index(
    names: tuple[str, ...], header: tuple[str, ...], source: str, advice: str = ""
) -> list[int]:
    """Return the position of each named column; raise naming the absent or repeated ones.

    ``advice``: what to do, appended to the absent ones' message (how to name the columns).
    A column the header names twice is refused: which of them holds the values is not known
    (a map names columns, so it cannot tell them apart either).
    """
    absent = [c for c in names if c not in header]
    if absent:
        raise WirecalError(
            f"{source}: no column {', '.join(repr(c) for c in absent)}; the header has "
            f"{', '.join(repr(h) for h in header)}{advice}"
        )
    for c in names:
        where = [str(k + 1) for k, h in enumerate(header) if h == c]
        if len(where) > 1:
            raise WirecalError(
                f"{source}: the header names {c!r} {len(where)} times (columns "
                f"{', '.join(where)}): which holds the values is not known; give the "
                "others other names in the header"
            )
    return [header.index(c) for c in names]


def column_numbers(
    rows: Cells,
    names: tuple[str, ...],
    index: list[int],
    source: str,
    *,
    empty: str = "",
    decimal_comma: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Return the rows' lines (N,) and their named cells as numbers (N, k).

    Raise naming every cell (``file:line``, at most ten) that is not a finite number, and
    on a table without rows. ``empty``: what to add to the message of an empty cell (a
    workbook's formulas); ``decimal_comma``: text cells write 0,5 for 0.5.
    """
    problems: list[str] = []
    lines, values = [], []
    for line, cells in rows:
        row = []
        for col, k in zip(names, index, strict=True):
            cell = cells[k] if k < len(cells) else ""
            value = _number(cell.replace(",", ".") if decimal_comma else cell)
            if value is None:
                hint = empty if cell == "" else ""
                problems.append(f"{source}:{line}: column {col!r} is {cell!r}, not a number{hint}")
            row.append(value)
        lines.append(line)
        values.append(row)
    if problems:
        shown = problems[:10] + ([f"… and {len(problems) - 10} more"] if len(problems) > 10 else [])
        raise WirecalError(shown)
    if not values:
        raise WirecalError(f"{source}: the table has a header but no data rows")
    return np.array(lines, dtype=int), np.array(values, dtype=float)


def _number(cell: Any) -> float | None:
    """Return a finite number from a cell (a float, or text like '12.5'), else None."""
    if isinstance(cell, bool):
        return None
    if isinstance(cell, int | float):
        value = float(cell)
    else:
        try:
            value = float(str(cell))
        except ValueError:
            return None
    return value if math.isfinite(value) else None


def resolution(values: np.ndarray) -> float:
    """Return the step of the values: 10^−d, d the decimals most values need (docstring)."""
    v = np.abs(np.asarray(values, dtype=float)).ravel()
    need = np.full(v.shape, MAX_DECIMALS)
    for d in range(MAX_DECIMALS, -1, -1):
        exact = np.abs(v - np.round(v, d)) <= 1e-9 * np.maximum(1.0, v)
        need[exact] = d
    return float(10.0 ** -np.quantile(need, RESOLUTION_QUANTILE, method="higher"))
