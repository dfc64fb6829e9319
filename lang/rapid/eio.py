r"""The I/O signals of a controller's configuration file (``EIO.cfg``), which modules read.

A module may name a signal of the I/O configuration without declaring it (``IF di1 = 1``,
``SetDO do1, 1``). ``EIO.cfg`` lists them in its ``EIO_SIGNAL:`` section, one record per
signal, ``-Name "di1" -SignalType "DI" …``, a record's lines joined by a trailing ``\``
(the format as IRC5 RobotWare 5 and 6 backups write it, e.g.
EdgarIvanMM/PaletizadoCajasConFrascos@850dc0e SYSPAR/EIO.cfg; ABB's page on it: unconfirmed,
not read).
"""

from __future__ import annotations

import re

CONFIG_SUFFIX = ".cfg"
"""The suffix of a controller configuration file (``EIO.cfg``)."""

_SECTION = re.compile(r"^([A-Z_]+):\s*$")
_NAME = re.compile(r'-Name\s+"([^"]+)"')
_TYPE = re.compile(r'-SignalType\s+"(DI|DO|GI|GO|AI|AO)"', re.IGNORECASE)


def config_signals(text: str) -> dict[str, str]:
    """Return the signals of an ``EIO.cfg`` text: lower-case name → RAPID type (signaldi …)."""
    signals: dict[str, str] = {}
    section = ""
    for record in re.sub(r"\\\s*\n", " ", text).splitlines():
        head = _SECTION.match(record.strip())
        if head is not None:
            section = head.group(1)
            continue
        name, kind = _NAME.search(record), _TYPE.search(record)
        if section == "EIO_SIGNAL" and name is not None and kind is not None:
            signals[name.group(1).lower()] = "signal" + kind.group(1).lower()
    return signals
