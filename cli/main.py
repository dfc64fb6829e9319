"""The ``wirecal`` command: entry point and shared option handling.

Every command has a Python API twin in :mod:`wirecal.solver` or :mod:`wirecal.gen`;
the commands only parse options, call it, and print. A :class:`WirecalError` is printed
as ``error: …`` lines on stderr, never as a traceback. Exit statuses: 0 done; 1 a run or
program stopped, or a check asked for failed (``psi --strict``); 2 bad input — a file,
option or log to fix (click's own usage errors too); 3 the plausibility gate refused
an identification (:class:`~wirecal.solver.errors.Implausible`).
"""

from __future__ import annotations

import functools
import json
import sys
from importlib.metadata import PackageNotFoundError, version
from typing import Any

import click

from wirecal.solver.errors import WirecalError


def _version() -> str:
    try:
        return version("wirecal")
    except PackageNotFoundError:  # pragma: no cover - only in an uninstalled checkout
        return "unknown"


def user_errors(func):
    """Turn :class:`WirecalError` (and any stray ``OSError``) into ``error: …`` lines and
    its exit status (2, or 3 for :class:`~wirecal.solver.errors.Implausible`)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            return func(*args, **kwargs)
        except WirecalError as exc:
            problems, status = exc.problems, exc.exit_status
        except OSError as exc:
            problems, status = [f"{exc.filename or 'file'}: {exc.strerror or exc}"], 2
        for line in problems:
            click.echo(f"error: {line}", err=True)
        sys.exit(status)

    return wrapper


def print_json(data: Any) -> None:
    click.echo(json.dumps(data, indent=2, ensure_ascii=False))


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(_version(), "--version", prog_name="wirecal")
def main() -> None:
    """Kinematic calibration of robot arms with a single draw-wire encoder.

    Implements the step-by-step procedure of Boschetti & Sinico: choose the encoder
    location θ0 and point sets where the wire-length error depends on one parameter
    at a time (the Ψ analysis), measure, and identify the parameters one by one.
    Angles are in degrees, lengths in mm. Start with:

        wirecal psi examples/viper_s650/robot.toml examples/viper_s650/paper_plan.toml

    Exit status: 0 done; 1 a run or program stopped, or a check asked for failed;
    2 bad input (a file, option or log to fix: the error lines say which).
    """


# Commands register themselves on import.
from wirecal.cli import demo as _demo  # noqa: E402,F401
from wirecal.cli import gen as _gen  # noqa: E402,F401
from wirecal.cli import identify as _identify  # noqa: E402,F401
from wirecal.cli import plan as _plan  # noqa: E402,F401
from wirecal.cli import psi as _psi  # noqa: E402,F401
from wirecal.cli import receive as _receive  # noqa: E402,F401
from wirecal.cli import report as _report  # noqa: E402,F401
from wirecal.cli import urdf as _urdf  # noqa: E402,F401
from wirecal.cli import validate as _validate  # noqa: E402,F401
