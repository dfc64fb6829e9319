"""The paper's two validation procedures (§3.6): the design of their runs, their logs, and
their analyses.

* Configuration change (§3.6.1): poses across the workspace, each reached in the four
  configurations above/below × noflip/flip (the shoulder kept); the draw-wire encoder sits
  at a fixed point outside the workspace. A well-calibrated robot puts the tool point at the
  same place in all four, so the wire length is the same; the metric is, per pose, the
  largest discrepancy among the four lengths.
* Plane fit (§3.6.2): a touch probe approaches a grid on a flat plate along −z until it
  trips; the controller's coordinates at contact are fitted by z = a·x + b·y + c (paper
  eq. 21–25) and the residuals Δ_i = a·x_i + b·y_i + c − z_i are the metric.

Setup file (TOML)::

    [configuration]
    encoder_mm = [900, 0, -100]   # encoder exit point, base frame, outside the workspace
    poses = 50
    seed = 1
    [plate]
    origin_mm = [220, -125, -200] # corner of the probed area on the plate's top face
    yaw_deg = 0                   # direction of the grid's first axis about base z
    size_mm = [400, 250]
    grid = [19, 11]
    approach_mm = 20              # start this far above the plate (search down to 2×)
    probe_mm = [0, 0, 100]        # probe tip in the flange frame
    signal = 1001                 # the probe's digital input
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import ik, pose
from .errors import Problems, WirecalError
from .fileio import read_toml
from .kinematics import Model, perturbed, tool_position
from .robot import Robot

CONFIGS = (("above", "noflip"), ("above", "flip"), ("below", "noflip"), ("below", "flip"))
"""The four configurations of the configuration-change test, numbered 1–4 in its log."""


@dataclass(frozen=True)
class Setup:
    encoder_mm: np.ndarray
    poses: int
    seed: int
    plate_origin_mm: np.ndarray
    plate_yaw_deg: float
    plate_size_mm: tuple[float, float]
    grid: tuple[int, int]
    approach_mm: float
    probe_mm: np.ndarray
    signal: int
    source: str = "<setup>"

    def fingerprint(self) -> str:
        canon = {k: (np.round(np.asarray(v, dtype=float), 6).tolist()
                     if isinstance(v, np.ndarray | tuple | float | int) else v)
                 for k, v in self.__dict__.items() if k != "source"}
        return hashlib.sha256(json.dumps(canon, sort_keys=True).encode()).hexdigest()


def load_setup(path: str | Path) -> Setup:
    data = read_toml(path, "validation setup")
    pr = Problems(str(path))
    cfg, plate = data.get("configuration", {}), data.get("plate", {})
    for name, table in (("configuration", cfg), ("plate", plate)):
        if not isinstance(table, dict) or not table:
            pr.add(name, f"the table [{name}] is missing")
    pr.raise_if_any()

    def vec(table, key, n, where, default=None):
        v = table.get(key, default)
        if (not isinstance(v, list) or len(v) != n
                or not all(isinstance(x, int | float) and math.isfinite(x) for x in v)):
            pr.add(f"{where}.{key}", f"must be {n} finite numbers")
            return np.zeros(n)
        return np.asarray(v, dtype=float)

    def num(table, key, where, default, kind=float, lo=None):
        v = table.get(key, default)
        if not isinstance(v, int | float) or isinstance(v, bool) or (
                kind is int and not isinstance(v, int)) or (lo is not None and v < lo):
            pr.add(f"{where}.{key}", f"is {v!r}; give a {'whole ' if kind is int else ''}"
                   f"number{'' if lo is None else f' ≥ {lo}'}")
            return kind(default)
        return kind(v)

    setup = Setup(
        encoder_mm=vec(cfg, "encoder_mm", 3, "configuration"),
        poses=num(cfg, "poses", "configuration", 50, int, 1),
        seed=num(cfg, "seed", "configuration", 1, int, 0),
        plate_origin_mm=vec(plate, "origin_mm", 3, "plate"),
        plate_yaw_deg=num(plate, "yaw_deg", "plate", 0.0),
        plate_size_mm=tuple(vec(plate, "size_mm", 2, "plate", [400, 250])),
        grid=tuple(int(x) for x in vec(plate, "grid", 2, "plate", [19, 11])),
        approach_mm=num(plate, "approach_mm", "plate", 5.0, float, 0.5),
        probe_mm=vec(plate, "probe_mm", 3, "plate", [0, 0, 100]),
        signal=num(plate, "signal", "plate", 1001, int, 1),
        source=str(path),
    )
    if min(setup.grid) < 2:
        pr.add("plate.grid", "needs at least 2 × 2 points to fit a plane")
    pr.raise_if_any()
    return setup


def _pose_reachable(model: Model, robot: Robot, R, p, margin_deg: float):
    lo, hi = robot.joint_min_deg + margin_deg, robot.joint_max_deg - margin_deg
    found = {}
    for s in ik.solve(model, R, p, lo, hi):
        if s.within_limits and s.config[0] == "righty":
            found[s.config[1:]] = s.q
    return [found.get(c) for c in CONFIGS]


def config_poses(robot: Robot, setup: Setup, margin_deg: float = 1.0) -> np.ndarray:
    """``setup.poses`` transformations (x, y, z, yaw, pitch, roll) spread over the
    workspace, each reachable righty in all four configurations within the limits with a
    margin, with wire lengths within the encoder's range in every one."""
    model = perturbed(robot)
    rng = np.random.default_rng(setup.seed)
    reach = np.abs(robot.dh[:, 1]).sum() + np.abs(robot.dh[:, 3]).sum()
    out = []
    for _ in range(400 * setup.poses):
        r = rng.uniform(0.35, 0.85) * reach
        az, el = rng.uniform(-np.pi / 2, np.pi / 2), rng.uniform(-0.6, 0.9)
        x, y, z = r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)
        yaw, pitch, roll = rng.uniform(-90, 90), rng.uniform(100, 170), rng.uniform(-90, 90)
        t = tuple(float(v) for v in np.round([x, y, z, yaw, pitch, roll], 1))
        qs = _pose_reachable(model, robot, *pose.matrix(*t), margin_deg)
        if any(q is None for q in qs):
            continue
        d = np.linalg.norm(tool_position(model, np.array(qs)) - setup.encoder_mm, axis=1)
        if np.all((d > 50) & (d < robot.encoder.range_mm - 50)):
            out.append(t)
            if len(out) == setup.poses:
                return np.array(out)
    raise WirecalError(f"{setup.source}: configuration.poses: found only {len(out)} of "
                       f"{setup.poses} poses reachable in all four configurations with the "
                       "wire within range; move encoder_mm or ask for fewer poses")


def plate_grid(robot: Robot, setup: Setup, margin_deg: float = 1.0):
    """The grid points on the plate and the flange targets above them (tool pointing down),
    each checked reachable (righty, above, noflip) at the approach height and 5 mm below
    the plate's nominal top."""
    nx, ny = setup.grid
    u = np.linspace(0, setup.plate_size_mm[0], nx)
    v = np.linspace(0, setup.plate_size_mm[1], ny)
    yaw = np.radians(setup.plate_yaw_deg)
    ex, ey = np.array([np.cos(yaw), np.sin(yaw), 0]), np.array([-np.sin(yaw), np.cos(yaw), 0])
    points = np.array([setup.plate_origin_mm + a * ex + b * ey for b in v for a in u])
    index = [(i + 1, j + 1) for j in range(ny) for i in range(nx)]
    model = perturbed(robot)
    targets, problems = [], []
    lo, hi = robot.joint_min_deg + margin_deg, robot.joint_max_deg - margin_deg
    for (i, j), p in zip(index, points, strict=True):
        flange = p + np.array([0, 0, setup.probe_mm[2] + setup.approach_mm])
        t = (*flange, setup.plate_yaw_deg, 180.0, 0.0)
        for depth in (0.0, setup.approach_mm + 5.0):
            R, o = pose.matrix(*t)
            o = o - np.array([0, 0, depth])
            ok = any(s.within_limits and s.config == ("righty", "above", "noflip")
                     for s in ik.solve(model, R, o, lo, hi))
            if not ok:
                problems.append(f"{setup.source}: plate: grid point ({i}, {j}) at "
                                f"{np.round(p, 1).tolist()} is out of reach (righty, above, "
                                "noflip, tool down); move origin_mm or shrink the plate")
                break
        targets.append(t)
    if problems:
        raise WirecalError(problems[:5] + ([f"… and {len(problems) - 5} more"]
                                           if len(problems) > 5 else []))
    return index, points, np.array(targets)


# ---------- logs ----------

@dataclass(frozen=True)
class ValidationLog:
    kind: str            # "configuration" or "plane"
    source: str
    robot: str
    setup: str
    mm_per_count: float
    rows: np.ndarray     # numbers, one row per reading, columns as COLUMNS[kind]


COLUMNS = {
    "configuration": ("pose", "config", "j1", "j2", "j3", "j4", "j5", "j6", "counts",
                      "samples", "spread"),
    "plane": ("row", "col", "x", "y", "z"),
}


def read_validation_log(path: str | Path, kind: str) -> ValidationLog:
    """Read a validation log; every problem as ``file:line: problem``."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise WirecalError(f"{path}: cannot read the validation log: {exc}") from None
    if not lines or lines[0].strip() != "# wirecal-validation 1":
        raise WirecalError(f"{path}:1: not a wirecal validation log: the first line must "
                           "be '# wirecal-validation 1'")
    header, n = {}, 1
    while n < len(lines) and lines[n].startswith("#"):
        key, _, value = lines[n][1:].partition(":")
        header[key.strip()] = value.strip()
        n += 1
    problems = []
    if header.get("kind") != kind:
        raise WirecalError(f"{path}:2: a {header.get('kind')!r} log where a {kind!r} log is "
                           "needed")
    for key in ("robot", "setup") + (("mm_per_count",) if kind == "configuration" else ()):
        if key not in header:
            problems.append(f"{path}:{n}: header '# {key}: …' is missing")
    columns = ",".join(COLUMNS[kind])
    if n >= len(lines) or lines[n].strip() != columns:
        problems.append(f"{path}:{n + 1}: the column line must be '{columns}'")
        raise WirecalError(problems)
    rows, seen = [], {}
    for k in range(n + 1, len(lines)):
        text = lines[k].strip()
        if not text or text.startswith("#"):
            continue
        cells = text.split(",")
        if len(cells) != len(COLUMNS[kind]):
            problems.append(f"{path}:{k + 1}: has {len(cells)} fields; expected "
                            f"{len(COLUMNS[kind])}")
            continue
        try:
            row = [float(c) for c in cells]
        except ValueError:
            problems.append(f"{path}:{k + 1}: a field is not a number: {text}")
            continue
        if not all(math.isfinite(x) for x in row):
            problems.append(f"{path}:{k + 1}: a field is not finite")
            continue
        key = (row[0], row[1])
        if key in seen:
            problems.append(f"{path}:{k + 1}: duplicate reading of {COLUMNS[kind][0]} "
                            f"{row[0]:g}, {COLUMNS[kind][1]} {row[1]:g} (first on line "
                            f"{seen[key]})")
            continue
        if kind == "configuration" and row[1] not in (1, 2, 3, 4):
            problems.append(f"{path}:{k + 1}: config {row[1]:g} is not 1–4")
            continue
        seen[key] = k + 1
        rows.append(row)
    mpc = header.get("mm_per_count", "nan")
    try:
        mpc = float(mpc)
    except ValueError:
        problems.append(f"{path}: mm_per_count {mpc!r} is not a number")
    if problems:
        raise WirecalError(_first(problems))
    if not rows:
        raise WirecalError(f"{path}: no readings")
    return ValidationLog(kind, str(path), header["robot"], header["setup"], float(mpc),
                         np.array(rows))


def _first(problems: list[str], n: int = 12) -> list[str]:
    """The first problems and a count of the rest: a wrong file should not bury its cause."""
    if len(problems) <= n:
        return problems
    return [*problems[:n], f"… and {len(problems) - n} more problems of the same kinds"]


@dataclass(frozen=True)
class Stats:
    values: np.ndarray
    mean: float
    std: float
    max: float

    @classmethod
    def of(cls, values) -> Stats:
        v = np.asarray(values, dtype=float)
        return cls(v, float(v.mean()), float(v.std(ddof=1)) if v.size > 1 else 0.0,
                   float(v.max()))


def config_discrepancy(log: ValidationLog, bits: int = 24) -> Stats:
    """Per pose, the largest difference among the wire lengths of its four configurations
    (mm); the counts are compared modulo the counter width."""
    rows = log.rows
    out = []
    half = 2.0 ** (bits - 1)
    incomplete = []
    for number in np.unique(rows[:, 0]):
        r = rows[rows[:, 0] == number]
        if len(r) != 4:
            incomplete.append(int(number))
            continue
        c = r[:, 8]
        rel = (c - c[0] + half) % (2 * half) - half
        out.append(float((rel.max() - rel.min()) * abs(log.mm_per_count)))
    if incomplete:
        raise WirecalError(f"{log.source}: poses {incomplete[:10]} lack one of the four "
                           "configurations; finish the run")
    return Stats.of(out)


def plane_residuals(log: ValidationLog) -> tuple[Stats, np.ndarray]:
    """|Δ_i| of the least-squares plane z = a·x + b·y + c through the probed points, and
    (a, b, c) (paper eq. 21–25)."""
    x, y, z = log.rows[:, 2], log.rows[:, 3], log.rows[:, 4]
    U = np.column_stack([x, y, np.ones_like(x)])
    coef, *_ = np.linalg.lstsq(U, z, rcond=None)
    return Stats.of(np.abs(U @ coef - z)), coef
