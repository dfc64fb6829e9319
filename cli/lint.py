"""``wirecal lint``: check program files with their language's checker (by file suffix)."""

from __future__ import annotations

import sys

import click

from wirecal.cli.main import user_errors
from wirecal.lang.registry import language_of_file
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import read_input
from wirecal.solver.robot import SOFTWARE_PATTERN


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--external-calls",
    is_flag=True,
    help="Allow CALLs to programs that are not in the file (loaded from another file).",
)
@click.option(
    "--software",
    metavar="VERSION",
    help='URScript: the controller software ("5.20", "3.15"); a call its manual pages do not '
    "document is a problem too.",
)
@user_errors
def lint(files, external_calls, software):
    """Check V+ program files as a controller's LOAD would, and URScript (.script) files.

    V+ files, ours or anyone's, against the V+ rules LOAD applies: program format, keywords
    as names (User's Guide p. 99), declarations first, 15-character names, type prefixes,
    labels (0-65535), CALL arguments, constants within the ranges of pp. 100 and 102. A file
    named *.script is URScript, checked against the rules of a script sent to a UR
    controller (def/sec and end in the first column, other lines indented), the language
    of the Script Manual (poses, threads, critical sections, default arguments), the
    functions it calls and their arguments, int32/float32 constants, encoder indices, and
    variables never assigned. What each rule rests on: docs/languages.md.

    Prints one "file:line: problem" line per problem. CRLF and LF line endings are both
    read.

    Exit status: 0 every file clean; 1 problems found; 2 a file cannot be read.
    """
    if software is not None and not SOFTWARE_PATTERN.fullmatch(software):
        raise WirecalError([f'--software {software!r}: give the version as numbers, e.g. "5.20"'])
    texts = {path: read_input(path, "program file")[0].decode("latin-1") for path in files}
    problems = 0
    for path, text in texts.items():
        lang = language_of_file(path)
        found = lang.lint(text, path, software, external_calls=external_calls)
        for line in found:
            click.echo(line)
        problems += len(found)
        if not found:
            click.echo(f"{path}: {lang.title}, no problems", err=True)
    if problems:
        click.echo(f"error: {problems} problem{'s' if problems != 1 else ''} found", err=True)
        sys.exit(1)
