"""Speed of the robot model: forward kinematics plus the wire-length Jacobian.

Times the vectorised path (wirecal.solver.distance.wire_jacobian) on 100,000 random Viper
configurations, on one core, against a naive per-point loop doing the same maths with
4×4 matrices, and checks both give the same numbers.

Then, against the code before (``solver/kinematics.py`` and ``solver/gravity.py`` of the git
revision ``--before``, copied to a temporary folder and imported beside the code now), the
CPU per call of the chain of frames, the tool Jacobian from frames, the gravity torques and
``with_errors``, by the number N of configurations per call (one DH table, or one per
configuration: "N x table"), median of ``--rounds`` interleaved rounds, with the ratio
now / before; every output is checked to be the same bit for bit. Run:

    python bench/bench_kinematics.py [--before main] [--rounds 5] [--no-naive]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"  # one core, before numpy loads

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import importlib.util  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from wirecal.formats.robot_file import load_robot  # noqa: E402
from wirecal.solver import gravity, kinematics  # noqa: E402
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


def naive_figures() -> None:
    """The vectorised FK and wire Jacobian against the naive loop (module docstring)."""
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


def code_before(ref: str, folder: Path) -> tuple:
    """Import ``solver/gravity.py`` and ``solver/kinematics.py`` of git revision ``ref``."""
    root = Path(__file__).resolve().parents[1]
    modules = []
    for name in ("gravity", "kinematics"):
        text = subprocess.run(
            ["git", "-C", str(root), "show", f"{ref}:solver/{name}.py"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        text = text.replace("from wirecal.solver.gravity import", "from before_gravity import")
        path = folder / f"before_{name}.py"
        path.write_text(text)
        spec = importlib.util.spec_from_file_location(f"before_{name}", path)
        module = importlib.util.module_from_spec(spec)  # type: ignore[arg-type]
        sys.modules[spec.name] = module  # type: ignore[union-attr]
        spec.loader.exec_module(module)  # type: ignore[union-attr]
        modules.append(module)
    return tuple(modules)


def cpu_per_call_us(fn, rounds_s: float = 0.02) -> float:
    """Return the CPU of one call of ``fn`` (µs), over calls filling about ``rounds_s``."""
    t, calls = time.process_time(), 0
    while time.process_time() - t < rounds_s:
        fn()
        calls += 1
    return (time.process_time() - t) / calls * 1e6


def same_bits(a, b) -> bool:
    """Return whether two outputs (arrays; tuples, frames or models of them) are the same."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(map(same_bits, a, b))
    if dataclasses.is_dataclass(a):
        arrays = [
            f.name for f in dataclasses.fields(a) if isinstance(getattr(a, f.name), np.ndarray)
        ]
        return all(same_bits(getattr(a, k), getattr(b, k)) for k in arrays)
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.tobytes() == b.tobytes()


def cases(robot, code: dict, rng: np.random.Generator):
    """Yield (figure, N, {"before"/"now": a call}) timed against the code before.

    ``code``: per "before"/"now", its (gravity, kinematics) modules.
    """
    names = list(robot.parameters)
    base = robot.nominal
    model = robot.model({"th2": 0.3, "a2": 0.2})
    dh = np.asarray(model.dh, dtype=float)
    weight, masses = gravity.wrist_weight(6), gravity.default_masses(dh)
    for N in (1, 2, 5, 10, 50, 100, 1000, 8192):
        q = rng.uniform(-np.pi, np.pi, (N, 6))
        per_row = dh + rng.normal(0.0, 1e-3, (N, 6, 4))
        f = kinematics.rigid_frames(model, q)
        values = rng.normal(0.0, 1e-3, (N, len(names)))
        for figure, module, function, args in (  # module: 0 gravity, 1 kinematics
            ("chain", 1, "_chain", (dh, q)),
            ("chain, N x table", 1, "_chain", (per_row, q)),
            ("tool_jacobian from frames", 1, "tool_jacobian", (model, q, names, f)),
            ("gravity, wrist weight", 0, "gravity_torques_nm", (weight, f.x, f.z, f.o)),
            ("gravity, link masses", 0, "gravity_torques_nm", (masses, f.x, f.z, f.o)),
            ("with_errors, N x table", 1, "with_errors", (base, names, values)),
        ):
            yield (
                figure,
                N,
                {who: partial(getattr(code[who][module], function), *args) for who in code},
            )
    yield (
        "with_errors",
        1,
        {who: partial(code[who][1].with_errors, base, names, values[0]) for who in code},
    )


def before_figures(ref: str, rounds: int) -> None:
    """Print the CPU per call now and before, by N, and the ratio (module docstring)."""
    robot = load_robot(ROBOT)
    with tempfile.TemporaryDirectory() as tmp:
        code = {"before": code_before(ref, Path(tmp)), "now": (gravity, kinematics)}
    print(f"\nCPU per call (us), median of {rounds} interleaved rounds; before: {ref}")
    print(f"  {'figure':28s} {'N':>5s} {'before':>9s} {'now':>9s}  ratio  same bits")
    for figure, N, calls in cases(robot, code, np.random.default_rng(0)):
        same = same_bits(calls["before"](), calls["now"]())
        times: dict[str, list[float]] = {"before": [], "now": []}
        for _ in range(rounds):
            for who in ("before", "now"):
                times[who].append(cpu_per_call_us(calls[who]))
        b, n = np.median(times["before"]), np.median(times["now"])
        print(f"  {figure:28s} {N:5d} {b:9.1f} {n:9.1f}  {n / b:5.2f}  {'yes' if same else 'NO'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--before", default="main", help="git revision of the code before")
    ap.add_argument("--rounds", type=int, default=5, help="interleaved rounds per figure")
    ap.add_argument("--no-naive", action="store_true", help="skip the naive loop's figures")
    args = ap.parse_args()
    if not args.no_naive:
        naive_figures()
    before_figures(args.before, args.rounds)


if __name__ == "__main__":
    main()
