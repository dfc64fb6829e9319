"""Every command answers --help with a description and its options; --version works; the
command line starts without importing what no command needs yet."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from wirecal import __version__
from wirecal.cli.help_text import HELP_TEXT
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


def heavy_imported(imports: str, heavy: tuple[str, ...], folder: Path) -> str:
    """Return which of the modules ``heavy`` a fresh Python has loaded after ``imports``."""
    code = f"import sys\n{imports}\nprint(' '.join(m for m in {heavy!r} if m in sys.modules))\n"
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=folder
    )
    return out.stdout.strip()


def command_imports(name: str, modules: str) -> str:
    """Return the imports of the command line loading command ``name``, then ``modules``."""
    return (
        "from wirecal.cli.main import main\nimport click\n"
        f"main.get_command(click.Context(main), {name!r})\nimport {modules}"
    )


def test_importing_the_cli_imports_no_heavy_package(tmp_path):
    """``wirecal --help`` costs little more than importing click: no matplotlib, lark,
    jinja2, numpy or scipy until a command needs them."""
    heavy = ("matplotlib", "lark", "jinja2", "numpy", "scipy")
    assert heavy_imported("import wirecal, wirecal.cli.main", heavy, tmp_path) == ""


def test_solve_imports_neither_the_twin_nor_matplotlib(tmp_path):
    """Nor scipy.stats, which doubled its start-up for one χ² quantile."""
    imports = command_imports("solve", "wirecal.solver.plausibility")
    assert heavy_imported(imports, ("matplotlib", "lark", "jinja2", "scipy.stats"), tmp_path) == ""


def test_plan_imports_no_scipy(tmp_path):
    """``wirecal plan`` needs numpy only: scipy.special alone cost 0.17 s of its CPU."""
    imports = command_imports("plan", "wirecal.solver.plan.planner, wirecal.solver.plan.compliance")
    assert heavy_imported(imports, ("matplotlib", "lark", "jinja2", "scipy"), tmp_path) == ""


HELP_MODULE = Path(__file__).resolve().parents[1] / "cli" / "help_text.py"


def rendered_help(name: str) -> str:
    """What ``wirecal NAME --help`` prints from the command itself, at click's default width."""
    parent = click.Context(
        main, info_name="wirecal", help_option_names=["-h", "--help"], terminal_width=80
    )
    command = main.get_command(CTX, name)
    return command.get_help(click.Context(command, info_name=name, parent=parent)) + "\n"


def string_literal(text: str) -> str:
    """``text`` as a Python literal in ruff format's quotes (double unless that escapes)."""
    if '"' in text and "'" not in text:
        return repr(text)
    return json.dumps(text, ensure_ascii=False)


def help_module_source() -> str:
    lines = [
        '"""The help text of every command, as ``wirecal CMD --help`` prints it.',
        "",
        "Rendered from the commands themselves, so that ``--help`` imports nothing beyond",
        "click. Generated, do not edit: after changing a command's help or options run",
        "``WIRECAL_UPDATE_GOLDEN=1 pytest tests/test_cli_help.py``.",
        '"""',
        "",
        "HELP_TEXT: dict[str, str] = {",
    ]
    for name in COMMANDS:
        lines.append(f'    "{name}": (')
        text = rendered_help(name).splitlines(keepends=True)
        lines += [f"        {string_literal(line)}" for line in text]
        lines.append("    ),")
    lines.append("}")
    return "\n".join(lines) + "\n"


def test_help_table_is_current():
    """``wirecal CMD --help`` prints from the table: it must be what the command says."""
    if os.environ.get("WIRECAL_UPDATE_GOLDEN"):
        HELP_MODULE.write_text(help_module_source(), encoding="utf-8")
        pytest.skip("cli/help_text.py regenerated")
    stale = [name for name in COMMANDS if HELP_TEXT.get(name) != rendered_help(name)]
    assert not stale, (
        f"cli/help_text.py is stale for {stale}: "
        "run WIRECAL_UPDATE_GOLDEN=1 pytest tests/test_cli_help.py"
    )


@pytest.mark.parametrize("command", ["demo", "solve", "report"])
def test_command_help_imports_only_click(command, tmp_path):
    """``wirecal CMD --help`` answers from the table: the same text, nothing heavy imported."""
    code = (
        "import sys\n"
        "from wirecal.cli.main import main\n"
        f"main([{command!r}, '--help'], standalone_mode=False)\n"
        "heavy = ('matplotlib', 'lark', 'jinja2', 'numpy', 'scipy', 'wirecal.app')\n"
        "print('imported:', ' '.join(m for m in heavy if m in sys.modules))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path
    )
    assert out.stdout == rendered_help(command) + "imported: \n"


def test_help_with_other_arguments_loads_the_command():
    """Only the exact form ``CMD --help`` uses the table; other arguments reach the command."""
    r = CliRunner().invoke(main, ["solve", "--help", "--json"])
    assert r.exit_code == 0
    assert "--json" in r.output
