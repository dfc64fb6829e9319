"""``wirecal fit``: calibrate from a cable-length table taken without wirecal.

The model is :mod:`~wirecal.solver.fit.model` (the anchor anywhere, the attachment in the
flange frame, a length offset per session, optionally the cable's scale, and the robot's
identifiable DH errors). The steps:

1. **Start**: the nominal tool points and the lengths give the anchor and the offset
   linearly (:func:`~wirecal.solver.fit.model.multilaterate`).
2. **Parameters**: the attachment, the anchor, the offsets (and the scale) always; then the
   DH errors of rows 2…n (:func:`candidates`), each kept when it raises the rank of
   ∂L/∂x over *these* rows and leaves every σ (from the quantisation floor) below
   :data:`~wirecal.solver.verdict.POORLY_IDENTIFIED` deg or mm (the scale: below the
   default datasheet tolerance, 500 ppm)
   (:func:`~wirecal.solver.identifiability.select_columns`). Row 1 is a rigid motion of the
   arm that the anchor absorbs; θ_n and d_n move the attachment, which is fitted.
3. **Robust fit, sessions**: least squares with the soft-L1 loss, f_scale the robust
   σ of the residual; rows beyond :data:`REJECT_SIGMA` σ are outliers (and rows whose x, y,
   z disagree with their joints, ``Data.excluded``); the lengths less the
   model without offsets, ordered by row, give the offset jumps
   (:mod:`~wirecal.solver.fit.sessions`); refit per session until the sessions stand.
4. **Final fit**: the parameters chosen again on the inliers with the robust σ (at least
   the floor) — identifiability decides on the rows actually used and their actual
   noise — then plain least squares, σ's from σ²·(JᵀJ)⁻¹ with σ the residual's
   (:func:`final_solve`: a second start when a DH error ends beyond plausibility; a
   parameter the final rows do not identify is refused).
   A jump still found in the final residual is refused (``single_session`` fits one
   offset on purpose and lists the jumps it ignores).
5. **Held-out validation** (:mod:`~wirecal.solver.fit.holdout`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from wirecal.solver import params as P
from wirecal.solver.compliance import SIGMA_LIMIT_URAD_PER_NM
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.holdout import (
    Holdout,
    check_training,
    first_same,
    parse_scheme,
    row_floor,
    splits,
    summarise,
)
from wirecal.solver.fit.model import (
    Layout,
    lengths,
    lengths_and_jacobian,
    lengths_then_jacobian,
    multilaterate,
    session_of,
)
from wirecal.solver.fit.select import bic_eliminated
from wirecal.solver.fit.sessions import change_points, noise_sigma, place, robust_sigma
from wirecal.solver.fit.solver import SolverLoss, minimised
from wirecal.solver.identifiability import (
    Identifiability,
    analyse_jacobian,
    covariance,
    select_columns,
)
from wirecal.solver.kinematics import Model, tool_position
from wirecal.solver.memo import Kept, digest
from wirecal.solver.robot import DEFAULT_SCALE_TOLERANCE_PPM, Robot
from wirecal.solver.verdict import POORLY_IDENTIFIED, implausible

REJECT_SIGMA = 5.0
"""Rows whose residual exceeds this many robust σ are outliers (snags, typos)."""

MAX_SESSION_PASSES = 6
"""Refits with new sessions before the sessions must stand."""


@dataclass(frozen=True)
class Core:
    """The result of the fit on a table's rows (before the held-out validation)."""

    layout: Layout
    x: np.ndarray  # internal units
    std: np.ndarray  # internal units
    starts: tuple[int, ...]  # 0-based data rows where a session starts
    session: np.ndarray  # (N,) 0-based session of each row
    inliers: np.ndarray  # (N,) bool
    residual_mm: np.ndarray  # (N,) model − measured at x, every row
    sigma_mm: float  # residual σ of the final fit (inliers)
    dropped: tuple[tuple[str, str], ...]
    identifiability: Identifiability
    ignored_jumps: tuple[int, ...] = ()  # jumps found but not fitted (single session)
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class Data:
    """The rows a fit uses: joints (rad), lengths (mm), each row's session, the floor."""

    q_rad: np.ndarray  # (N, n)
    length_mm: np.ndarray  # (N,)
    session: np.ndarray  # (N,) 0-based session of each row
    floor_mm: float  # the quantisation floor's RMS at the nominal model (a least σ)
    joint_cov_rad2: np.ndarray | None = None  # (N, n, n) refined joints' covariance
    excluded: np.ndarray | None = None  # (N,) bool: rows known bad (x, y, z disagree, copies)
    group: np.ndarray | None = None  # (N,) rows at the same logged joints: one group (holdout)


def candidates(base: Model) -> tuple[str, ...]:
    """Return the DH errors a fit may choose from, in the order it tries them.

    Rows 2…n: the θ offsets, the lengths a, d that are non-zero in the robot file, the zero
    ones, then the twists α; of a degenerate set (the d's of parallel axes) the first is kept,
    so a length the data sheet names wins over one it leaves at zero.
    """
    n = base.n_joints
    rows = range(1, n)
    lengths = [f"a{i}" for i in rows] + [f"d{i + 1}" for i in rows]
    nonzero = {
        name
        for i in rows
        for name, v in ((f"a{i}", base.dh[i, 1]), (f"d{i + 1}", base.dh[i, 3]))
        if abs(v) > 1e-9
    }
    return (
        *(f"th{i + 1}" for i in rows),
        *(p for p in lengths if p in nonzero),
        *(p for p in lengths if p not in nonzero),
        *(f"al{i}" for i in rows),
    )


def point_model(robot: Robot) -> Model:
    """Return the robot's nominal model with the wire leaving from a point (the anchor).

    With ``[calibration] compliances`` it carries the arm's masses and compliances (the
    robot file's, else 0), so the fit can estimate c_j beside the geometry
    (:func:`choose`); otherwise it is rigid.
    """
    nominal = robot.nominal
    if not robot.compliances or nominal.masses is None:
        return Model(dh=nominal.dh, tool_point=nominal.tool_point)
    c = np.zeros(robot.n_joints) if nominal.compliance is None else nominal.compliance
    return Model(nominal.dh, nominal.tool_point, masses=nominal.masses, compliance=c)


def start(base: Model, layout: Layout, data: Data) -> np.ndarray:
    """Return the starting vector: nominal geometry, anchor and offsets by multilateration."""
    p = tool_position(base, data.q_rad)
    lin = multilaterate(p, data.length_mm, data.session, layout.n_sessions)
    x = np.zeros(len(layout.names))
    g = len(layout.geometry)
    x[g : g + 3] = lin[:3]
    x[g + 3 + int(layout.scale) :] = lin[3:]
    return x


def _boundary_jacobian(J: np.ndarray, layout: Layout) -> np.ndarray:
    """Return ∂L/∂x per boundary unit (mm/deg, mm/mm, mm/ppm)."""
    return J / layout.boundary_per_internal


def _carry(old: Layout, x: np.ndarray, new: Layout) -> np.ndarray:
    """Return ``x`` of layout ``old`` in layout ``new``: shared names keep their values."""
    by_name = dict(zip(old.names, x, strict=True))
    return np.array([by_name.get(n, 0.0) for n in new.names])


def choose(
    base: Model,
    layout: Layout,
    x: np.ndarray,
    data: Data,
    rows: np.ndarray,
    sigma_mm: float,
    compliances: tuple[str, ...] = (),
) -> tuple[Layout, np.ndarray, tuple[tuple[str, str], ...]]:
    """Choose the identifiable DH errors at ``x`` over ``rows`` (module docstring, step 2).

    ``layout`` may hold any geometry; the result holds the attachment and the chosen DH
    errors, with ``x`` carried over (a newly added parameter starts at 0).
    ``compliances`` (c_j, ``base`` with the arm's masses) are tried after the DH errors,
    each kept when it raises the rank and its σ stays below
    :data:`~wirecal.solver.compliance.SIGMA_LIMIT_URAD_PER_NM` (and the others' below
    theirs): a compliance whose torque changes too little over the rows is a θ_j offset.

    The columns are judged at the nominal DH geometry (``x``'s attachment, anchor, offsets
    and scale): which DH errors can be told apart is the arm's structure, and a DH error
    fitted to noise must not decide it. A twist fitted at −0.004° between the Viper's
    parallel axes 2 and 3 made d₃ look separable from d₂; the twist, chosen after it, then
    dropped out (0: the axes parallel again), and the final fit ran along the exact
    degeneracy d₂ − d₃ (d₂ +2683 mm, d₃ −2683 mm).
    """
    full = replace(layout, geometry=(*P.TOOL_NAMES, *candidates(base), *compliances))
    xf = _carry(layout, x, full)
    g = len(full.geometry)
    nominal = xf.copy()
    nominal[3:g] = 0.0  # the DH errors and compliances (the attachment, fitted, stays)
    _, J = lengths_and_jacobian(base, full, nominal, data.q_rad[rows], data.session[rows])
    order = [*range(3), *range(g, len(full.names)), *range(3, g)]  # required first
    limit = np.full(len(full.names), np.inf)  # attachment, anchor, offsets: what they are
    limit[3:g] = [
        SIGMA_LIMIT_URAD_PER_NM if n in compliances else POORLY_IDENTIFIED
        for n in full.geometry[3:]
    ]  # DH errors: deg or mm; compliances: µrad/(N·m)
    if layout.scale:
        limit[g + 3] = DEFAULT_SCALE_TOLERANCE_PPM
    sel = select_columns(
        _boundary_jacobian(J, full)[:, order],
        [full.names[k] for k in order],
        len(full.names) - g + 3,
        sigma_mm=sigma_mm,
        max_std=limit[order],
    )
    kept = {order[k] for k in sel.kept}
    chosen = replace(layout, geometry=tuple(n for k, n in enumerate(full.geometry) if k in kept))
    return chosen, _carry(full, xf, chosen), sel.dropped


def residual(base: Model, layout: Layout, x: np.ndarray, data: Data) -> np.ndarray:
    """Return model − measured length (mm) of every row at ``x``."""
    return lengths(base, layout, x, data.q_rad, data.session) - data.length_mm


def solve(
    base: Model,
    layout: Layout,
    x0: np.ndarray,
    data: Data,
    rows: np.ndarray,
    *,
    loss: SolverLoss = "linear",
    f_scale: float = 1.0,
    free: np.ndarray | None = None,
) -> np.ndarray:
    """Return the least-squares ``x`` over ``rows`` from ``x0`` (analytic Jacobian).

    ``free`` (k,) bool: the parameters to adjust (default all); the others keep ``x0``'s.
    The solver is :func:`~wirecal.solver.fit.solver.levenberg_marquardt` (the normal
    equations, k × k, instead of a factorisation of the N × k Jacobian); each point's
    lengths and Jacobian are evaluated together.
    """
    return _solved(base, layout, x0, data, rows, loss, f_scale, free)[0]


def _solved(
    base: Model,
    layout: Layout,
    x0: np.ndarray,
    data: Data,
    rows: np.ndarray,
    loss: SolverLoss,
    f_scale: float,
    free: np.ndarray | None = None,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return :func:`solve`'s ``x`` with the residual and ∂L/∂x (``free``'s) over ``rows`` there.

    ``start``: the residual and ∂L/∂x (every column) over ``rows`` at ``x0`` when the caller
    has them (the solver does not evaluate them again).
    """
    free = np.ones(len(x0), dtype=bool) if free is None else free
    q, length, session = data.q_rad[rows], data.length_mm[rows], data.session[rows]

    def full(xf: np.ndarray) -> np.ndarray:
        x = x0.copy()
        x[free] = xf
        return x

    def fun(xf: np.ndarray) -> tuple[np.ndarray, Callable[[], np.ndarray]]:
        model, jacobian = lengths_then_jacobian(base, layout, full(xf), q, session)
        return model - length, lambda: jacobian()[:, free]  # taken where the solver accepts

    at = None if start is None else (start[0], start[1][:, free])
    xf, r, J = minimised(fun, x0[free], loss=loss, f_scale=f_scale, start=at)
    return full(xf), r, J


def _every_row(
    base: Model, layout: Layout, x: np.ndarray, data: Data
) -> tuple[np.ndarray, np.ndarray]:
    """Return the residual, model − measured (N,), and ∂L/∂x (N, k) of every row at ``x``."""
    model, J = lengths_and_jacobian(base, layout, x, data.q_rad, data.session)
    return model - data.length_mm, J


def _implausible(layout: Layout, x: np.ndarray) -> list[str]:
    """Return the DH errors of ``x`` beyond a physically plausible size (the gate's)."""
    g = len(layout.geometry)
    values = x[:g] * layout.boundary_per_internal[:g]
    dh = [k for k, n in enumerate(layout.geometry) if n not in P.TOOL_NAMES]
    return implausible([layout.geometry[k] for k in dh], values[dh])


def final_solve(
    base: Model, layout: Layout, x0: np.ndarray, data: Data, rows: np.ndarray
) -> np.ndarray:
    """Return the plain least-squares ``x`` over ``rows``, from a second start if need be.

    A first result with a DH error beyond a physically plausible size
    (:func:`~wirecal.solver.verdict.implausible`) is a local minimum or a run along a
    weak direction, not an estimate: the fit starts again with the DH errors at 0 (the
    attachment, anchor, offsets as found) and keeps the second result unless it fits
    worse. Still beyond, it is reported as it is and the plausibility gate refuses it.
    """
    first = solve(base, layout, x0, data, rows)
    if not _implausible(layout, first):
        return first
    restart = x0.copy()
    restart[[k for k, n in enumerate(layout.geometry) if n not in P.TOOL_NAMES]] = 0.0
    second = solve(base, layout, restart, data, rows)

    def cost(x: np.ndarray) -> float:
        return float(np.sum(residual(base, layout, x, data)[rows] ** 2))

    return second if cost(second) <= cost(first) * (1 + 1e-9) else first


@dataclass(frozen=True)
class Estimate:
    """A fit at its estimate, evaluated once: the residual, ∂L/∂x, σ and the covariance."""

    layout: Layout
    x: np.ndarray
    residual_mm: np.ndarray  # (N,) model − measured, every row
    jacobian: np.ndarray  # (len(rows), k) ∂L/∂x over the rows fitted
    sigma_mm: float  # the residual's σ over the rows fitted
    cov: np.ndarray  # (k, k) σ²·(JᵀJ)⁺ over the directions the rows see
    identified: np.ndarray  # (k,) bool


def evaluate(base: Model, layout: Layout, x: np.ndarray, data: Data, rows: np.ndarray) -> Estimate:
    """Return the fit at ``x`` over ``rows``: the covariance from R of a thin QR of ∂L/∂x.

    R (k × k) has the Jacobian's singular values and right vectors: the SVD of the
    covariance runs on k rows instead of N.
    """
    r, J = _every_row(base, layout, x, data)
    sigma = float(np.sqrt(np.sum(r[rows] ** 2) / max(len(rows) - len(x), 1)))
    J = J[rows]
    R = np.linalg.qr(J, mode="r") if len(rows) > len(x) else J
    cov, identified = covariance(np.asarray(R), sigma**2)
    return Estimate(layout, x, r, J, sigma, cov, identified)


def generalise(
    base: Model, layout: Layout, x: np.ndarray, data: Data, rows: np.ndarray
) -> tuple[Estimate, tuple[tuple[str, str], ...]]:
    """Drop the DH errors BIC does not keep (:mod:`~wirecal.solver.fit.select`) and refit.

    Returns the final fit evaluated at its estimate and why each DH error was dropped.
    """
    est = evaluate(base, layout, x, data, rows)
    if not est.identified.all():
        return est, ()  # not BIC's to drop as "not worth a parameter": fit_core refuses it
    dh = [k for k, n in enumerate(layout.geometry) if n not in P.TOOL_NAMES]
    out = bic_eliminated(est.cov, x, dh, len(rows))
    if not out:
        return est, ()
    bar = np.sqrt(np.log(len(rows)))
    why = tuple(
        (
            layout.names[k],
            f"not worth a parameter (BIC): |z| {z:.2f} < √ln N = {bar:.2f}, "
            "so it stays at the robot file's value",
        )
        for k, z in out
    )
    gone = {layout.names[k] for k, _ in out}
    kept = replace(layout, geometry=tuple(n for n in layout.geometry if n not in gone))
    x = final_solve(base, kept, _carry(layout, x, kept), data, rows)
    return evaluate(base, kept, x, data, rows), why


SUBSAMPLE_ROWS = 4096
"""Rows of a large table the first robust solve uses (:func:`robust_pass`)."""


def subsample(n_rows: int) -> np.ndarray:
    """Return every row, or of more than 2 × :data:`SUBSAMPLE_ROWS` rows an even stride of them.

    An even stride, not a random draw: the fit stays deterministic, and the rows' order
    (the sessions) is sampled evenly.
    """
    stride = 1 if n_rows <= 2 * SUBSAMPLE_ROWS else -(-n_rows // SUBSAMPLE_ROWS)
    return np.arange(0, n_rows, stride)


@dataclass(frozen=True)
class Pass:
    """One robust pass: its layout and estimate, the residual, the inliers and their σ."""

    layout: Layout
    x: np.ndarray
    residual_mm: np.ndarray
    inliers: np.ndarray
    sigma_mm: float


def robust_pass(base: Model, layout: Layout, x0: np.ndarray, data: Data) -> Pass:
    """Soft-L1 fit (f_scale: the residual's robust σ), then the rows beyond 5σ rejected.

    The first of the two solves runs on :func:`subsample`'s rows: it travels from the start
    (the most iterations), the second, on every row, from near its end. Each solve starts
    from the residual and ∂L/∂x of every row its start was evaluated at (the first solve's
    end, when it ran on every row), and the pass's residual is the second's at its end.
    """
    n = len(data.length_mm)
    x = x0
    r, J = _every_row(base, layout, x, data)
    for rows in (subsample(n), np.arange(n)):  # the second with the σ of the first's residual
        sigma = max(robust_sigma(r), data.floor_mm)
        x, *end = _solved(base, layout, x, data, rows, "soft_l1", sigma, start=(r[rows], J[rows]))
        r, J = end if rows.size == n else _every_row(base, layout, x, data)
    sigma = max(robust_sigma(r), 1e-9)
    inliers = np.abs(r - np.median(r)) <= REJECT_SIGMA * sigma
    if data.excluded is not None:
        inliers &= ~data.excluded
    return Pass(layout, x, r, inliers, sigma)


def offset_sequence(layout: Layout, x: np.ndarray, r: np.ndarray, data: Data) -> np.ndarray:
    """Return the lengths less the model without offsets, c_s − r, row by row."""
    return layout.split(x)[3][data.session] - r


def _session_starts(ps: Pass, data: Data, values: np.ndarray | None = None) -> tuple[int, ...]:
    """Return the rows where sessions start: change points of the offsets c_s − r.

    Every row is searched, the fit's outliers too: rows a fit rejects may be a session it
    does not yet follow (the search deals with lone outliers itself); then every boundary is
    placed robustly (:func:`~wirecal.solver.fit.sessions.place`). ``values``: search these.
    Rows known bad (``data.excluded``: copies, x, y, z disagreeing) are not searched: a
    session of copies alone would have an offset no row identifies.
    """
    u = offset_sequence(ps.layout, ps.x, ps.residual_mm, data) if values is None else values
    bad = data.excluded if data.excluded is not None and not data.excluded.all() else None
    kept = np.arange(u.size) if bad is None else np.flatnonzero(~bad)
    sigma = noise_sigma(u[kept])  # the search's σ and the placing's: found once
    found = place(u[kept], (0, *change_points(u[kept], sigma)), sigma)
    return (0, *(int(kept[s]) for s in found[1:]))


def _with_sessions(
    ps: Pass, data: Data, starts: tuple[int, ...]
) -> tuple[Layout, np.ndarray, Data]:
    """Return layout, start vector and data with an offset per session of ``starts``."""
    u = offset_sequence(ps.layout, ps.x, ps.residual_mm, data)
    new = replace(data, session=session_of(starts, len(data.length_mm)))
    layout = replace(ps.layout, n_sessions=len(starts))
    x = _carry(ps.layout, ps.x, layout)
    k = len(layout.names) - layout.n_sessions
    for s in range(layout.n_sessions):
        mine = ps.inliers & (new.session == s)
        x[k + s] = np.median(u[mine]) if np.any(mine) else np.median(u[new.session == s])
    return layout, x, new


def _settle_sessions(
    base: Model, layout: Layout, x: np.ndarray, data: Data, single_session: bool
) -> tuple[Pass, Data, tuple[int, ...], tuple[int, ...]]:
    """Refit with the sessions found until they stand; return the pass, starts, ignored jumps.

    A boundary may alternate between rows a few apart (each fit places it where the other
    did not: simulated, rows 450 and 452 of 1000 in turn); once a set of sessions comes
    back, the cycle stands and its fit with the fewest outliers (then the least robust σ) is
    kept: rows given the wrong session's offset are outliers of their fit.
    """
    starts: tuple[int, ...] = (0,)
    passes: dict[tuple[int, ...], tuple[Pass, Data]] = {}
    for _ in range(MAX_SESSION_PASSES):
        ps = robust_pass(base, layout, x, data)
        passes[starts] = (ps, data)
        found = _session_starts(ps, data)
        if single_session:
            return ps, data, starts, found[1:]
        if found == starts:
            return ps, data, starts, ()
        if found in passes:
            cycle = list(passes)[list(passes).index(found) :]
            best = min(cycle, key=lambda s: (np.sum(~passes[s][0].inliers), passes[s][0].sigma_mm))
            return *passes[best], best, ()
        starts = found
        layout, x, data = _with_sessions(ps, data, starts)
    raise WirecalError(
        f"the offset jumps did not settle after {MAX_SESSION_PASSES} refits (last found at "
        f"data rows {', '.join(map(str, starts[1:]))}): the lengths do not fit one model; "
        "check the column map and the robot file"
    )


def fit_core(
    base: Model,
    data: Data,
    *,
    scale: bool = False,
    single_session: bool = False,
    compliances: tuple[str, ...] = (),
) -> Core:
    """Fit the model to every row of ``data`` (module docstring, steps 1–4).

    ``compliances``: the c_j to try beside the DH errors (:func:`choose`; ``base`` from
    :func:`point_model` of a robot file that asks for them). Kept by the contents of its
    inputs (:data:`KEPT_FITS`); each caller is given its own copy.
    """
    key = digest("fit_core", base, data, scale, single_session, compliances)
    return _FITS.copy_of(key, lambda: _fit_core(base, data, scale, single_session, compliances))


KEPT_FITS = 16
"""How many fits (:func:`fit_core`) are kept by their inputs' contents
(:mod:`~wirecal.solver.memo`): a table is fitted again with the same rows and options (the
same table with another held-out validation, which fits its splits anew), the very same
computation. A refusal is not kept."""

_FITS: Kept[Core] = Kept(KEPT_FITS)


def _fit_core(
    base: Model, data: Data, scale: bool, single_session: bool, compliances: tuple[str, ...]
) -> Core:
    """Return :func:`fit_core` computed."""
    n = len(data.length_mm)
    data = replace(data, session=np.zeros(n, dtype=int))
    layout = Layout(P.TOOL_NAMES, base.n_joints, 1, scale)
    x = start(base, layout, data)
    layout, x, _ = choose(base, layout, x, data, np.arange(n), data.floor_mm, compliances)
    ps, data, starts, ignored = _settle_sessions(base, layout, x, data, single_session)
    rows = np.flatnonzero(ps.inliers)
    noise = max(data.floor_mm, ps.sigma_mm)  # a noisier table identifies less
    layout, x, dropped = choose(base, ps.layout, ps.x, data, rows, noise, compliances)
    x = final_solve(base, layout, x, data, rows)
    est, weak = generalise(base, layout, x, data, rows)
    layout, x, r, sigma, identified = (
        est.layout,
        est.x,
        est.residual_mm,
        est.sigma_mm,
        est.identified,
    )
    if not identified.all():  # choose() keeps identifiable parameters only: a defect
        unseen = ", ".join(n for n, ok in zip(layout.names, identified, strict=True) if not ok)
        raise WirecalError(
            f"the fit's parameters {unseen} are not identified by these rows at the fitted "
            "values (the fit ran far from the robot file's geometry): check that the table is "
            "this robot's (the joint columns its joints in degrees, in the robot file's "
            "convention) and that --map names the cable length's column; nothing is reported"
        )
    if not single_session:  # a jump the offsets do not follow
        final = Pass(layout, x, r, ps.inliers, sigma)
        ignored = _session_starts(final, data, values=r)[1:]
    return Core(
        layout=layout,
        x=x,
        std=np.sqrt(np.clip(np.diag(est.cov), 0, None)),
        starts=starts,
        session=data.session,
        inliers=ps.inliers,
        residual_mm=r,
        sigma_mm=sigma,
        dropped=dropped + weak,
        identifiability=analyse_jacobian(_boundary_jacobian(est.jacobian, layout), layout.names),
        ignored_jumps=ignored,
    )


def nominal_floor(base: Model, data: Data, joint_res_deg: float, length_res_mm: float) -> float:
    """Return the quantisation floor's RMS over the rows, with the anchor from the start."""
    layout = Layout((), base.n_joints, 1, False)
    x = start(base, layout, replace(data, session=np.zeros(len(data.length_mm), dtype=int)))
    f = row_floor(base, layout, x, data.q_rad, joint_res_deg, length_res_mm, data.joint_cov_rad2)
    return float(np.sqrt(np.mean(f**2)))


def holdout(
    base: Model,
    core: Core,
    data: Data,
    scheme: str,
    *,
    repeats: int,
    seed: int,
    resolution: tuple[float, float],
) -> Holdout:
    """Refit on each split's training rows and predict its held-out rows (fit_holdout)."""
    kind, share = parse_scheme(scheme)
    layout, data = core.layout, replace(data, session=core.session)
    k0 = len(layout.names) - layout.n_sessions
    residuals, floors, notes = [], [], []
    group = first_same(data.q_rad) if data.group is None else data.group
    for train, test in splits(kind, share, core.inliers, group, repeats, seed):
        check_training(scheme, len(train), int(core.inliers.sum()), len(core.x))
        free = np.ones(len(core.x), dtype=bool)
        unseen = sorted(set(data.session[test]) - set(data.session[train]))
        free[[k0 + s for s in unseen]] = False
        x = solve(base, layout, core.x, data, train, free=free)
        r = residual(base, layout, x, data)[test]
        for s in unseen:
            mine = data.session[test] == s
            r[mine] -= np.median(r[mine])
            notes.append(
                f"session {s + 1} has no training row: its offset is the median of its "
                "held-out rows"
            )
        residuals.append(r)
        cov = None if data.joint_cov_rad2 is None else data.joint_cov_rad2[test]
        floors.append(row_floor(base, layout, core.x, data.q_rad[test], *resolution, cov))
    used = repeats if kind == "random" else int(kind == "half")
    return summarise(scheme, used, residuals, floors, notes)
