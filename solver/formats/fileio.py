"""Writing output files safely: atomically, and never over an existing file unless asked."""

from __future__ import annotations

import os
import tempfile
import tomllib
from pathlib import Path
from typing import Any

from wirecal.solver.errors import WirecalError


def check_writable(paths: list[Path], force: bool = False) -> None:
    """Refuse, before anything is written, if an output exists (unless ``force``) or its
    folder is missing; all problems at once."""
    problems = []
    for path in map(Path, paths):
        if path.exists() and not force:
            problems.append(f"{path}: exists; choose another name or pass --force to replace it")
        elif not path.parent.is_dir():
            problems.append(f"{path}: folder {path.parent} does not exist")
    if problems:
        raise WirecalError(problems)


def write_atomic(path: str | Path, text: str, *, force: bool = False) -> Path:
    """Write ``text`` to ``path`` via a temporary file and rename, so a reader never sees
    half a file. Refuse to replace an existing file unless ``force``."""
    path = Path(path)
    check_writable([path], force)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """Parse a TOML input file; any problem is a :class:`WirecalError` naming the file."""
    path = Path(path)
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise WirecalError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise WirecalError(
            f"{path}: not UTF-8 text (byte {exc.start}); is this a {what}?"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise WirecalError(f"{path}: not valid TOML: {exc}") from None
