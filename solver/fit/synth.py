"""Simulated cable-length tables with known truth, for the tests and the bench of ``fit``.

What a data set taken without wirecal looks like: random configurations within the joint
limits, the joints logged rounded to a pendant's 0.1°, an absolute length to an anchor
somewhere in the cell (rounded to the sensor's resolution, with reading noise), sessions
whose sensor re-mounts shift the offset, a few snagged rows (the wire caught: longer) and
mistyped rows (a joint or a length off by a digit), and the controller's nominal x, y, z of
its TCP computed from the unrounded joints.

The truth perturbs the robot file's ``parameters`` less θ_n and d_n (which the attachment,
fitted, absorbs), each uniform within ±:data:`ERROR_SIZE` deg or mm.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver.fit.cable_data import AXES, CableTable, ColumnMap
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.robot import Robot
from wirecal.solver.verdict import READING_NOISE_MM
from wirecal.solver.zero_reading import joint_sigma_rad

ERROR_SIZE = 0.5
"""Largest true DH error (deg or mm)."""

CONTROLLER_TCP_MM = (0.0, 0.0, 100.0)
"""The controller's TCP in the flange frame, which its x, y, z refer to."""


@dataclass(frozen=True)
class Synthetic:
    """A simulated table and the truth it was made from (deg, mm)."""

    table: CableTable
    errors: dict[str, float]  # true DH errors (deg, mm)
    attachment_mm: np.ndarray  # (3,) the true wire attachment in the flange frame
    anchor_mm: np.ndarray  # (3,) the true anchor in the base frame
    starts: tuple[int, ...]  # 0-based data rows where a session starts
    offsets_mm: np.ndarray  # (S,) each session's length offset
    snags: tuple[int, ...]  # rows whose wire was caught
    typos: tuple[int, ...]  # rows with a mistyped joint or length
    bad_mm: dict[int, float]  # each snagged or mistyped row's error of the length it implies
    q_true_deg: np.ndarray  # (N, n) the unrounded joints


def truth_names(robot: Robot) -> tuple[str, ...]:
    """Return the DH errors the simulation perturbs (module docstring)."""
    n = robot.n_joints
    return tuple(p for p in robot.parameters if p not in (f"th{n}", f"d{n}"))


def _configurations(robot: Robot, n: int, rng: np.random.Generator) -> np.ndarray:
    """Return configurations uniform within the middle 80 % of each joint's range (deg)."""
    lo, hi = robot.joint_min_deg, robot.joint_max_deg
    mid, half = (lo + hi) / 2, 0.4 * (hi - lo)
    return rng.uniform(mid - half, mid + half, (n, robot.n_joints))


def _anchor(points: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Return an anchor in the cell at least 150 mm from every tool point."""
    centre = points.mean(axis=0)
    for _ in range(1000):
        a = centre + rng.uniform([-900, -900, -400], [900, 900, 400])
        if np.min(np.linalg.norm(points - a, axis=1)) > 150:
            return a
    raise RuntimeError("no anchor clear of the points")  # pragma: no cover - 1000 tries


def _starts(n: int, sessions: int, rng: np.random.Generator) -> tuple[int, ...]:
    """Return session starts, each session at least a tenth of the rows."""
    if sessions <= 1:
        return (0,)
    while True:
        cuts = np.sort(rng.choice(np.arange(n // 10, n - n // 10), sessions - 1, replace=False))
        if np.all(np.diff(np.concatenate([[0], cuts, [n]])) >= n // 10):
            return (0, *map(int, cuts))


def synthetic_table(
    robot: Robot,
    n_rows: int,
    *,
    seed: int = 0,
    sessions: int = 3,
    snags: int = 3,
    typos: int = 2,
    joint_resolution_deg: float = 0.1,
    length_resolution_mm: float = 0.01,
    noise_mm: float = READING_NOISE_MM,
    compliance_urad_per_nm: np.ndarray | None = None,
    repeatability_mm: float | None = None,
) -> Synthetic:
    """Return a simulated table of ``n_rows`` rows and its truth (module docstring).

    ``compliance_urad_per_nm`` (n,): the true arm bends under gravity with these joint
    compliances and the robot file's masses (:func:`~wirecal.solver.kinematics.frames`);
    None: rigid. ``repeatability_mm``: the arm lands off the joints it logs, each by
    N(0, σ_q²) (:func:`~wirecal.solver.zero_reading.joint_sigma_rad`, the twin's rule);
    None: exactly on them.
    """
    rng = np.random.default_rng(seed)
    names = truth_names(robot)
    err = dict(zip(names, rng.uniform(-ERROR_SIZE, ERROR_SIZE, len(names)), strict=True))
    attach = robot.tool_point + rng.uniform(-30, 30, 3)
    true = _true_model(robot, err, attach, compliance_urad_per_nm)
    q_true = _configurations(robot, n_rows, rng)
    p = tool_position(true, _landed(np.radians(q_true), repeatability_mm, rng))
    anchor = _anchor(p, rng)
    starts = _starts(n_rows, sessions, rng)
    offsets = 100 + np.cumsum(rng.choice([-1, 1], len(starts)) * rng.uniform(3, 30, len(starts)))
    session = np.searchsorted(starts, np.arange(n_rows), side="right") - 1
    length = np.linalg.norm(p - anchor, axis=1) + offsets[session]
    length += rng.normal(0, noise_mm, n_rows)
    q_log = np.round(q_true / joint_resolution_deg) * joint_resolution_deg
    bad = _spoil(length, q_log, snags, typos, rng)
    length = np.round(length / length_resolution_mm) * length_resolution_mm
    implied = np.linalg.norm(tool_position(true, np.radians(q_log[bad])) - anchor, axis=1)
    bad_mm = {
        int(r): float(length[r] - implied[k] - offsets[session[r]]) for k, r in enumerate(bad)
    }
    tcp = tool_position(Model(robot.nominal.dh, np.array(CONTROLLER_TCP_MM)), np.radians(q_true))
    resolutions = (joint_resolution_deg, length_resolution_mm)
    return Synthetic(
        table=_table(q_log, length, np.round(tcp, 2), resolutions),
        errors=err,
        attachment_mm=attach,
        anchor_mm=anchor,
        starts=starts,
        offsets_mm=offsets,
        snags=tuple(sorted(int(b) for b in bad[:snags])),
        typos=tuple(sorted(int(b) for b in bad[snags:])),
        bad_mm=bad_mm,
        q_true_deg=q_true,
    )


def _true_model(
    robot: Robot, err: dict[str, float], attach: np.ndarray, compliance: np.ndarray | None
) -> Model:
    """Return the true arm: the DH errors, the attachment, and (given) its compliances."""
    true = robot.model(err)
    if compliance is None:
        return Model(true.dh, attach)
    c = np.asarray(compliance, dtype=float) * 1e-6  # rad/(N·m)
    return Model(true.dh, attach, masses=robot.masses, compliance=c)


def _landed(
    q_rad: np.ndarray, repeatability_mm: float | None, rng: np.random.Generator
) -> np.ndarray:
    """Return where an arm of this repeatability lands for the joints ``q_rad`` (rad)."""
    if repeatability_mm is None:
        return q_rad
    return q_rad + rng.normal(0, joint_sigma_rad(repeatability_mm), q_rad.shape)


def _spoil(
    length: np.ndarray, q_log: np.ndarray, snags: int, typos: int, rng: np.random.Generator
) -> np.ndarray:
    """Spoil rows in place: ``snags`` cable snags, then ``typos`` typing errors; return them.

    A snag lengthens the cable 5–40 mm; the typos alternate a joint one digit off (±10°)
    and a length with swapped digits (±9 or ±90 mm). The snags' rows come first.
    """
    bad = rng.choice(len(length), snags + typos, replace=False)
    length[bad[:snags]] += rng.uniform(5, 40, snags)
    for k, row in enumerate(bad[snags:]):
        if k % 2:
            length[row] += rng.choice([-1, 1]) * 9 * 10 ** rng.integers(0, 2)  # swapped digits
        else:
            j = rng.integers(0, q_log.shape[1])
            q_log[row, j] += rng.choice([-1, 1]) * 10.0  # one digit off
    return bad


def _table(
    q_log: np.ndarray, length: np.ndarray, xyz_mm: np.ndarray, resolutions: tuple[float, float]
) -> CableTable:
    """Return the synthetic rows as a table read from a file (lines from 2, resolutions given)."""
    n_rows, n_joints = q_log.shape
    return CableTable(
        source="<synthetic>",
        sha256="0" * 64,
        columns=ColumnMap(tuple(f"j{i + 1}" for i in range(n_joints)), "length", AXES),
        lines=np.arange(2, n_rows + 2),
        q_deg=q_log,
        length_mm=length,
        xyz_mm=xyz_mm,
        joint_resolution_deg=resolutions[0],
        length_resolution_mm=resolutions[1],
        xyz_resolution_mm=0.01,
    )


def take_rows(table: CableTable, rows: np.ndarray) -> CableTable:
    """Return a table of ``table``'s ``rows`` in that order (repeats allowed), lines from 2."""
    rows = np.asarray(rows)
    return replace(
        table,
        lines=np.arange(2, len(rows) + 2),
        q_deg=table.q_deg[rows],
        length_mm=table.length_mm[rows],
        xyz_mm=None if table.xyz_mm is None else table.xyz_mm[rows],
    )


def table_text(table: CableTable) -> str:
    """Return a table as CSV with a header line (the format ``wirecal fit`` reads)."""
    jd = max(0, -int(np.floor(np.log10(table.joint_resolution_deg) + 1e-9)))
    ld = max(0, -int(np.floor(np.log10(table.length_resolution_mm) + 1e-9)))
    cols = list(table.columns.columns)
    lines = [",".join(cols)]
    for k in range(len(table.length_mm)):
        cells = [f"{v:.{jd}f}" for v in table.q_deg[k]] + [f"{table.length_mm[k]:.{ld}f}"]
        if table.xyz_mm is not None:
            cells += [f"{v:.2f}" for v in table.xyz_mm[k]]
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"
