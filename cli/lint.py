"""``wirecal lint``: check V+ files as the controller's LOAD would, and URScript files."""

from __future__ import annotations

import sys

import click

from wirecal.cli.main import user_errors
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.fileio import read_input
from wirecal.twin.urscript.parser import parse_program
from wirecal.twin.vplus.parser import parse_module


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--external-calls",
    is_flag=True,
    help="Allow CALLs to programs that are not in the file (loaded from another file).",
)
@user_errors
def lint(files, external_calls):
    """Check V+ program files as a controller's LOAD would, and URScript (.script) files.

    V+ files, ours or anyone's, against the V+ rules LOAD applies: program format, keywords
    as names (User's Guide p. 99), declarations first, 15-character names, type prefixes,
    labels, CALL arguments. A file named *.script is URScript, checked against the rules of
    a script sent to a UR controller (def/end in the first column, other lines indented),
    its syntax, the functions it calls and their arguments, and variables never assigned.

    Prints one "file:line: problem" line per problem. CRLF and LF line endings are both
    read.

    Exit status: 0 every file clean; 1 problems found; 2 a file cannot be read.
    """
    texts = {path: read_input(path, "program file")[0].decode("latin-1") for path in files}
    problems = 0
    for path, text in texts.items():
        try:
            if path.lower().endswith(".script"):
                functions = len(parse_program(text, path).functions)
                what = f"URScript, {functions} function{'s' if functions != 1 else ''}"
            else:
                module = parse_module(text, path, external_calls=external_calls)
                what = f"{len(module.programs)} programs"
        except WirecalError as exc:
            for line in exc.problems:
                click.echo(line)
            problems += len(exc.problems)
            continue
        click.echo(f"{path}: {what}, no problems", err=True)
    if problems:
        click.echo(f"error: {problems} problem{'s' if problems != 1 else ''} found", err=True)
        sys.exit(1)
