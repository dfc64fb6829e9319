"""Run ``wirecal lint`` on files written into a test's folder (shared by the lint tests)."""

from __future__ import annotations

from pathlib import Path

from click.testing import CliRunner, Result

from wirecal.cli.main import main


def lint(tmp_path: Path, *files: tuple[str, str], args: tuple[str, ...] = ()) -> Result:
    """Write each (name, text) into ``tmp_path`` and lint them together with ``args``."""
    paths = []
    for name, text in files:
        (tmp_path / name).write_text(text)
        paths.append(str(tmp_path / name))
    return CliRunner().invoke(main, ["lint", *args, *paths])
