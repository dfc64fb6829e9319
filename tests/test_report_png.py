"""The report's figures drawn once: ``_png`` writes the PNG of a tight ``savefig``, byte for byte.

``_png`` measures the tight box itself instead of letting ``savefig(bbox_inches="tight")``
draw the figure once more for its layout (issue 34); what it writes must not change. Each
figure here has the parts of one of the report's (an image with a colour bar and row
labels, log-scaled bars with rotated labels and a legend, a histogram with a grid), and is
written both ways.
"""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest

from wirecal.app.report import DPI, _png, _pyplot


def _image(plt):
    fig, ax = plt.subplots(figsize=(5, 4.3))
    im = ax.imshow(np.linspace(-1, 1, 49).reshape(7, 7), cmap="coolwarm", vmin=-1, vmax=1)
    ax.axhline(2.5, color="white", lw=1.5)
    ax.set_yticks([1, 4], ["step 1: th2", "step 2: a2"])
    ax.set_title("|Ψ| of every calibration point (mm/deg, mm/mm)")
    fig.colorbar(im, ax=ax, shrink=0.8)
    return fig


def _bars(plt):
    fig, ax = plt.subplots(figsize=(7, 3))
    x = np.arange(4)
    ax.bar(x - 0.2, [3.0, 0.2, 0.05, 0.01], 0.4, label="before")
    ax.bar(x + 0.2, [0.1, 0.02, 0.004, 0.003], 0.4, label="after")
    ax.set_yscale("log")
    ax.set_xticks(x, ["1: th2", "2: a2", "3: th3", "4: d4"], rotation=30)
    ax.legend()
    return fig


def _histogram(plt):
    fig, ax = plt.subplots(figsize=(7, 3.2))
    values = np.random.default_rng(1).gamma(2.0, 0.2, 40)
    ax.hist(values, bins=np.linspace(0, values.max() * 1.02, 34).tolist(), alpha=0.75, label="x")
    ax.set_xlabel("Maximum discrepancy among configurations (mm)")
    ax.legend()
    ax.grid(alpha=0.3)
    return fig


@pytest.mark.parametrize("figure", [_image, _bars, _histogram])
def test_a_figure_is_the_png_of_a_tight_savefig(figure):
    plt = _pyplot()
    buf = io.BytesIO()
    tight = figure(plt)
    tight.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    plt.close(tight)
    uri = _png(figure(plt))
    assert uri.startswith("data:image/png;base64,")
    assert base64.b64decode(uri.split(",", 1)[1]) == buf.getvalue()
