"""Every command answers --help with a description and its options; --version works."""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from wirecal.cli.main import main

COMMANDS = sorted(main.commands)


def test_the_commands_are_all_there():
    assert COMMANDS == [
        "demo",
        "export-urdf",
        "gen",
        "import-urdf",
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
    doc = main.commands[command].help
    assert doc and len(doc.split()) >= 15, f"{command}: describe what it does"
    for param in main.commands[command].params:
        if param.param_type_name == "option" and not param.hidden:
            assert param.help, f"{command} --{param.name} has no help"


def test_version():
    r = CliRunner().invoke(main, ["--version"])
    assert r.exit_code == 0
    assert r.output.startswith("wirecal, version ")
