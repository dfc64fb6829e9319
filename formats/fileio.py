"""Output files that never lose data, and reading TOML inputs.

A command's outputs are one :class:`Outputs` set: checked and reserved before any work,
written to temporary files beside their final names, then published together — all of
them or none. Publishing a new file is a hard link of its temporary file, which fails if
the name exists: of two runs writing the same name at once exactly one wins, and it never
overwrites a file that appeared meanwhile. Only ``force`` replaces a file (by rename, the
old file's mode kept); an input is never replaced. New files get mode ``0666 & ~umask``,
like any file a shell command creates.
"""

from __future__ import annotations

import errno
import os
import pickle
import re
import shutil
import signal
import sys
import tempfile
import threading
import tomllib
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from types import TracebackType
from typing import Any

import numpy as np

from wirecal.solver.errors import WirecalError

# Filesystems without hard links (FAT on a USB stick, some network shares) answer these.
_NO_LINKS = {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.ENOSYS}


def os_problem(path: str | Path, exc: OSError) -> WirecalError:
    """``path: reason`` for an operating-system failure (full disk, no permission, …)."""
    return WirecalError(f"{path}: {exc.strerror or exc}")


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)
    except OSError:  # one of them does not exist yet
        return a.resolve() == b.resolve()


_DEFERRED = {signal.SIGINT, signal.SIGTERM}


@contextmanager
def _signals_deferred() -> Iterator[None]:
    """Hold Ctrl-C and SIGTERM until the block is done (where the platform can)."""
    mask = getattr(signal, "pthread_sigmask", None)
    if mask is None or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = mask(signal.SIG_BLOCK, _DEFERRED)
    try:
        yield
    finally:
        mask(signal.SIG_SETMASK, old)


class Outputs:
    """A command's output files, published all or none (see the module docstring).

    Use as a context manager around the work that produces the texts::

        with Outputs([log, truth], force=force, inputs=[robot, plan]) as out:
            ...
            out.put(log, log_text)
            out.put(truth, truth_text)

    Entering refuses, all problems at once, an existing output (unless ``force``), a
    missing folder (unless it is ``folder``, which is created and removed again if the
    command fails), a folder given as a file, an output named twice and an output that is
    also an input; then it reserves a temporary file beside each output, so an unwritable
    folder is found before the work. Leaving normally publishes every output that was
    ``put`` (each one must be); leaving by an exception, or a failure while publishing,
    withdraws whatever was published, restores replaced files and removes the temporaries.
    Every ``OSError`` becomes a :class:`WirecalError` naming the output.
    """

    def __init__(
        self,
        paths: Iterable[str | Path],
        *,
        force: bool = False,
        inputs: Iterable[str | Path] = (),
        folder: str | Path | None = None,
    ):
        self.paths = [Path(p) for p in paths]
        self.force = force
        self.inputs = [Path(p) for p in inputs]
        self.folder = Path(folder) if folder is not None else None
        self._created_folder = False
        self._tmp: dict[Path, Path] = {}
        self._text: dict[Path, bytes] = {}

    # -- reserve ---------------------------------------------------------------------
    def __enter__(self) -> Outputs:
        """Check the outputs can be written and reserve them."""
        self.check()
        try:
            if self.folder is not None and not self.folder.exists():
                try:
                    self.folder.mkdir(parents=True)
                except OSError as exc:
                    raise os_problem(self.folder, exc) from None
                self._created_folder = True
            for path in self.paths:
                with _signals_deferred():  # a temporary file is always one of self._tmp
                    try:
                        fd, tmp = tempfile.mkstemp(
                            dir=path.parent, prefix=f".{path.name}.", suffix=".tmp"
                        )
                    except OSError as exc:
                        raise os_problem(path, exc) from None
                    os.close(fd)
                    self._tmp[path] = Path(tmp)
        except BaseException:
            self._discard()
            raise
        return self

    def check(self) -> None:
        """Refuse, all problems at once, outputs that cannot be written (class docstring)."""
        problems = []
        for k, path in enumerate(self.paths):
            if path in self.paths[:k]:
                problems.append(f"{path}: named for two outputs; give each its own name")
                continue
            clash = next((p for p in self.inputs if _same_file(path, p)), None)
            if clash is not None:
                problems.append(
                    f"{path}: is also an input ({clash}); write the output to another name"
                )
            elif path.is_dir():
                problems.append(f"{path}: is a folder; give a file name")
            elif (path.exists() or path.is_symlink()) and not self.force:
                problems.append(
                    f"{path}: exists; choose another name or pass --force to replace it"
                )
            elif not path.parent.is_dir() and path.parent != self.folder:
                problems.append(f"{path}: folder {path.parent} does not exist")
        if self.folder is not None and self.folder.exists() and not self.folder.is_dir():
            problems.append(f"{self.folder}: is a file; give a folder for the outputs")
        if problems:
            raise WirecalError(problems)

    # -- fill ------------------------------------------------------------------------
    def put(self, path: str | Path, text: str) -> Path:
        """Write the text of output ``path`` (UTF-8, LF line ends) to its temporary file."""
        path = Path(path)
        data = text.encode("utf-8")
        try:
            with open(self._tmp[path], "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
        except OSError as exc:
            raise os_problem(path, exc) from None
        self._text[path] = data
        return path

    # -- publish ---------------------------------------------------------------------
    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Publish every output when the block succeeded; otherwise leave nothing behind."""
        try:
            if kind is None:
                missing = [p for p in self.paths if p not in self._text]
                if missing:  # a programming error, not the user's
                    raise RuntimeError(f"outputs never written: {missing}")
                self._publish()
                self._created_folder = False  # it holds the outputs now
        finally:
            self._discard()

    def _publish(self) -> None:
        mode = 0o666 & ~_umask()
        done: list[tuple[Path, Path | None]] = []  # (published path, backup of the old one)
        try:
            for path in self.paths:
                tmp = self._tmp[path]
                try:
                    done.append((path, self._publish_one(path, tmp, mode)))
                except FileExistsError:
                    raise WirecalError(
                        f"{path}: appeared while this command ran (another run writing "
                        "the same name?); nothing written"
                    ) from None
                except OSError as exc:
                    raise os_problem(path, exc) from None
        except BaseException:
            for path, backup in reversed(done):
                self._withdraw(path, backup)
            raise
        for _, backup in done:
            if backup is not None:
                backup.unlink(missing_ok=True)

    def _publish_one(self, path: Path, tmp: Path, mode: int) -> Path | None:
        """Publish one output; the backup of a replaced file, if one was replaced."""
        try:
            os.chmod(tmp, mode)
            os.link(tmp, path)
            return None
        except FileExistsError:
            if not self.force:
                raise
        except OSError as exc:
            if exc.errno not in _NO_LINKS:
                raise
            if not path.exists():
                self._create_exclusive(path, mode)
                return None
            if not self.force:
                raise FileExistsError(errno.EEXIST, "exists", str(path)) from None
        # --force over an existing file: keep its mode, keep it aside until all are done.
        os.chmod(tmp, os.stat(path).st_mode & 0o7777)
        backup = tmp.with_name(tmp.name + ".old")
        try:
            os.link(path, backup)
        except OSError as exc:
            if exc.errno not in _NO_LINKS:
                raise
            shutil.copy2(path, backup)
        try:
            os.replace(tmp, path)
        except BaseException:
            backup.unlink(missing_ok=True)
            raise
        return backup

    def _create_exclusive(self, path: Path, mode: int) -> None:
        """No hard links here: create the name exclusively and copy the text in."""
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(self._text[path])
                f.flush()
                os.fsync(f.fileno())
        except BaseException:
            path.unlink(missing_ok=True)
            raise

    def _withdraw(self, path: Path, backup: Path | None) -> None:
        try:
            if backup is not None:
                os.replace(backup, path)
            else:
                path.unlink(missing_ok=True)
        except OSError:  # pragma: no cover - nothing better to do while failing already
            pass

    def _discard(self) -> None:
        with _signals_deferred():  # a second Ctrl-C does not stop the clean-up halfway
            for tmp in self._tmp.values():
                tmp.unlink(missing_ok=True)
            self._tmp.clear()
        if self._created_folder and self.folder is not None:
            try:
                self.folder.rmdir()  # only if still empty, i.e. the command failed
            except OSError:
                pass
            self._created_folder = False


STDIN = "-"
"""The file name that means standard input (a log pasted from the controller's terminal)."""

MAX_INPUT_BYTES = 16 * 2**20
"""Largest input file read (bytes): a log of a 10 000-point plan is about 1 MB, a robot
file or plan a few kB; anything larger (``/dev/zero``, a disk image given by mistake) is
refused after reading this much, so time and memory stay bounded."""

MAX_TOML_DEPTH = 16
"""Deepest nesting of arrays and tables read in a TOML input (wirecal's files nest at most
three deep); Python's TOML reader recurses per level and would fail near 500."""

_TOML_SKIP = re.compile(
    r'"""(?:[^"\\]|\\.|"(?!""))*"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*',
    re.S,
)
"""Strings and comments of a TOML text: their brackets do not nest anything."""

_BRACKET_STEP = np.zeros(256, dtype=np.int64)
_BRACKET_STEP[[ord("["), ord("{")]] = 1
_BRACKET_STEP[[ord("]"), ord("}")]] = -1
"""Each byte's step in the nesting: +1 opens an array or table, -1 closes one."""

_PARSED_KEPT = 64
"""How many TOML inputs :func:`read_toml` keeps parsed (the most recently read)."""
_PARSED_MAX_BYTES = 2**16
"""Largest input kept parsed: a robot file or plan is a few kB."""
_PARSED: dict[bytes, bytes] = {}
"""Input bytes -> its parsed document, pickled: read again, the same bytes parse the same."""
_PARSED_LOCK = threading.Lock()


def read_input(path: str | Path, what: str, max_bytes: int = MAX_INPUT_BYTES) -> tuple[bytes, str]:
    """Return an input's bytes (at most ``max_bytes``) and its name for messages.

    ``-`` reads standard input. Any problem is a :class:`WirecalError` naming the input.
    """
    if str(path) == STDIN:
        source = "<stdin>"
        if sys.stdin is None or sys.stdin.closed:
            raise WirecalError(
                f"{source}: standard input is closed; give the {what}'s file name, or "
                "paste it into a terminal"
            )
        raw = sys.stdin.buffer.read(max_bytes + 1)
    else:
        source = str(path)
        try:
            with open(path, "rb") as f:
                raw = f.read(max_bytes + 1)
        except OSError as exc:
            raise WirecalError(f"{source}: cannot read {what}: {exc.strerror or exc}") from None
    if len(raw) > max_bytes:
        raise WirecalError(
            f"{source}: more than {max_bytes // 2**20} MiB: not a {what} (wirecal's "
            "largest inputs are about 1 MB); check the file name"
        )
    return raw, source


def is_utf16(raw: bytes) -> bool:
    """Whether ``raw`` is UTF-16 text (what Windows calls "Unicode").

    Told by its byte-order mark, or, without one, by a NUL in nine of ten of the high bytes
    of its first 2048 characters (ASCII text in UTF-16 has every one NUL).
    """
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        return True
    pairs = len(raw[:4096]) // 2
    if pairs == 0:
        return False
    head = raw[: 2 * pairs]
    return max(head[1::2].count(0) / pairs, head[0::2].count(0) / pairs) >= 0.9


def refuse_utf16(raw: bytes, source: str, what: str) -> None:
    """Raise a :class:`WirecalError` naming the encoding if ``raw`` is UTF-16."""
    if is_utf16(raw):
        raise WirecalError(
            f"{source}: UTF-16 text; save it as UTF-8 (a {what} is plain UTF-8 text)"
        )


def decode_text(raw: bytes, source: str, what: str) -> str:
    """Return an input's bytes as UTF-8 text; a :class:`WirecalError` names any other encoding."""
    refuse_utf16(raw, source, what)
    if b"\x00" in raw[:4096]:
        raise WirecalError(f"{source}: not text (it holds NUL bytes); is this a {what}?")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise WirecalError(
            f"{source}: not UTF-8 text (byte {exc.start}); is this a {what}?"
        ) from None


def toml_depth(text: str) -> int:
    """Return how deep the arrays and tables of a TOML text nest (strings, comments aside)."""
    data = np.frombuffer(_TOML_SKIP.sub("", text).encode("utf-8"), dtype=np.uint8)
    return int(np.cumsum(_BRACKET_STEP[data]).max(initial=0))


def read_toml(path: str | Path, what: str) -> dict[str, Any]:
    """Parse a TOML input file; any problem is a :class:`WirecalError` naming the file.

    Bounded: at most :data:`MAX_INPUT_BYTES`, nested at most :data:`MAX_TOML_DEPTH` deep.
    Bytes read before and accepted are not parsed again (the commands of one process, the
    tests', read the same robot file and plan many times): their document is a fresh copy
    of the one parsed then, as every check and the parse depend on the bytes alone.
    """
    raw, source = read_input(path, what)
    with _PARSED_LOCK:
        kept = _PARSED.pop(raw, None)
        if kept is not None:
            _PARSED[raw] = kept  # the most recently read last: the first is dropped first
    if kept is not None:
        return pickle.loads(kept)
    document = _parse_toml(raw, source, what)
    if len(raw) <= _PARSED_MAX_BYTES:
        with _PARSED_LOCK:
            _PARSED[raw] = pickle.dumps(document, pickle.HIGHEST_PROTOCOL)
            while len(_PARSED) > _PARSED_KEPT:
                del _PARSED[next(iter(_PARSED))]
    return document


def _parse_toml(raw: bytes, source: str, what: str) -> dict[str, Any]:
    """Return the TOML document of an input's bytes, refusing what :func:`read_toml` does."""
    text = decode_text(raw, source, what)
    text = text.removeprefix("\ufeff")  # a byte-order mark some editors write
    depth = toml_depth(text)
    if depth > MAX_TOML_DEPTH:
        raise WirecalError(
            f"{source}: arrays and tables nested {depth} deep (more than "
            f"{MAX_TOML_DEPTH}; a {what} nests at most 3): not a {what}"
        )
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise WirecalError(f"{source}: not valid TOML: {exc}") from None
