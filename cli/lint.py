"""``wirecal lint``: check program files as a controller loads them, each with its language."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from wirecal.cli.main import user_errors
from wirecal.formats.fileio import read_input, refuse_utf16
from wirecal.solver.errors import WirecalError
from wirecal.solver.robot import SOFTWARE_PATTERN

NOT_PROGRAMS = {
    ".toml": "a TOML file (a robot file, plan, patch, truth or validation setup)",
    ".csv": "a CSV file (a log or table)",
    ".urdf": "a URDF",
    ".html": "an HTML file (a report)",
    ".xlsx": "a workbook",
    ".stl": "a mesh",
}
"""Suffixes of the files wirecal reads and writes that are not programs: lint says so
rather than reading one as V+ (a suffix no language has) and listing every line."""


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@click.option(
    "--language",
    "language_key",
    metavar="KEY",
    help="The language of every file (rapid, urscript, vplus) when the suffixes do not say it.",
)
@click.option(
    "--separately",
    is_flag=True,
    help="Check each file alone instead of the files of one language as one program.",
)
@click.option(
    "--external-calls",
    is_flag=True,
    help="Allow calls to routines and programs in none of the files (loaded from elsewhere).",
)
@click.option(
    "--software",
    metavar="VERSION",
    help='The controller software ("5.20", "3.15" for URScript; "6.13" for RAPID); a call '
    "its manual pages do not document is a problem too.",
)
@user_errors
def lint(files, language_key, separately, external_calls, software):
    """Check program files as the controller would load them, together as one program.

    The files of one language form one program: a RAPID task's modules (global data,
    types and routines shared), V+ files sharing programs, a URScript program with the
    files it includes. The language comes from the suffix, or --language:

    RAPID (.mod .modx .sys .sysx .prg) against the RAPID kernel's syntax and the
    reference manual's instructions, functions and data types; URScript (.script
    .urscript) against the Script Manual of the --software version; V+ (.v2 .pg) against
    LOAD's rules in the V+ Language User's Guide v17 (format, keywords, declarations,
    ranges).

    A file with another suffix is read as V+ unless --language says otherwise. Each rule
    cites the page it rests on, or says it is unconfirmed: docs/languages.md,
    docs/rapid.md.

    Prints one "file:line: problem" line per problem. CRLF and LF line endings are both
    read.

    Exit status: 0 every file clean; 1 problems found; 2 a file cannot be read.
    """
    from wirecal.lang.registry import language, language_of_file, language_of_suffix

    if software is not None and not SOFTWARE_PATTERN.fullmatch(software):
        raise WirecalError([f'--software {software!r}: give the version as numbers, e.g. "5.20"'])
    chosen = language(language_key) if language_key is not None else None
    groups: dict[str, dict[str, str]] = {}
    for path in dict.fromkeys(files):
        lang = chosen or language_of_file(path)
        if chosen is None and Path(path).suffix.lower() in NOT_PROGRAMS:
            raise WirecalError(
                f"{path}: {NOT_PROGRAMS[Path(path).suffix.lower()]}, not a program: give the "
                "program files 'wirecal gen' wrote (or --language to read it as one)"
            )
        if chosen is None and language_of_suffix(path) is None:
            click.echo(f"{path}: no language has this suffix: read as {lang.title}", err=True)
        raw, source = read_input(path, "program file")
        refuse_utf16(raw, source, "program file")
        text = raw.decode("latin-1")  # a controller's 8-bit text
        groups.setdefault(lang.key, {})[path] = text
    problems = 0
    for key, texts in groups.items():
        lang = language(key)
        units = [{p: t} for p, t in texts.items()] if separately else [texts]
        found = [
            line
            for unit in units
            for line in lang.lint_files(unit, software, external_calls=external_calls)
        ]
        for line in found:
            click.echo(line)
        problems += len(found)
        for path in texts:
            if not any(line.startswith(f"{path}:") for line in found):
                click.echo(f"{path}: {lang.title}, no problems", err=True)
    if problems:
        click.echo(f"error: {problems} problem{'s' if problems != 1 else ''} found", err=True)
        sys.exit(1)
