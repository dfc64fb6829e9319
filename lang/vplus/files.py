"""V+ files loaded together: programs in one file CALL programs in another.

LOAD reads each file's programs into the one program memory, so a CALL is resolved among
every loaded program (V+ Language User's Guide v17, p. 45: "main programs and subroutines
always exist as separate programs"; a program not in memory is "*Undefined program or
variable name*" when called). :func:`check_files` checks each file's programs with every
file's programs callable. A program defined in two of the files is refused: which one
memory would keep is not stated on the pages read (*unconfirmed*).
"""

from __future__ import annotations

from collections.abc import Mapping

from wirecal.lang.vplus.parser import Program, check_programs, read_programs
from wirecal.solver.errors import WirecalError


def check_files(texts: Mapping[str, str], *, external_calls: bool = False) -> list[str]:
    """Return the problems of V+ files loaded together (file name → text), 'FILE:LINE: what'."""
    problems: list[str] = []
    read: list[tuple[str, dict[str, Program]]] = []
    visible: dict[str, Program] = {}
    where: dict[str, str] = {}
    for source, text in texts.items():
        try:
            found, programs = read_programs(text, source)
        except WirecalError as exc:  # a file nested too deep to read: its problem, not a crash
            problems += exc.problems
            continue
        problems += found
        for name, prog in programs.items():
            if name in where and where[name] != source:
                problems.append(
                    f"{source}:{prog.line}: program {name} is also defined in {where[name]} "
                    "(which one LOAD keeps is unconfirmed)"
                )
            where.setdefault(name, source)
            visible.setdefault(name, prog)
        read.append((source, programs))
    for source, programs in read:
        if not programs and not any(p.startswith(f"{source}:") for p in problems):
            problems.append(f"{source}: no .PROGRAM in the file")
        check_programs(programs, source, problems, external_calls, visible)
    return problems
