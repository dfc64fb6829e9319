"""A progress bar on standard error, drawn only when standard error is a terminal.

One bar for every long-running command (``wirecal plan``, ``wirecal demo``) and the bench
scripts. In a pipe, a CI log or a test's captured output nothing is written at all, so
the output of a command is the same with or without it.

    with ProgressBar("planning") as bar:
        bar.update(0.5)            # a fraction of the work done, 0…1
        bar.echo("a line")         # printed on stdout above the bar
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from typing import TextIO

_STAGE = re.compile(r"\[(\d+)/(\d+)\]")
WIDTH = 30  # characters of the bar itself
LABEL = 44  # characters of the label (cut, or padded)


class ProgressBar:
    """A one-line bar on ``stream`` (standard error), redrawn as the work advances.

    Silent unless ``stream.isatty()``. ``update`` takes the fraction done (0…1) and an
    optional new label; the line is redrawn only when the shown percentage or the label
    changes. Leaving the ``with`` block clears the line.
    """

    def __init__(self, label: str, stream: TextIO | None = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(getattr(self.stream, "isatty", lambda: False)())
        self.label = label
        self.shown: tuple[int, str] | None = None
        self.fraction = 0.0

    def __enter__(self) -> ProgressBar:
        """Draw the empty bar."""
        self.update(0.0)
        return self

    def __exit__(self, *exc: object) -> None:
        """Clear the bar's line."""
        self.clear()

    def update(self, fraction: float, label: str | None = None) -> None:
        """Show ``fraction`` (0…1) of the work done, under ``label`` when given."""
        self.fraction = min(max(float(fraction), 0.0), 1.0)
        if label is not None:
            self.label = label
        if not self.enabled:
            return
        pct = int(100 * self.fraction)
        if self.shown == (pct, self.label):
            return
        self.shown = (pct, self.label)
        done = round(WIDTH * self.fraction)
        text = f"{self.label[:LABEL]:<{LABEL}} [{'#' * done}{'.' * (WIDTH - done)}] {pct:3d}%"
        self.stream.write("\r" + text)
        self.stream.flush()

    def clear(self) -> None:
        """Remove the bar from the terminal (a later ``update`` draws it again)."""
        if self.enabled and self.shown is not None:
            self.stream.write("\r" + " " * (LABEL + WIDTH + 8) + "\r")
            self.stream.flush()
            self.shown = None

    def echo(self, line: str, out: TextIO | None = None) -> None:
        """Print ``line`` on ``out`` (standard output) without breaking the bar."""
        self.clear()
        print(line, file=sys.stdout if out is None else out, flush=True)
        self.update(self.fraction)

    def stages(self, echo: bool = False) -> Callable[[str], None]:
        """Return a callback for a workflow's stage lines, "[n/N] text …" (``run_demo``'s).

        A line starts stage n of N: the bar shows (n − 1)/N under the line's text; with
        ``echo`` the line is printed too (a line without the prefix only printed).
        """

        def stage(line: str) -> None:
            if echo:
                self.echo(line)
            m = _STAGE.match(line)
            if m:
                n, total = int(m.group(1)), int(m.group(2))
                self.update((n - 1) / total, line.split(" …")[0])

        return stage
