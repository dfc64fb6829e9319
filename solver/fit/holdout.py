"""Held-out validation of a cable-length fit, beside the quantisation floor.

The fit's parameters, sessions and outliers are those of the fit on every row; each split
refits the parameters (plain least squares from the full fit's estimate) on its training
rows and predicts the lengths of its held-out rows. Schemes:

* ``random:F`` — a random share F of the inlier rows held out, ``repeats`` times;
* ``half`` — the first half of the rows trains, the second half is held out (once);
* ``none`` — no validation.

Two rules keep the held-out figure out-of-sample (:func:`splits`): **a held-out row never
trains** — rows at the same joints (copies, repeated readings) form one group, and a group
is held out or trains as a whole (``half``: with its first row); and **a split trains on at
least twice as many rows as the fit has parameters** (:data:`MIN_ROWS_PER_PARAMETER`), else
the refit follows its own rows' noise and the figure reads below the floor
(:func:`check_training`).

A session with no training row (``half`` with a re-mount in the second half) cannot be
predicted: its offset is taken from its held-out rows' median (one number per session, said
in the notes). The figures pool every held-out row of every repeat: RMS, mean absolute and
largest |model − measured|, and the **quantisation floor** — the RMS over the same rows of
the σ that rounding the joints and the length alone gives
(:func:`~wirecal.solver.fit.model.quantisation_floor`) — and their ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.model import Layout, length_joint_gradient, quantisation_floor
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


MIN_ROWS_PER_PARAMETER = 2
"""A split's training rows per fitted parameter, at least (module docstring)."""


def first_same(values: np.ndarray) -> np.ndarray:
    """Return each row's group: the first row (0-based) with exactly the same values."""
    _, first, inverse = np.unique(values, axis=0, return_index=True, return_inverse=True)
    return first[inverse.ravel()]


def copies(q: np.ndarray, length_mm: np.ndarray) -> tuple[tuple[int, int], ...]:
    """Return (row, the earlier row it copies) of each row repeating joints and length.

    A copy adds no information (the fit leaves it out) and, held out, tests a training row.
    """
    first = first_same(np.column_stack([q, length_mm]))
    return tuple((int(r), int(f)) for r, f in enumerate(first) if f != r)


def splits(
    scheme: str, share: float, inliers: np.ndarray, group: np.ndarray, repeats: int, seed: int
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Return (training rows, held-out rows) of each split, inlier rows only.

    ``group`` (N,): each row's group (:func:`first_same` of the joints); a group never
    straddles a split (module docstring). ``random:F`` holds out a share F of the groups.
    """
    rows = np.flatnonzero(inliers)
    if scheme == "none":
        return []
    if scheme == "half":
        held = group[rows] >= len(inliers) // 2  # each row with its group's first row
        return [(rows[~held], rows[held])]
    groups = np.unique(group[rows])
    rng = np.random.default_rng(seed)
    k = max(1, round(share * len(groups)))
    out = []
    for _ in range(repeats):
        held = np.isin(group[rows], rng.permutation(groups)[:k])
        out.append((rows[~held], rows[held]))
    return out


def check_training(scheme: str, n_train: int, n_inliers: int, n_parameters: int) -> None:
    """Refuse a split with fewer than twice as many training rows as parameters."""
    need = MIN_ROWS_PER_PARAMETER * n_parameters
    if n_train >= need:
        return
    most = (n_inliers - need) / n_inliers if n_inliers else 0.0
    fix = (
        f"hold out at most a share {np.floor(most * 100) / 100:.2f} (--holdout random:F)"
        if most >= 0.01
        else "the table has too few rows to hold any out: add rows or pass --holdout none"
    )
    raise WirecalError(
        f"--holdout {scheme}: a split trains on {n_train} rows for {n_parameters} parameters; "
        f"a held-out figure needs at least {need} training rows (twice the parameters), "
        f"else it reads the training rows' own noise: {fix}"
    )


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
