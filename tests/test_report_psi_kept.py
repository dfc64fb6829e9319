"""The report's Ψ figure kept by what it shows: drawn once for the runs of one plan.

Every run of one plan has the same Ψ (issue 34: the tests report run after run of the
paper plan), so :func:`~wirecal.app.report.psi_figure` keeps its PNG by the digest of the
|Ψ|, the steps, the plan's order and the names it draws. Here the drawing is counted (a
stand-in for matplotlib's): a result with the same contents is not drawn again (nor one
whose Ψ differs in signs alone: the figure shows |Ψ|), and one that differs in any of
them, by as little as one bit, is.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from wirecal.app import report
from wirecal.solver.memo import Kept


@pytest.fixture
def drawn(monkeypatch) -> list[tuple]:
    """The drawings asked for (their inputs), each returning a PNG named by its count."""
    calls: list[tuple] = []

    def draw(psi, step, order, names) -> str:
        calls.append((psi.copy(), step.copy(), tuple(order), tuple(names)))
        return f"data:image/png;base64,figure{len(calls)}"

    monkeypatch.setattr(report, "_psi_png", draw)
    monkeypatch.setattr(report, "_PSI_FIGURES", Kept(8))
    return calls


def _result(psi=None, step=(1, 1, 2, 2, 2), order=("th2", "a2"), names=("th2", "a2")):
    psi = np.arange(10.0).reshape(5, 2) - 4.5 if psi is None else psi
    return SimpleNamespace(
        psi=psi, step=np.array(step), plan=SimpleNamespace(order=order), names=names
    )


def test_another_run_of_the_plan_shows_the_figure_drawn_for_the_first(drawn):
    first = report.psi_figure(_result())
    again = report.psi_figure(_result())  # other objects, the same contents
    signs = report.psi_figure(_result(psi=4.5 - np.arange(10.0).reshape(5, 2)))
    assert first == again == signs == "data:image/png;base64,figure1"
    assert len(drawn) == 1
    psi, step, order, names = drawn[0]
    assert np.array_equal(psi, np.abs(np.arange(10.0).reshape(5, 2) - 4.5))
    assert step.tolist() == [1, 1, 2, 2, 2]
    assert (order, names) == (("th2", "a2"), ("th2", "a2"))


@pytest.mark.parametrize(
    "other",
    [
        {"psi": np.nextafter(np.arange(10.0).reshape(5, 2) - 4.5, 9.0)},  # one ulp each
        {"psi": np.arange(10.0).reshape(5, 2) - 4.0},  # one |Ψ| the same, the others not
        {"step": (1, 1, 1, 2, 2)},
        {"order": ("a2", "th2")},
        {"names": ("th2", "a3")},
    ],
    ids=["psi-ulp", "psi", "step", "order", "names"],
)
def test_a_figure_of_other_contents_is_drawn_anew(drawn, other):
    assert report.psi_figure(_result()) == "data:image/png;base64,figure1"
    assert report.psi_figure(_result(**other)) == "data:image/png;base64,figure2"
    assert len(drawn) == 2
    assert report.psi_figure(_result()) == "data:image/png;base64,figure1"  # still kept
    assert len(drawn) == 2
