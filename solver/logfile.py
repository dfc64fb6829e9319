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
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import WirecalError
from .plan import Plan
from .robot import Robot

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
    comments: tuple[str, ...]
    readings: tuple[Reading, ...]
    sha256: str
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class Tolerances:
    """What the reader accepts; each is a CLI option of ``wirecal solve``."""

    joint_deg: float = 0.05   # logged joints vs the plan
    spread_mm: float = 0.1    # max − min of a point's samples: the robot was still moving
    zero_mm: float = 0.1      # a step's zero reading vs the first: the wire slipped


def format_row(kind: str, step: int, index: int, joints_deg, counts: float, samples: int,
               spread: float) -> str:
    """One data line, numbers written without loss at the log's resolution."""
    joints = ",".join(f"{x:.4f}" for x in joints_deg)
    return f"{kind},{step},{index},{joints},{counts:.4f},{samples:d},{spread:g}"


def format_header(robot: str, fingerprint: str, mm_per_count: float,
                  comments: tuple[str, ...] = ()) -> str:
    lines = [f"{MAGIC} {VERSION}", f"# robot: {robot}", f"# plan: {fingerprint}",
             f"# mm_per_count: {mm_per_count!r}"]
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
        raise WirecalError(f"{path}: not UTF-8 text (byte {exc.start}); is this a wirecal "
                           "log?") from None
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
        raise WirecalError(f"{source}:1: not a wirecal log: the first line must be "
                           f"'{MAGIC} {VERSION}'")
    version = first[len(MAGIC):].strip()
    if version != str(VERSION):
        raise WirecalError(f"{source}:1: log version {version!r}; this wirecal reads version "
                           f"{VERSION}")

    header: dict[str, tuple[str, int]] = {}
    comments: list[str] = []
    n = 1
    while n < len(lines) and lines[n].startswith("#"):
        body = lines[n][1:].strip()
        key, sep, value = body.partition(":")
        if sep and key.strip() in ("robot", "plan", "mm_per_count"):
            if key.strip() in header:
                bad(n + 1, f"'{key.strip()}' is given twice")
            header[key.strip()] = (value.strip(), n + 1)
        else:
            comments.append(body)
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
        bad(n, "the column line is missing: "
            f"expected '{','.join(COLUMNS)}'")
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
                notes.append(f"{source}:{line_no}: incomplete last line ignored (the run "
                             "stopped while writing it)")
                continue
            bad(line_no, f"has {len(cells)} fields; expected {len(COLUMNS)}")
            continue
        reading = _parse_row(cells, line_no, bad)
        if reading is not None:
            readings.append(reading)
    if problems:
        raise WirecalError(problems)
    return Log(source=source, robot=header["robot"][0], plan=header["plan"][0],
               mm_per_count=mpc, comments=tuple(comments), readings=tuple(readings),
               sha256=sha256, notes=tuple(notes))


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
    for name, cell in zip((*JOINT_COLUMNS, "counts", "spread"), [*cells[3:10], cells[11]],
                          strict=True):
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
    return Reading(kind, ints["step"], ints["index"],
                   np.array([floats[j] for j in JOINT_COLUMNS]), floats["counts"],
                   ints["samples"], floats["spread"], line)


@dataclass(frozen=True)
class Measurements:
    """A log checked against its plan: one wire length per plan point (NaN where missing)."""

    source: str
    sha256: str
    mm_per_count: float
    theta0_deg: np.ndarray          # joints of the reference zero reading
    step: np.ndarray                # (N,) 1-based, plan order
    index: np.ndarray               # (N,)
    joints_deg: np.ndarray          # (N, n) as logged (plan values where missing)
    distance_mm: np.ndarray         # (N,) NaN where missing
    zero_drift_mm: dict[int, float]  # per step with a zero reading
    notes: tuple[str, ...] = ()
    missing: tuple[tuple[int, int], ...] = field(default=())

    @property
    def present(self) -> np.ndarray:
        return ~np.isnan(self.distance_mm)

    def missing_text(self) -> str:
        """Missing points in words, e.g. 'step 5 points 3–6; steps 6–10 (all points)'."""
        return describe_missing(self.missing, self.step, self.index)


def describe_missing(missing, step: np.ndarray, index: np.ndarray) -> str:
    if not missing:
        return "none"
    parts: list[str] = []
    by_step: dict[int, list[int]] = {}
    for s, i in missing:
        by_step.setdefault(s, []).append(i)
    whole = [s for s, idx in by_step.items() if len(idx) == int(np.sum(step == s))]
    for s, idx in sorted(by_step.items()):
        if s in whole:
            continue
        parts.append(f"step {s} point{'s' if len(idx) > 1 else ''} {_ranges(idx)}")
    if whole:
        parts.append(f"step{'s' if len(whole) > 1 else ''} {_ranges(whole)} (all points)")
    return "; ".join(parts)


def _ranges(values: list[int]) -> str:
    values = sorted(values)
    out, start = [], values[0]
    for a, b in zip(values, [*values[1:], None], strict=True):
        if b != a + 1:
            out.append(str(start) if start == a else f"{start}–{a}")
            start = b
    return ", ".join(out)


def check_log(log: Log, plan: Plan, robot: Robot, tol: Tolerances = Tolerances(),
              force: bool = False) -> Measurements:
    """Validate a log against the plan and robot; wire lengths for every plan point.

    Raises :class:`WirecalError` listing every ``file:line: problem``. A fingerprint or
    robot-name mismatch is refused unless ``force``. Missing points are not an error here:
    they are listed in the result (a run that stopped is still readable).
    """
    src = log.source
    problems: list[str] = []
    if log.plan != plan.fingerprint() and not force:
        problems.append(f"{src}: plan fingerprint {log.plan[:16]}… differs from {plan.source} "
                        f"({plan.fingerprint()[:16]}…): the log was taken with another plan; "
                        "use that plan, or --force if you are sure")
    if log.robot != robot.name and not force:
        problems.append(f"{src}: robot {log.robot!r} differs from {robot.source} "
                        f"({robot.name!r}); use the matching robot file, or --force")
    if not math.isclose(abs(log.mm_per_count), abs(robot.encoder.mm_per_count), rel_tol=1e-6) \
            and not force:
        problems.append(f"{src}: mm_per_count {log.mm_per_count!r} differs from the robot "
                        f"file's encoder.mm_per_count {robot.encoder.mm_per_count!r}")
    if problems:  # a log of another plan or robot: row-by-row complaints would be noise
        raise WirecalError(problems)

    q_plan, step_no, index_no = plan.all_points()
    position = {(int(s), int(i)): k for k, (s, i) in enumerate(zip(step_no, index_no,
                                                                   strict=True))}
    counts = np.full(len(q_plan), np.nan)
    joints = q_plan.copy()
    zeros: dict[int, Reading] = {}
    seen: dict[tuple[str, int, int], int] = {}
    mpc = log.mm_per_count
    modulus = 2.0 ** robot.encoder.counter_bits
    spread_counts = tol.spread_mm / abs(mpc)
    n_steps = len(plan.steps)

    def bad(r: Reading, message: str) -> None:
        problems.append(f"{src}:{r.line}: {message}")

    for r in log.readings:
        key = (r.kind, r.step, r.index)
        if key in seen:
            bad(r, f"duplicate {r.kind} reading of step {r.step}"
                   + (f" point {r.index}" if r.kind == "point" else "")
                   + f" (first on line {seen[key]}); keep one run per log")
            continue
        seen[key] = r.line
        if not 1 <= r.step <= n_steps:
            bad(r, f"step {r.step} is not in the plan (it has {n_steps} steps)")
            continue
        if r.kind == "zero":
            if r.index != 0:
                bad(r, f"a zero reading has index 0, not {r.index}")
                continue
            expected = plan.theta0_deg
        else:
            k = position.get((r.step, r.index))
            if k is None:
                bad(r, f"step {r.step} has {len(plan.steps[r.step - 1].points_deg)} points; "
                       f"point {r.index} is not in the plan")
                continue
            expected = q_plan[k]
        if r.joints_deg.shape != expected.shape:
            bad(r, "joint count differs from the robot's")
            continue
        off = np.abs(r.joints_deg - expected)
        if np.any(off > tol.joint_deg):
            j = int(np.argmax(off))
            bad(r, f"joint {j + 1} is {r.joints_deg[j]:.4f} deg; the plan says "
                   f"{expected[j]:g} (tolerance {tol.joint_deg:g}): the robot was not where the "
                   "plan puts it")
            continue
        if r.spread > spread_counts:
            bad(r, f"spread of {r.samples} samples is {r.spread:g} counts "
                   f"({r.spread * abs(mpc):.3f} mm > {tol.spread_mm:g} mm): the robot was "
                   f"still moving; lengthen the settle time and repeat step {r.step}")
            continue
        if r.kind == "zero":
            zeros[r.step] = r
        else:
            counts[k] = r.counts
            joints[k] = r.joints_deg

    first_zero = zeros[min(zeros)] if zeros else None
    if first_zero is None and log.readings:
        problems.append(f"{src}: no zero reading: the log must start with the zero reading "
                        "at θ0")
    drift: dict[int, float] = {}
    if first_zero is not None:
        first = first_zero.counts

        def wrapped(c, ref):
            return (np.asarray(c) - ref + modulus / 2) % modulus - modulus / 2

        for s, r in sorted(zeros.items()):
            drift[s] = float(wrapped(r.counts, first) * mpc)
            if abs(drift[s]) > tol.zero_mm:
                prev = max(s - 1, 1)
                bad(r, f"zero reading at step {s} is {drift[s]:+.3f} mm from the first "
                       f"(tolerance {tol.zero_mm:g} mm): the wire slipped or the encoder "
                       f"moved after the zero of step {prev}; remount at θ0 and repeat from "
                       f"step {prev}")
        for s in sorted({int(x) for x in step_no[~np.isnan(counts)]}):
            if s not in zeros:
                problems.append(f"{src}: step {s} has points but no zero reading; the zero "
                                "check at θ0 guards against a slipped wire")
        # The reference is the mean of all zero readings: every length is measured from
        # it, so its error is common to all points; averaging the steps' zeros shrinks it.
        ref = first + np.mean([wrapped(r.counts, first) for r in zeros.values()])
        distance = wrapped(counts, ref) * mpc
        for k in np.flatnonzero(~np.isnan(distance)):
            line = seen[("point", int(step_no[k]), int(index_no[k]))]
            if distance[k] > robot.encoder.range_mm:
                problems.append(f"{src}:{line}: wire length {distance[k]:.1f} mm is beyond "
                                f"the encoder's range {robot.encoder.range_mm:g} mm")
            elif distance[k] < -tol.zero_mm:
                problems.append(f"{src}:{line}: wire length {distance[k]:.3f} mm is "
                                "negative: is the sign of mm_per_count right?")
    else:
        distance = counts
    if problems:
        raise WirecalError(problems)
    missing = tuple((int(step_no[k]), int(index_no[k])) for k in np.flatnonzero(
        np.isnan(distance)))
    theta0 = first_zero.joints_deg if first_zero is not None else plan.theta0_deg
    return Measurements(source=src, sha256=log.sha256, mm_per_count=mpc, theta0_deg=theta0,
                        step=step_no, index=index_no, joints_deg=joints, distance_mm=distance,
                        zero_drift_mm=drift, notes=log.notes, missing=missing)


def load_measurements(path: str | Path, plan: Plan, robot: Robot,
                      tol: Tolerances = Tolerances(), force: bool = False) -> Measurements:
    """Read a log file and check it against the plan (:func:`read_log` + :func:`check_log`)."""
    return check_log(read_log(path), plan, robot, tol, force)
