"""Speed of the robot model: forward kinematics plus the wire-length Jacobian.

Times the vectorised path (wirecal.solver.distance.wire_jacobian) on 100,000 random Viper
configurations, on one core, against a naive per-point loop doing the same maths with
4×4 matrices, and checks both give the same numbers. Run:

    python bench/bench_kinematics.py
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver.distance import wire_jacobian  # noqa: E402

ROBOT = Path(__file__).resolve().parents[1] / "examples" / "viper_s650" / "robot.toml"


def naive(model, q, q0, names):
    """One configuration at a time, 4×4 homogeneous matrices, Python loops."""

    def chain(qi):
        T = np.eye(4)
        frames = [T]
        for (alpha, a, off, d), qj in zip(model.dh, qi, strict=True):
            ca, sa, ct, st = np.cos(alpha), np.sin(alpha), np.cos(qj + off), np.sin(qj + off)
            T = T @ np.array(
                [
                    [ct, -st, 0, a],
                    [ca * st, ca * ct, -sa, -sa * d],
                    [sa * st, sa * ct, ca, ca * d],
                    [0, 0, 0, 1],
                ]
            )
            frames.append(T)
        p = (T @ np.append(model.tool_point, 1))[:3]
        cols = []
        for name in names:
            kind, idx = name.rstrip("0123456789"), int(name.lstrip("adhlt"))
            if kind == "th":
                F = frames[idx]
                cols.append(np.cross(F[:3, 2], p - F[:3, 3]))
            elif kind == "d":
                cols.append(frames[idx][:3, 2])
            elif kind == "a":
                cols.append(frames[idx][:3, 0])
        return p, np.array(cols).T

    p0, J0 = chain(q0)
    d = np.empty(len(q))
    dd = np.empty((len(q), len(names)))
    for k, qi in enumerate(q):
        p, J = chain(qi)
        diff = p - p0
        d[k] = np.linalg.norm(diff)
        dd[k] = (diff / d[k]) @ (J - J0)
    return d, dd


def best_of(fn, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    robot = load_robot(ROBOT)
    model = robot.model({"th2": 0.3, "a2": 0.2})
    names = robot.parameters
    rng = np.random.default_rng(0)
    q = np.radians(rng.uniform(robot.joint_min_deg, robot.joint_max_deg, (100_000, 6)))
    q0 = np.radians([0, -90, 210, -90, 0, -90])

    t_vec, (d, dd) = best_of(lambda: wire_jacobian(model, q, q0, names), 5)
    n_naive = 2_000
    t_naive, (d_n, dd_n) = best_of(lambda: naive(model, q[:n_naive], q0, names), 2)
    assert np.allclose(d[:n_naive], d_n)
    assert np.allclose(dd[:n_naive], dd_n, atol=1e-9)
    per_point_naive = t_naive / n_naive
    per_point_vec = t_vec / len(q)
    print(f"FK + wire-length Jacobian ({len(names)} parameters), one core")
    print(
        f"  vectorised : {len(q):,} configurations in {t_vec:.3f} s "
        f"({per_point_vec * 1e6:.2f} us/config)"
    )
    print(
        f"  naive loop : {n_naive:,} configurations in {t_naive:.3f} s "
        f"({per_point_naive * 1e6:.1f} us/config; 100,000 would take "
        f"{per_point_naive * 1e5:.1f} s)"
    )
    print(f"  speed-up   : {per_point_naive / per_point_vec:.0f}x (same numbers to 1e-9)")


if __name__ == "__main__":
    main()
