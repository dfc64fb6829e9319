"""Measurement logs: the CSV the controller program writes, and its strict reader.

Format (UTF-8)::

    # wirecal-log 1
    # robot: Adept Viper s650
    # plan: <sha256 fingerprint of the plan>
    # mm_per_count: 0.025488          (negative when counts fall as the wire extends)
    # <free comments>
    kind,step,index,j1,j2,j3,j4,j5,j6,counts,samples,spread
    zero,1,0,0.0000,-90.0000,...,8388000.5000,10,1
    point,1,1,...

``kind`` is ``zero`` (θ0 at the start of a step, index 0) or ``point``; step and index are
1-based plan positions; j1..j6 the joints the controller reports (deg); ``counts`` the
mean of ``samples`` raw counter readings, unwrapped relative to the first of them;
``spread`` their max − min (counts). A point's wire length is (counts − reference) ×
mm_per_count, the difference taken modulo the counter width; the reference is the mean of
the zero readings (each checked against the first: a drift means the wire slipped).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from wirecal.solver.errors import WirecalError

MAGIC = "# wirecal-log"
VERSION = 1
JOINT_COLUMNS = tuple(f"j{i}" for i in range(1, 7))
COLUMNS = ("kind", "step", "index", *JOINT_COLUMNS, "counts", "samples", "spread")


@dataclass(frozen=True)
class Reading:
    kind: str
    step: int
    index: int
    joints_deg: np.ndarray
    counts: float
    samples: int
    spread: float
    line: int


@dataclass(frozen=True)
class Log:
    """A log as written: header fields and readings, checked for format only."""

    source: str
    robot: str
    plan: str
    mm_per_count: float
    readings: tuple[Reading, ...]
    sha256: str
    notes: tuple[str, ...] = ()


def format_row(
    kind: str, step: int, index: int, joints_deg, counts: float, samples: int, spread: float
) -> str:
    """One data line, numbers written without loss at the log's resolution."""
    joints = ",".join(f"{x:.4f}" for x in joints_deg)
    return f"{kind},{step},{index},{joints},{counts:.4f},{samples:d},{spread:g}"


def format_header(
    robot: str, fingerprint: str, mm_per_count: float, comments: tuple[str, ...] = ()
) -> str:
    lines = [
        f"{MAGIC} {VERSION}",
        f"# robot: {robot}",
        f"# plan: {fingerprint}",
        f"# mm_per_count: {mm_per_count!r}",
    ]
    lines += [f"# {c}" for c in comments]
    lines.append(",".join(COLUMNS))
    return "\n".join(lines) + "\n"


def read_log(path: str | Path) -> Log:
    """Parse a log; every format problem is reported as ``file:line: problem``."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise WirecalError(f"{path}: cannot read log: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise WirecalError(
            f"{path}: not UTF-8 text (byte {exc.start}); is this a wirecal log?"
        ) from None
    return parse_log(text, str(path), hashlib.sha256(raw).hexdigest())


def parse_log(text: str, source: str, sha256: str = "") -> Log:
    problems: list[str] = []
    notes: list[str] = []
    lines = text.split("\n")
    ends_with_newline = text.endswith("\n")
    if ends_with_newline:
        lines = lines[:-1]

    def bad(line: int, message: str) -> None:
        problems.append(f"{source}:{line}: {message}")

    first = lines[0].strip() if lines else ""
    if not first.startswith(MAGIC):
        raise WirecalError(
            f"{source}:1: not a wirecal log: the first line must be '{MAGIC} {VERSION}'"
        )
    version = first[len(MAGIC) :].strip()
    if version != str(VERSION):
        raise WirecalError(
            f"{source}:1: log version {version!r}; this wirecal reads version {VERSION}"
        )

    header: dict[str, tuple[str, int]] = {}
    n = 1
    while n < len(lines) and lines[n].startswith("#"):
        body = lines[n][1:].strip()
        key, sep, value = body.partition(":")
        if sep and key.strip() in ("robot", "plan", "mm_per_count"):
            if key.strip() in header:
                bad(n + 1, f"'{key.strip()}' is given twice")
            header[key.strip()] = (value.strip(), n + 1)
        n += 1
    for key in ("robot", "plan", "mm_per_count"):
        if key not in header:
            bad(n, f"header '# {key}: …' is missing")
    mpc = math.nan
    if "mm_per_count" in header:
        value, line = header["mm_per_count"]
        try:
            mpc = float(value)
            if not math.isfinite(mpc) or mpc == 0:
                raise ValueError
        except ValueError:
            bad(line, f"mm_per_count {value!r} is not a non-zero number")

    if n >= len(lines):
        bad(n, f"the column line is missing: expected '{','.join(COLUMNS)}'")
        raise WirecalError(problems)
    if lines[n].strip() != ",".join(COLUMNS):
        bad(n + 1, f"columns are {lines[n].strip()!r}; expected '{','.join(COLUMNS)}'")
        raise WirecalError(problems)

    readings: list[Reading] = []
    for k in range(n + 1, len(lines)):
        line_no = k + 1
        line = lines[k].strip()
        if not line or line.startswith("#"):
            continue
        cells = line.split(",")
        last = k == len(lines) - 1
        if len(cells) != len(COLUMNS):
            if last and not ends_with_newline and len(cells) < len(COLUMNS):
                notes.append(
                    f"{source}:{line_no}: incomplete last line ignored (the run "
                    "stopped while writing it)"
                )
                continue
            bad(line_no, f"has {len(cells)} fields; expected {len(COLUMNS)}")
            continue
        reading = _parse_row(cells, line_no, bad)
        if reading is not None:
            readings.append(reading)
    if problems:
        raise WirecalError(problems)
    return Log(
        source=source,
        robot=header["robot"][0],
        plan=header["plan"][0],
        mm_per_count=mpc,
        readings=tuple(readings),
        sha256=sha256,
        notes=tuple(notes),
    )


def _parse_row(cells: list[str], line: int, bad) -> Reading | None:
    kind = cells[0].strip()
    ok = True
    if kind not in ("zero", "point"):
        bad(line, f"kind {kind!r} is neither 'zero' nor 'point'")
        ok = False
    ints = {}
    for name, cell in (("step", cells[1]), ("index", cells[2]), ("samples", cells[10])):
        try:
            ints[name] = int(cell)
        except ValueError:
            bad(line, f"{name} {cell.strip()!r} is not a whole number")
            ok = False
    floats = {}
    for name, cell in zip(
        (*JOINT_COLUMNS, "counts", "spread"), [*cells[3:10], cells[11]], strict=True
    ):
        try:
            floats[name] = float(cell)
            if not math.isfinite(floats[name]):
                raise ValueError
        except ValueError:
            bad(line, f"{name} {cell.strip()!r} is not a number")
            ok = False
    if not ok:
        return None
    if ints["samples"] < 1:
        bad(line, f"samples {ints['samples']} must be at least 1")
        return None
    if floats["spread"] < 0:
        bad(line, f"spread {floats['spread']:g} cannot be negative")
        return None
    return Reading(
        kind,
        ints["step"],
        ints["index"],
        np.array([floats[j] for j in JOINT_COLUMNS]),
        floats["counts"],
        ints["samples"],
        floats["spread"],
        line,
    )
