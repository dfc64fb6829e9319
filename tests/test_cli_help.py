"""Every command answers --help with a description and its options; --version works; the
command line starts without importing what no command needs yet."""

from __future__ import annotations

import subprocess
import sys

import click
import pytest
from click.testing import CliRunner

from wirecal import __version__
from wirecal.cli.main import main

CTX = click.Context(main)
COMMANDS = main.list_commands(CTX)


def test_the_commands_are_all_there():
    assert COMMANDS == [
        "demo",
        "export-urdf",
        "fit",
        "gen",
        "import-urdf",
        "lint",
        "observe",
        "plan",
        "psi",
        "receive",
        "report",
        "simulate",
        "solve",
        "validate",
    ]


@pytest.mark.parametrize("command", COMMANDS)
def test_help(command):
    r = CliRunner().invoke(main, [command, "--help"])
    assert r.exit_code == 0
    assert r.output.startswith(f"Usage: main {command}") or "Usage:" in r.output
    cmd = main.get_command(CTX, command)
    assert cmd.help
    assert len(cmd.help.split()) >= 15, f"{command}: describe what it does"
    for param in cmd.params:
        if param.param_type_name == "option" and not param.hidden:
            assert param.help, f"{command} --{param.name} has no help"


@pytest.mark.parametrize("command", COMMANDS)
def test_listed_summary_is_the_commands_own(command):
    """``wirecal --help`` lists each command without importing it: its summary must be
    what the command's docstring says."""
    summary = main.lazy[command][1]
    assert summary == main.get_command(CTX, command).get_short_help_str(10_000)


def test_version():
    r = CliRunner().invoke(main, ["--version"])
    assert r.exit_code == 0
    assert r.output == f"wirecal, version {__version__}\n"


def test_importing_the_cli_imports_no_heavy_package(tmp_path):
    """``wirecal --help`` costs little more than importing click: no matplotlib, lark,
    jinja2, numpy or scipy until a command needs them."""
    code = (
        "import sys\n"
        "import wirecal, wirecal.cli.main\n"
        "heavy = ('matplotlib', 'lark', 'jinja2', 'numpy', 'scipy')\n"
        "print(' '.join(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout.strip() == ""


def test_solve_imports_neither_the_twin_nor_matplotlib(tmp_path):
    code = (
        "import sys\n"
        "from wirecal.cli.main import main\n"
        "import click\n"
        "main.get_command(click.Context(main), 'solve')\n"
        "heavy = ('matplotlib', 'lark', 'jinja2')\n"
        "print(' '.join(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout.strip() == ""
