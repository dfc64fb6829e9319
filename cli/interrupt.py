"""Ctrl-C and SIGTERM: a command stops within a second and leaves nothing half-written.

SIGTERM (``kill``, a closed session, a service manager) is turned into :class:`Terminated`,
an exception like Ctrl-C's ``KeyboardInterrupt``: either unwinds through the command's
:class:`~wirecal.solver.formats.fileio.Outputs`, which withdraws every output and removes
its temporary files. Then the process ends at once, by ``os._exit``, without the
interpreter's finalization: a signal arriving while modules are being imported or torn down
can otherwise end it in "Fatal Python error" (seen once in 50 Ctrl-C of ``report``).
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

import click

EXIT_SIGNAL = 128
"""A command ended by signal N exits with status 128 + N, as a shell reports it."""


class Terminated(BaseException):
    """SIGTERM arrived: unwind like Ctrl-C."""


def _terminate(signum: int, frame: FrameType | None) -> None:
    raise Terminated


@contextmanager
def stop_cleanly() -> Iterator[None]:
    """Run a command so that SIGTERM and Ctrl-C unwind it and then end the process at once."""
    try:
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:  # not the main thread: leave the signals alone
        previous = None
    try:
        yield
    except (KeyboardInterrupt, Terminated) as exc:
        number = signal.SIGINT if isinstance(exc, KeyboardInterrupt) else signal.SIGTERM
        click.echo(f"\nstopped ({signal.Signals(number).name}); nothing written", err=True)
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(EXIT_SIGNAL + number)
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
