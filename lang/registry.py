"""The registered controller languages, found by importing every sub-package of ``wirecal.lang``.

Adding a language adds a folder ``lang/<key>/`` whose ``__init__`` registers its
:class:`~wirecal.lang.base.Language` with :func:`register`; no list names them.
"""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache
from pathlib import PurePath
from typing import TypeVar

import wirecal.lang
from wirecal.lang.base import Language
from wirecal.solver.errors import WirecalError

_REGISTERED: dict[str, Language] = {}

L = TypeVar("L", bound=type[Language])


def register(cls: L) -> L:
    """Class decorator: register one instance of the Language ``cls`` under its key."""
    if cls.key in _REGISTERED and type(_REGISTERED[cls.key]) is not cls:
        raise ValueError(f"two languages declare the key {cls.key!r}")
    _REGISTERED[cls.key] = cls()
    return cls


@cache
def _load() -> None:
    """Import every language sub-package once (each registers itself)."""
    for info in pkgutil.iter_modules(wirecal.lang.__path__):
        if info.ispkg:
            importlib.import_module(f"wirecal.lang.{info.name}")


def languages() -> dict[str, Language]:
    """Return every registered language by key, in key order."""
    _load()
    return dict(sorted(_REGISTERED.items()))


def language(key: str) -> Language:
    """Return the language registered as ``key``; a WirecalError naming the known keys if none."""
    known = languages()
    if key not in known:
        raise WirecalError(
            f"unknown controller language {key!r}: wirecal knows " + ", ".join(map(repr, known))
        )
    return known[key]


def default_language() -> Language:
    """Return the language of a robot file without ``[controller]`` (the one marked default)."""
    (only,) = (lang for lang in languages().values() if lang.default)
    return only


def language_of_suffix(path: str) -> Language | None:
    """Return the language one of whose program suffixes ``path`` has; None if none does."""
    suffix = PurePath(path).suffix.lower()
    for lang in languages().values():
        if suffix in lang.all_suffixes():
            return lang
    return None


def language_of_file(path: str) -> Language:
    """Return the language whose program suffix ``path`` has; the default language otherwise."""
    return language_of_suffix(path) or default_language()


def first_channel(interface: str | None) -> int:
    """Return the first ``[encoder] channel`` of an encoder interface.

    0 unless its language says otherwise (V+ belt encoders count from 1).
    """
    for lang in languages().values():
        for name, channel in lang.first_channel.items():
            if name == interface:
                return channel
    return 0
