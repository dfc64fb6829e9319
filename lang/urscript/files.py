"""URScript files sent together: a program and the script files included in it.

A URScript program is one ``def … end`` (or ``sec``) text (Script Manual SW10.6,
*Connecting to URControl*); the files included in it — PolyScope's *Script* node with a
file, or a sender's template include such as ``{% include "…" %}`` in Universal Robots'
client library (``src/control/script_reader.cpp``, ``replaceIncludes``) — are fragments
whose text becomes part of the program. :func:`check_files` checks each program file with
every fragment inserted at the top of its body (each fragment line indented, as the
layout rule wants), so a call to a function a fragment defines is known, and reports every
problem at its own file and line. Where in the body an include sits does not change what
the checker finds (a function is known wherever it is defined in the program); what the
fragment's own statements do at run time is the twin's, not the checker's. Every file laid
out as a whole program is a program; every other file is included in each of them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from wirecal.lang.urscript.parser import program_problems

_WHERE = re.compile(r"^<combined>:(\d+): ")


def is_program(text: str) -> bool:
    """Tell whether a file's text is laid out as a whole program (not a fragment to include).

    As the layout rule has it: the first line (blank and comment lines aside) opens ``def``
    or ``sec`` in the first column, the last is ``end`` in the first column, every other
    line is indented. A file of several top-level functions is a fragment.
    """
    lines = [x for x in text.splitlines() if x.strip() and not x.lstrip().startswith("#")]
    return (
        len(lines) >= 2
        and re.match(r"(def|sec)\s", lines[0]) is not None
        and lines[-1].rstrip() == "end"
        and all(x[:1].isspace() for x in lines[1:-1])
    )


def check_files(texts: Mapping[str, str], software: str | None = None) -> list[str]:
    """Return the problems of programs and the files included in them (file name → text).

    Each file laid out as a whole program (:func:`is_program`) is a program, checked with
    every other file inserted; without one, each file is checked alone (and so refused as a
    program). A problem found in an included file is reported once.
    """
    programs = [s for s, t in texts.items() if is_program(t)]
    if not programs:
        return [p for s, t in texts.items() for p in program_problems(t, s, software)]
    fragments = [(s, t) for s, t in texts.items() if s not in programs]
    problems: list[str] = []
    for source in programs:
        text, origin = _combined(source, texts[source], fragments)
        for problem in program_problems(text, "<combined>", software):
            m = _WHERE.match(problem)
            if m is None:
                problems.append(problem.replace("<combined>", source, 1))
            else:
                file, line = origin[int(m.group(1)) - 1]
                problems.append(f"{file}:{line}: {problem[m.end() :]}")
    return list(dict.fromkeys(problems))


def _combined(
    source: str, text: str, fragments: list[tuple[str, str]]
) -> tuple[str, list[tuple[str, int]]]:
    """Return the program with the fragments after its ``def`` line, and each line's origin."""
    lines = text.split("\n")
    head = next(k for k, line in enumerate(lines) if re.match(r"(def|sec)\s", line))
    out = [(line, (source, k + 1)) for k, line in enumerate(lines[: head + 1])]
    for name, fragment in fragments:
        for k, line in enumerate(fragment.split("\n")):
            out.append((("  " + line) if line.strip() else line, (name, k + 1)))
    out += [(line, (source, k + 1)) for k, line in enumerate(lines[head + 1 :], head + 1)]
    return "\n".join(line for line, _ in out), [where for _, where in out]
