"""The demo's figures: the whole chain in the twin for several seeds (true errors within
±1 deg/mm, unmodelled errors on), before/after reductions and timings; writes the two
validation histograms of the first seed to docs/ for the README.

    python bench/bench_demo.py [--seeds 3]
"""

from __future__ import annotations

import argparse
import base64
import tempfile
from pathlib import Path

import numpy as np

from wirecal.app.demo import run_demo
from wirecal.app.progress import ProgressBar
from wirecal.app.report import histogram_figure

DOCS = Path(__file__).resolve().parents[1] / "docs"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    rows = []
    for seed in range(1, args.seeds + 1):
        with tempfile.TemporaryDirectory() as tmp, ProgressBar(f"demo, seed {seed}") as bar:
            r = run_demo(Path(tmp), seed=seed, progress=bar.stages())
        cfg, pln = r.validations
        rows.append((seed, cfg, pln, r.tool_error_mm, r.total_s))
        print(
            f"seed {seed}: configuration {cfg.before.mean:.3f} → {cfg.after.mean:.4f} mm "
            f"({100 * cfg.reduction['mean']:.0f} %), plane {pln.before.mean:.4f} → "
            f"{pln.after.mean:.4f} mm ({100 * pln.reduction['mean']:.0f} %), tool point "
            f"{r.tool_error_mm['before']:.3f} → {r.tool_error_mm['after']:.4f} mm; "
            f"{r.total_s:.0f} s (" + ", ".join(f"{k} {v:.1f}" for k, v in r.seconds.items()) + ")"
        )
        if seed == 1:
            DOCS.mkdir(exist_ok=True)
            for v in r.validations:
                uri = histogram_figure(v)
                (DOCS / f"validation_{v.kind}.png").write_bytes(
                    base64.b64decode(uri.split(",", 1)[1])
                )
    red_c = [100 * c.reduction["mean"] for _, c, _, _, _ in rows]
    red_p = [100 * p.reduction["mean"] for _, _, p, _, _ in rows]
    print(
        f"reduction of the mean, configuration change: min {min(red_c):.0f} %, "
        f"mean {np.mean(red_c):.0f} % (target 80 %, paper 84 %)"
    )
    print(
        f"reduction of the mean, plane fit: min {min(red_p):.0f} %, "
        f"mean {np.mean(red_p):.0f} % (target 70 %, paper 77 %)"
    )
    print(f"demo time, start to end: max {max(r[4] for r in rows):.0f} s (target 15 s)")


if __name__ == "__main__":
    main()
