"""Ctrl-C and SIGTERM: a command stops within a second and leaves nothing half-written.

SIGTERM (``kill``, a closed session, a service manager) is turned into :class:`Terminated`,
an exception like Ctrl-C's ``KeyboardInterrupt``: either unwinds through the command's
:class:`~wirecal.formats.fileio.Outputs`, which withdraws every output and removes
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
from typing import Any, NoReturn

import click

EXIT_SIGNAL = 128
"""A command ended by signal N exits with status 128 + N, as a shell reports it."""


class Terminated(BaseException):
    """SIGTERM arrived: unwind like Ctrl-C."""


_RECEIVED: list[int] = []
"""The signals a running command received (:func:`stop_cleanly`)."""


def _terminate(signum: int, frame: FrameType | None) -> None:
    _RECEIVED.append(signum)
    raise Terminated


def _interrupt(signum: int, frame: FrameType | None) -> None:
    _RECEIVED.append(signum)
    raise KeyboardInterrupt


def exit_stopped(number: int) -> NoReturn:
    """Say that the command stopped on signal ``number`` and end the process at once."""
    click.echo(f"\nstopped ({signal.Signals(number).name}); nothing written", err=True)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(EXIT_SIGNAL + number)


def _exit_at_once(signum: int, frame: FrameType | None) -> None:
    exit_stopped(signum)


@contextmanager
def quiet_start() -> Iterator[None]:
    """While modules are imported (nothing written yet), Ctrl-C ends the process at once.

    Only where Ctrl-C would raise ``KeyboardInterrupt`` (not where it is ignored, as in a
    background job); the handler before is restored after.
    """
    changed = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if changed:
        try:
            signal.signal(signal.SIGINT, _exit_at_once)
        except ValueError:  # not the main thread
            changed = False
    try:
        yield
    finally:
        if changed:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def ignore_after_end() -> None:
    """Ignore Ctrl-C and SIGTERM through the shutdown of an interpreter whose command ended.

    Its outputs are published or withdrawn by then, so a signal can change nothing; caught
    by Python's default handler while modules are torn down it ended the process killed by
    SIGINT, or once in "Fatal Python error … finalizing" (NC09).
    """
    for number in (signal.SIGINT, signal.SIGTERM):
        try:
            signal.signal(number, signal.SIG_IGN)
        except ValueError:  # not the main thread: leave the signals alone
            return


@contextmanager
def stop_cleanly() -> Iterator[None]:
    """Run a command so that SIGTERM and Ctrl-C unwind it and then end the process at once.

    An error that a signal caused is the signal: Ctrl-C while a compiled module initialises
    (a lazy ``import scipy.optimize``) surfaces as ``ImportError: initialization failed``,
    which then ends the command like the Ctrl-C it was, not in a traceback.
    """
    previous = _install({signal.SIGTERM: _terminate, signal.SIGINT: _interrupt})
    try:
        yield
    except (KeyboardInterrupt, Terminated) as exc:
        exit_stopped(signal.SIGINT if isinstance(exc, KeyboardInterrupt) else signal.SIGTERM)
    except Exception:
        if _RECEIVED:
            exit_stopped(_RECEIVED[0])
        raise
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def _install(handlers: dict[int, Any]) -> dict[int, Any]:
    """Install ``handlers`` where Python's own would run; return the handlers replaced.

    SIGINT only where it raises ``KeyboardInterrupt`` (not where it is ignored, as in a
    background job); none outside the main thread.
    """
    previous: dict[int, Any] = {}
    for number, handler in handlers.items():
        current = signal.getsignal(number)
        if number == signal.SIGINT and current is not signal.default_int_handler:
            continue
        try:
            previous[number] = signal.signal(number, handler)
        except ValueError:  # not the main thread: leave the signals alone
            return previous
    return previous
