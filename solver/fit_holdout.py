"""Held-out validation of a cable-length fit, beside the quantisation floor.

The fit's parameters, sessions and outliers are those of the fit on every row; each split
refits the parameters (plain least squares from the full fit's estimate) on its training
rows and predicts the lengths of its held-out rows. Schemes:

* ``random:F`` — a random share F of the inlier rows held out, ``repeats`` times;
* ``half`` — the first half of the rows trains, the second half is held out (once);
* ``none`` — no validation.

A session with no training row (``half`` with a re-mount in the second half) cannot be
predicted: its offset is taken from its held-out rows' median (one number per session, said
in the notes). The figures pool every held-out row of every repeat: RMS, mean absolute and
largest |model − measured|, and the **quantisation floor** — the RMS over the same rows of
the σ that rounding the joints and the length alone gives
(:func:`~wirecal.solver.fit_model.quantisation_floor`) — and their ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.fit_model import Layout, length_joint_gradient, quantisation_floor
from wirecal.solver.kinematics import Model


@dataclass(frozen=True)
class Holdout:
    """Held-out figures (mm) and the floor they are compared with."""

    scheme: str
    repeats: int
    rows: int  # held-out rows pooled over the repeats
    rms_mm: float
    mae_mm: float
    max_mm: float
    floor_mm: float
    notes: tuple[str, ...] = ()

    @property
    def ratio(self) -> float:
        """Return the held-out RMS over the floor."""
        return self.rms_mm / self.floor_mm if self.floor_mm > 0 else float("inf")

    def as_json(self) -> dict:
        """Return the figures as a JSON-ready dict (null where nothing was held out)."""
        figures = {
            "rms_mm": self.rms_mm,
            "mae_mm": self.mae_mm,
            "max_mm": self.max_mm,
            "floor_mm": self.floor_mm,
            "ratio": self.ratio,
        }
        return {
            "scheme": self.scheme,
            "repeats": self.repeats,
            "rows": self.rows,
            **{k: float(v) if np.isfinite(v) else None for k, v in figures.items()},
            "notes": list(self.notes),
        }


def parse_scheme(text: str) -> tuple[str, float]:
    """Return ("random", F), ("half", 0.5) or ("none", 0); raise on anything else."""
    t = text.strip()
    if t in ("half", "none"):
        return t, 0.5 if t == "half" else 0.0
    head, sep, tail = t.partition(":")
    try:
        share = float(tail) if head == "random" and sep else float("nan")
    except ValueError:
        share = float("nan")
    if not 0 < share < 1:
        raise WirecalError(
            f"--holdout: {text!r}; give random:F with 0 < F < 1 (e.g. random:0.2), half or none"
        )
    return "random", share


def splits(
    scheme: str, share: float, inliers: np.ndarray, repeats: int, seed: int
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Return (training rows, held-out rows) of each split, inlier rows only."""
    rows = np.flatnonzero(inliers)
    if scheme == "half":
        half = len(inliers) // 2
        return [(rows[rows < half], rows[rows >= half])]
    if scheme == "none":
        return []
    rng = np.random.default_rng(seed)
    k = max(1, round(share * len(rows)))
    out = []
    for _ in range(repeats):
        perm = rng.permutation(rows)
        out.append((np.sort(perm[k:]), np.sort(perm[:k])))
    return out


def row_floor(
    base: Model,
    layout: Layout,
    x: np.ndarray,
    q_rad: np.ndarray,
    joint_res_deg: float,
    length_res_mm: float,
    joint_cov_rad2: np.ndarray | None = None,
) -> np.ndarray:
    """Return each row's quantisation σ (mm) at the model ``x`` (refined joints: their cov)."""
    g = length_joint_gradient(base, layout, x, q_rad)
    return quantisation_floor(g, joint_res_deg, length_res_mm, joint_cov_rad2)


def summarise(
    scheme: str,
    repeats: int,
    residuals: list[np.ndarray],
    floors: list[np.ndarray],
    notes: list[str],
) -> Holdout:
    """Return the pooled figures of the held-out residuals and their rows' floors."""
    r = np.concatenate(residuals) if residuals else np.zeros(0)
    f = np.concatenate(floors) if floors else np.zeros(0)
    if r.size == 0:
        nan = float("nan")
        return Holdout(scheme, 0, 0, nan, nan, nan, nan, tuple(notes))
    return Holdout(
        scheme=scheme,
        repeats=repeats,
        rows=int(r.size),
        rms_mm=float(np.sqrt(np.mean(r**2))),
        mae_mm=float(np.mean(np.abs(r))),
        max_mm=float(np.max(np.abs(r))),
        floor_mm=float(np.sqrt(np.mean(f**2))),
        notes=tuple(dict.fromkeys(notes)),
    )
