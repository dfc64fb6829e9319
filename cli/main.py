"""The ``wirecal`` command: entry point and shared option handling.

Every command has a Python API twin (see :mod:`wirecal`); the commands only parse
options, call it, and print. A :class:`WirecalError` is printed as ``error: …`` lines on
stderr, never as a traceback. Exit statuses: 0 done; 1 a run or program stopped, or a check
asked for failed (``psi --strict``); 2 bad input — a file, option or log to fix (click's own
usage errors too); 3 the plausibility gate refused an identification
(:class:`~wirecal.solver.errors.Implausible`).

The commands are registered below, each by the module that defines it, and imported only
when that command runs or its help is shown: ``wirecal --help`` imports click alone, and a
command imports only what it uses (matplotlib for the report and the demo only).
``wirecal CMD --help`` prints the command's help from :data:`~wirecal.cli.help_text.HELP_TEXT`
(rendered from the commands themselves, kept current by ``tests/test_cli_help.py``), so it
imports nothing beyond click either.
"""

from __future__ import annotations

import atexit
import functools
import gc
import importlib
import json
import os
import sys
from typing import Any

# wirecal's matrices are small (tens of columns; at most a few thousand rows): BLAS threads
# cost more than they give — fit on 1000 rows 0.8 s with one thread, 10 s with the default
# threads on two busy cores; solve 0.8 vs 0.9 s, plan 10.5 vs 11.7 s on a quiet one, the same
# plan. Set before numpy is first imported (the commands import it lazily); a value the user
# set is kept.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

GC_THRESHOLD = (50_000, 20, 20)
"""The cyclic garbage collector's thresholds for every command (Python's are 700, 10, 10).

Importing numpy and scipy alone sets off over a hundred collections, and leaves some 50,000
objects that each full collection walks again (9–20 ms on this machine); wirecal's arrays
make few reference cycles, so collecting rarely costs little memory. ``wirecal solve``: about
25 ms less, one full collection fewer (its lazy import of scipy.optimize set one off). The
start-up bench runs its bare imports with the same setting.
"""
gc.set_threshold(*GC_THRESHOLD)
# At the interpreter's exit (the last handler, being registered first) nothing alive is
# collected any more: Python's finalisation walks every object still alive for garbage (the
# demo's 280,000: 0.2–0.4 s of its 5 s wall). The process ends next and the commands close
# their own files (every output is written inside a ``with``), so that is the OS's work.
atexit.register(gc.freeze)

import click  # noqa: E402 - after the thread settings

from wirecal.cli.interrupt import ignore_after_end, quiet_start, stop_cleanly  # noqa: E402

with quiet_start():  # Ctrl-C while starting: no traceback
    from wirecal import __version__
    from wirecal.cli.help_text import HELP_TEXT
    from wirecal.solver.errors import WirecalError, first_problems

MAX_ERROR_LINES = 40
"""Most ``error:`` lines a command prints; a count stands for the rest."""


def user_errors(func):
    """Turn :class:`WirecalError` (and any stray ``OSError``) into ``error: …`` lines.

    And its exit status (2, or 3 for :class:`~wirecal.solver.errors.Implausible`).
    """

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        try:
            with stop_cleanly():
                return func(*args, **kwargs)
        except WirecalError as exc:
            problems, status = exc.problems, exc.exit_status
        except BrokenPipeError:  # the reader (| head) has what it wants: not an error
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())  # the exit's flush writes nowhere
            sys.exit(0)
        except OSError as exc:
            problems, status = [f"{exc.filename or 'file'}: {exc.strerror or exc}"], 2
        for line in first_problems(problems, MAX_ERROR_LINES):
            click.echo(f"error: {line}", err=True)
        sys.exit(status)

    return wrapper


def print_json(data: Any) -> None:
    """Print ``data`` as indented JSON (UTF-8 kept) on standard output."""
    click.echo(json.dumps(data, indent=2, ensure_ascii=False))


class LazyGroup(click.Group):
    """A group whose commands live in modules imported on first use.

    ``lazy`` maps a command name to its ``module:attribute`` and the one-line summary that
    ``--help`` lists (the first sentence of the command's docstring; a test keeps the two
    equal). Looking a command up imports its module and adds the command with
    :meth:`add_command`.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.lazy: dict[str, tuple[str, str]] = {}

    def main(self, args: Any = None, *rest: Any, **kwargs: Any) -> Any:
        """Run the command line; once it has ended, a signal is ignored (:func:`ignore_after_end`).

        Only for the process's own command line (``args`` None): a test's runner passes its
        arguments and keeps its signals.
        """
        try:
            return super().main(args, *rest, **kwargs)
        finally:
            if args is None:
                ignore_after_end()

    def add_lazy_command(self, name: str, target: str, summary: str) -> None:
        """Register ``name`` as ``module:attribute`` to import when run, with its summary."""
        self.lazy[name] = (target, summary)

    def list_commands(self, ctx: click.Context) -> list[str]:
        """Return every command name, loaded or lazy, sorted."""
        return sorted({*self.commands, *self.lazy})

    def resolve_command(
        self, ctx: click.Context, args: list[str]
    ) -> tuple[str | None, click.Command | None, list[str]]:
        """Answer ``wirecal CMD --help`` from :data:`HELP_TEXT`, without importing CMD.

        Only the exact form ``CMD --help`` (or ``-h``) of a command not yet loaded is
        answered from the table; anything else (or a command the table lacks) loads it.
        """
        name, rest = args[0], args[1:]
        if rest in (["--help"], ["-h"]) and name not in self.commands and name in HELP_TEXT:
            text = HELP_TEXT[name]
            return name, click.Command(name, callback=lambda: click.echo(text, nl=False)), []
        return super().resolve_command(ctx, args)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        """Return the command, importing a lazy one on first use."""
        if cmd_name not in self.commands and cmd_name in self.lazy:
            module, _, attribute = self.lazy[cmd_name][0].partition(":")
            with quiet_start():  # importing numpy, scipy, matplotlib: Ctrl-C ends it quietly
                self.add_command(getattr(importlib.import_module(module), attribute), cmd_name)
        return self.commands.get(cmd_name)

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """Write the command list from the summaries, without importing any command."""
        names = self.list_commands(ctx)
        if not names:
            return
        limit = formatter.width - 6 - max(len(n) for n in names)
        rows = []
        for name in names:
            if name in self.commands:
                rows.append((name, self.commands[name].get_short_help_str(limit)))
            else:
                rows.append(
                    (name, click.Command(name, help=self.lazy[name][1]).get_short_help_str(limit))
                )
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="wirecal")
def main() -> None:
    """Kinematic calibration of robot arms with a single draw-wire encoder.

    Implements the step-by-step procedure of Boschetti & Sinico: choose the encoder
    location θ0 and point sets where the wire-length error depends on one parameter
    at a time (the Ψ analysis), measure, and identify the parameters one by one.
    Angles are in degrees, lengths in mm. Start with:

        wirecal psi examples/viper_s650/robot.toml examples/viper_s650/paper_plan.toml

    Exit status: 0 done; 1 a run or program stopped, or a check asked for failed;
    2 bad input (a file, option or log to fix: the error lines say which); 3 the
    plausibility gate refused the identification (nothing written).
    """


for _name, _target, _summary in (
    (
        "demo",
        "wirecal.cli.demo:demo",
        "Calibrate a simulated robot end to end, before and after.",
    ),
    (
        "fit",
        "wirecal.cli.fit:fit",
        "Calibrate ROBOT from a TABLE of joint angles and cable lengths taken without wirecal.",
    ),
    (
        "gen",
        "wirecal.cli.gen:gen",
        "Write the controller programs that run PLAN: V+/eV+, URScript or ABB RAPID.",
    ),
    (
        "export-urdf",
        "wirecal.cli.urdf:export_urdf",
        "Write the robot, calibrated by PATCH if given, as a URDF.",
    ),
    (
        "import-urdf",
        "wirecal.cli.urdf:import_urdf",
        "Write a robot file in Craig's modified DH from a URDF's chain BASE → TIP.",
    ),
    (
        "lint",
        "wirecal.cli.lint:lint",
        "Check program files as the controller would load them, together as one program.",
    ),
    (
        "observe",
        "wirecal.cli.psi:observe",
        "Which parameters the plan's wire lengths can identify, and how well.",
    ),
    (
        "plan",
        "wirecal.cli.plan:plan",
        "Design a calibration plan for ROBOT's [calibration] parameters.",
    ),
    (
        "psi",
        "wirecal.cli.psi:psi",
        "Ψ of every calibration point, step by step (the paper's Table 4).",
    ),
    (
        "receive",
        "wirecal.cli.receive:receive_cmd",
        "Receive a measurement log from a robot program over TCP.",
    ),
    ("report", "wirecal.cli.report:report", "Write a self-contained HTML report of a calibration."),
    (
        "simulate",
        "wirecal.cli.simulate:simulate",
        "Simulate a measurement run of PLAN on a robot with known errors.",
    ),
    (
        "solve",
        "wirecal.cli.solve:solve",
        "Identify the kinematic errors from a measurement LOG.",
    ),
    (
        "validate",
        "wirecal.cli.validate:validate",
        "Compute the validation metric of a log from wc.vcfg or wc.vpln (paper §3.6).",
    ),
):
    main.add_lazy_command(_name, _target, _summary)


if __name__ == "__main__":  # pragma: no cover - python -m wirecal.cli.main
    main()
