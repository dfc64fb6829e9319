"""A Python emulation of exactly the controller solver: same tables, same operations in
the same order, in float64 or float32 arithmetic, or counting operations.

It mirrors ``templates/vplus/solver.v2.j2`` line by line; the reference solver
(:mod:`wirecal.solver.identify`) cross-checks it.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from wirecal.gen.tables import JOINT_ITERATIONS, STEP_ITERATIONS, Tables, sin_cosm1_small
from wirecal.solver.formats.log import Log
from wirecal.solver.plan import Plan


class Counted(float):
    """A float that counts the arithmetic done with it (for the cost figures)."""

    ops: ClassVar[Counter] = Counter()

    def _op(self, kind, value):
        Counted.ops[kind] += 1
        return Counted(value)

    def __add__(self, o):
        return self._op("add", float(self) + float(o))

    def __radd__(self, o):
        return self._op("add", float(o) + float(self))

    def __sub__(self, o):
        return self._op("add", float(self) - float(o))

    def __rsub__(self, o):
        return self._op("add", float(o) - float(self))

    def __mul__(self, o):
        return self._op("mul", float(self) * float(o))

    def __rmul__(self, o):
        return self._op("mul", float(o) * float(self))

    def __truediv__(self, o):
        return self._op("div", float(self) / float(o))

    def __rtruediv__(self, o):
        return self._op("div", float(o) / float(self))

    def __neg__(self):
        return Counted(-float(self))


FLAVOURS = {"float64": np.float64, "float32": np.float32, "count": Counted}


def _sqrt(x):
    if isinstance(x, Counted):
        Counted.ops["sqrt"] += 1
        return Counted(np.sqrt(float(x)))
    return type(x)(np.sqrt(x))


@dataclass(frozen=True)
class Readings:
    """What the measurement program stores for the solver (per configuration c = 0..N).

    Counts are kept as an integer base (the first sample, exact in a REAL) plus a small
    DOUBLE offset (the mean of the unwrapped samples minus the base), per point and per
    step's zero reading.
    """

    q: np.ndarray  # (N+1, n) logged joints (deg); row 0: the first zero reading
    cb: np.ndarray  # (N+1,) count base of each point (row 0 unused)
    co: np.ndarray  # (N+1,) count offset of each point
    zb: np.ndarray  # (S,) count base of each step's zero
    zo: np.ndarray  # (S,) count offset of each step's zero
    mm_per_count: float
    bits: int


def readings_from_log(log: Log, plan: Plan) -> Readings:
    """The arrays the measurement program would have filled, rebuilt from its log."""
    q_plan, step_no, index_no = plan.all_points()
    pos = {(int(s), int(i)): k + 1 for k, (s, i) in enumerate(zip(step_no, index_no, strict=True))}
    n = q_plan.shape[1]
    q = np.vstack([plan.theta0_deg, q_plan])
    cb = np.zeros(len(q))
    co = np.zeros(len(q))
    zb = np.zeros(len(plan.steps))
    zo = np.zeros(len(plan.steps))
    first_zero = True
    for r in log.readings:
        base = float(np.round(r.counts))
        if r.kind == "zero" and r.step > len(plan.steps):
            continue  # the closing zero checks the last step; it is not a reference
        if r.kind == "zero":
            zb[r.step - 1], zo[r.step - 1] = base, r.counts - base
            if first_zero:
                q[0] = r.joints_deg[:n]
                first_zero = False
        else:
            k = pos[(r.step, r.index)]
            cb[k], co[k], q[k] = base, r.counts - base, r.joints_deg[:n]
    return Readings(q, cb, co, zb, zo, log.mm_per_count, 24)


def wrap(x, half, full):
    """A count difference brought into [−half, half) as the controller does it."""
    if x >= half:
        return x - full
    if x < -half:
        return x + full
    return x


class Controller:
    """The controller solver's state and routines (wc.dist, wc.fk, wc.dp, wc.step …)."""

    def __init__(self, t: Tables, r: Readings, flavour: str = "float64"):
        num = FLAVOURS[flavour]
        self.num = num
        self.one = num(1.0)
        conv = np.vectorize(lambda v: num(float(v)), otypes=[object])
        self.t = {
            k: conv(getattr(t, k))
            for k in (
                "ca",
                "sa",
                "la",
                "ld",
                "tool",
                "ct",
                "st",
                "qp",
                "vn",
                "dn",
                "dni",
                "dnf",
                "omega",
            )
        }
        self.t["to_boundary"] = conv(t.errors.boundary_per_internal)
        self.tab = t
        self.q = conv(r.q)
        self.d2r = num(np.pi / 180)
        self.n, self.m = t.n, len(t.names)
        self.e = [num(0.0)] * (self.m + 1)  # estimates, 1-based
        self.wd = self._distances(r)  # m_i = d̃_i − d_n,i

    # wc.dist: m_i = d̃_i − d_n,i from the stored counts, small numbers only. The
    # reference is the mean of the zeros; counts are relative to the first zero (zb[0]).
    def _distances(self, r: Readings):
        num = self.num
        half, full = num(2.0 ** (r.bits - 1)), num(2.0**r.bits)
        S = len(r.zb)
        zsum = num(0.0)
        for s in range(S):
            zsum = zsum + (wrap(num(r.zb[s]) - num(r.zb[0]), half, full) + num(r.zo[s]))
        ref = zsum / S
        mpc = num(self.tab.mpc)
        md = [num(0.0)] * len(r.cb)
        for i in range(1, len(r.cb)):
            whole = wrap(num(r.cb[i]) - num(r.zb[0]), half, full) - self.t["dni"][i]
            md[i] = (whole + ((num(r.co[i]) - ref) - self.t["dnf"][i])) * mpc
        return md

    # wc.apply: current estimates per DH row (eth, ed, ea, eal) and tool (et)
    def _apply(self):
        zero = self.num(0.0)
        rows = {kind: [zero] * (self.n + 1) for kind in (1, 2, 3, 4)}
        et = [zero] * 4
        for j in range(1, self.m + 1):
            kind, row = int(self.tab.pk[j - 1]), int(self.tab.pr[j - 1])
            if kind == 5:
                et[row] = self.e[j]
            else:
                rows[kind][row] = self.e[j]
        self.eth, self.ed, self.ea, self.eal = rows[1], rows[2], rows[3], rows[4]
        self.et = et

    # wc.fk: configuration c as nominal frames (Xn, Yn, Zn, On) plus deviations (ΔX, ΔY,
    # ΔZ, ΔO) carried side by side; every Δ update is a sum of products with a small
    # factor, so no big number is ever subtracted from another. Returns Δp and p.
    def _fk(self, c):
        num, t = self.num, self.t
        zero, one = num(0.0), self.one
        Xn, Yn, Zn, On = [one, zero, zero], [zero, one, zero], [zero, zero, one], [zero] * 3
        dX, dY, dZ, dO = [zero] * 3, [zero] * 3, [zero] * 3, [zero] * 3
        self.fx, self.fo0, self.fz, self.fo = {}, {}, {}, {}
        for k in range(1, self.n + 1):
            self.fx[k] = [Xn[i] + dX[i] for i in range(3)]
            self.fo0[k] = [On[i] + dO[i] for i in range(3)]
            # twist α_{k-1} + estimate turns (Y, Z); then lengths; then θ_k turns (X, Y)
            Yn2, Zn2, dY2, dZ2 = _turn(
                t["ca"][k - 1], t["sa"][k - 1], self.eal[k], Yn, Zn, dY, dZ, one
            )
            an, dn = t["la"][k - 1], t["ld"][k - 1]
            a, d = an + self.ea[k], dn + self.ed[k]
            On = [On[i] + an * Xn[i] + dn * Zn2[i] for i in range(3)]
            dO = [
                dO[i] + self.ea[k] * Xn[i] + a * dX[i] + self.ed[k] * Zn2[i] + d * dZ2[i]
                for i in range(3)
            ]
            eps = (self.q[c, k - 1] - t["qp"][c, k - 1]) * self.d2r + self.eth[k]
            Xn, Yn, dX, dY = _turn(t["ct"][c, k - 1], t["st"][c, k - 1], eps, Xn, Yn2, dX, dY2, one)
            Zn, dZ = Zn2, dZ2
            self.fz[k] = [Zn[i] + dZ[i] for i in range(3)]
            self.fo[k] = [On[i] + dO[i] for i in range(3)]
        tn = t["tool"]
        et = self.et
        X = [Xn[i] + dX[i] for i in range(3)]
        Y = [Yn[i] + dY[i] for i in range(3)]
        Z = [Zn[i] + dZ[i] for i in range(3)]
        self.R = (X, Y, Z)
        dp = [
            dO[i]
            + dX[i] * tn[0]
            + dY[i] * tn[1]
            + dZ[i] * tn[2]
            + X[i] * et[1]
            + Y[i] * et[2]
            + Z[i] * et[3]
            for i in range(3)
        ]
        p = [On[i] + Xn[i] * tn[0] + Yn[i] * tn[1] + Zn[i] * tn[2] + dp[i] for i in range(3)]
        return dp, p

    # wc.dp: ∂p/∂e_j from the frames of the last wc.fk
    def _dp(self, j, p):
        kind, k = int(self.tab.pk[j - 1]), int(self.tab.pr[j - 1])
        if kind == 1:
            return _cross(self.fz[k], [p[i] - self.fo[k][i] for i in range(3)])
        if kind == 2:
            return self.fz[k]
        if kind == 3:
            return self.fx[k]
        if kind == 4:
            return _cross(self.fx[k], [p[i] - self.fo0[k][i] for i in range(3)])
        return self.R[k - 1]

    # the residual of point i from the small deviations Δν = Δp_i − Δp_0:
    # u = 2 ν_n·Δν + |Δν|², d − d_n = u / (d_n + √(d_n² + u)); SQRT only scales a small
    # quantity, so its precision does not matter.
    def _residual(self, i, dp, dp0):
        t = self.t
        dv = [dp[a] - dp0[a] for a in range(3)]
        u = 2 * (t["vn"][i, 0] * dv[0] + t["vn"][i, 1] * dv[1] + t["vn"][i, 2] * dv[2]) + (
            dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]
        )
        dn = t["dn"][i]
        dd = u / (dn + _sqrt(dn * dn + u))
        r = dd - self.wd[i]
        nu = [t["vn"][i, a] + dv[a] for a in range(3)]
        return r, nu, dn + dd

    # wc.step: the paper's step j, fixed Gauss–Newton iterations within ±Ω
    def step(self, s):
        tab = self.tab
        j = int(tab.spar[s - 1])
        om = self.t["omega"][s - 1]
        self.e[j] = self.num(0.0)
        for _ in range(STEP_ITERATIONS):
            self._apply()
            dp0, p0 = self._fk(0)
            g0 = self._dp(j, p0)
            srg, sgg = self.num(0.0), self.num(0.0)
            for i in range(int(tab.first[s - 1]), int(tab.first[s - 1] + tab.count[s - 1])):
                dp, p = self._fk(i)
                g = self._dp(j, p)
                r, nu, d = self._residual(i, dp, dp0)
                gr = (nu[0] * (g[0] - g0[0]) + nu[1] * (g[1] - g0[1]) + nu[2] * (g[2] - g0[2])) / d
                srg = srg + r * gr
                sgg = sgg + gr * gr
            x = self.e[j] - srg / sgg
            self.e[j] = om if x > om else (-om if x < -om else x)

    # wc.polish: joint Gauss–Newton over all parameters, LDLᵀ (no square root)
    def polish(self):
        m, zero = self.m, self.num(0.0)
        for _ in range(JOINT_ITERATIONS):
            self._apply()
            dp0, p0 = self._fk(0)
            g0 = [None] + [self._dp(j, p0)[:] for j in range(1, m + 1)]
            H = [[zero] * (m + 1) for _ in range(m + 1)]
            b = [zero] * (m + 1)
            for i in range(1, self.tab.n_points + 1):
                dp, p = self._fk(i)
                r, nu, d = self._residual(i, dp, dp0)
                gr = [zero] * (m + 1)
                for j in range(1, m + 1):
                    g = self._dp(j, p)
                    gr[j] = (
                        nu[0] * (g[0] - g0[j][0])
                        + nu[1] * (g[1] - g0[j][1])
                        + nu[2] * (g[2] - g0[j][2])
                    ) / d
                for a in range(1, m + 1):
                    b[a] = b[a] + gr[a] * r
                    for c in range(a, m + 1):
                        H[a][c] = H[a][c] + gr[a] * gr[c]
            x = _ldlt_solve(H, b, m, zero)
            for j in range(1, m + 1):
                self.e[j] = self.e[j] - x[j]

    def estimates(self) -> np.ndarray:
        """Estimates in boundary units (deg, mm), identification order."""
        return np.array(
            [float(self.e[j] * self.t["to_boundary"][j - 1]) for j in range(1, self.m + 1)]
        )


def _turn(cn, sn, eps, U, V, dU, dV, one):
    """Turn the pair (U, V) by the nominal angle (cos cn, sin sn) plus a small ε, for the
    nominal vectors and, separately, their deviations (wc.fk's rotation step):
    U' = c·U + s·V, V' = c·V − s·U with c = cn + δc, s = sn + δs."""
    s, cm1 = sin_cosm1_small(eps, one)
    dc = cn * cm1 - sn * s
    ds = sn * cm1 + cn * s
    c, sv = cn + dc, sn + ds
    Un = [cn * U[i] + sn * V[i] for i in range(3)]
    Vn = [cn * V[i] - sn * U[i] for i in range(3)]
    dUn = [c * dU[i] + sv * dV[i] + dc * U[i] + ds * V[i] for i in range(3)]
    dVn = [c * dV[i] - sv * dU[i] + dc * V[i] - ds * U[i] for i in range(3)]
    return Un, Vn, dUn, dVn


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _ldlt_solve(H, b, m, zero):
    """Solve H x = b (H symmetric, upper triangle filled) by LDLᵀ: + − × ÷ only."""
    L = [[zero] * (m + 1) for _ in range(m + 1)]
    D = [zero] * (m + 1)
    for j in range(1, m + 1):
        s = H[j][j]
        for k in range(1, j):
            s = s - L[j][k] * L[j][k] * D[k]
        D[j] = s
        for i in range(j + 1, m + 1):
            s = H[j][i]
            for k in range(1, j):
                s = s - L[i][k] * L[j][k] * D[k]
            L[i][j] = s / D[j]
    y = [zero] * (m + 1)
    for i in range(1, m + 1):
        s = b[i]
        for k in range(1, i):
            s = s - L[i][k] * y[k]
        y[i] = s
    x = [zero] * (m + 1)
    for i in range(m, 0, -1):
        s = y[i] / D[i]
        for k in range(i + 1, m + 1):
            s = s - L[k][i] * x[k]
        x[i] = s
    return x


def run_controller(
    tables: Tables, readings: Readings, flavour: str = "float64", polish: bool = False
) -> tuple[np.ndarray, np.ndarray | None]:
    """The whole controller solve: stepwise estimates, and the polished ones if asked."""
    ctl = Controller(tables, readings, flavour)
    for s in range(1, len(tables.first) + 1):
        ctl.step(s)
    stepwise = ctl.estimates()
    if not polish:
        return stepwise, None
    ctl.polish()
    return stepwise, ctl.estimates()


def operation_counts(tables: Tables, readings: Readings, polish: bool) -> Counter:
    """Arithmetic operations of one full solve (add/sub, mul, div, sqrt)."""
    Counted.ops = Counter()
    run_controller(tables, readings, "count", polish)
    return Counted.ops
