"""What the three parsers made of a fixed corpus, kept as a reference for their identity tests.

``tests/data/parse_reference.json`` holds, for each text of :func:`corpus`, the outcome of
parsing it (:func:`outcome`): the SHA-256 of the node tree written out in full
(:func:`canonical`: every class, field and value, its exact type; not ``==``, which a
``Token`` equal to its text would pass), or the problems with their lines; and the lint
problems. It was written by main's parsers (dc1a97b) before the parsers were made faster,
with ``python -m tests.parse_reference``; write it again only on purpose (a parser changed
what it reads, or a golden program of the corpus changed: then with the parsers of the commit
before, from a copy of tests/ so that they are the ones imported), saying why in the commit.

The corpus: the golden programs and the payload programs under tests/, the languages'
conformance examples, windows of the golden programs cut out of their modules (syntax
errors, open blocks, at their lines), and expressions nested around the depth bound
(:data:`~wirecal.lang.syntax.MAX_EXPRESSION_DEPTH`), on one line and across lines.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
from collections.abc import Callable
from pathlib import Path

from wirecal.lang.registry import language
from wirecal.solver.errors import WirecalError

TESTS = Path(__file__).parent
REFERENCE = TESTS / "data" / "parse_reference.json"

_FILES = {
    "rapid": ["golden/abb_irb120/WIRECAL.mod", "data/payload_abb_irb120/WIRECAL.mod"],
    "vplus": ["golden/viper_s650/WIRECAL.V2", "data/payload_viper_s650/WIRECAL.V2"],
    "urscript": [
        f"golden/{arm}/wc_{name}.script"
        for arm in ("ur5", "ur5e")
        for name in ("run", "check", "mount")
    ]
    + ["data/payload_ur5e/wc_run.script"],
}


def canonical(obj: object) -> str:
    """Write ``obj`` out in full: each object's exact type, fields and values (no sharing)."""
    out: list[str] = []
    stack: list[object] = [obj]
    while stack:  # iterative: a tree nested to the depth bound is deeper than a few frames
        item = stack.pop()
        if isinstance(item, _Text):
            out.append(item.text)
        elif dataclasses.is_dataclass(item) and not isinstance(item, type):
            attrs = {f.name: getattr(item, f.name) for f in dataclasses.fields(item)}
            attrs |= dict(sorted(getattr(item, "__dict__", {}).items()))
            _push(stack, type(item).__qualname__, list(attrs.items()))
        elif isinstance(item, list | tuple):
            _push(stack, type(item).__name__, list(item))
        elif isinstance(item, dict):
            _push(stack, "dict", list(item.items()))
        else:
            out.append(f"{type(item).__name__}:{item!r}")
    return "".join(out)


class _Text:
    def __init__(self, text: str) -> None:
        self.text = text


def _push(stack: list[object], name: str, items: list) -> None:
    stack.append(_Text(")"))
    for item in reversed(items):
        stack.extend([_Text(","), item])
    stack.append(_Text(f"{name}("))


def _digest(tree: object) -> str:
    return "tree " + hashlib.sha256(canonical(tree).encode()).hexdigest()


def _module(*body: str) -> str:
    return "MODULE T\n  VAR num x;\n  PROC main()\n" + "\n".join(body) + "\n  ENDPROC\nENDMODULE\n"


def _vplus(*body: str) -> str:
    return ".PROGRAM t.main()\n" + "\n".join(body) + "\n.END\n"


def _urscript(*body: str) -> str:
    return "def main():\n" + "\n".join("  " + line for line in body) + "\nend\n"


def _broken(text: str, every: int) -> str:
    """``text`` with a line break after every ``every``-th space (an expression over lines)."""
    words = text.split(" ")
    return "".join(w + ("\n" if k % every == every - 1 else " ") for k, w in enumerate(words))


def _deep_rapid() -> dict[str, str]:
    """RAPID expressions nested around the bound, each construct, on one line and over lines."""
    out: dict[str, str] = {}
    for n in (33, 34, 99, 100, 101):
        k = min(n, 100)  # brackets beyond 100 are refused before parsing
        chains = {
            "operators": "x := 1" + " + 1" * n + ";",
            "right operands": "x := " + "1 + (" * k + "1" + ")" * k + ";",
            "minus signs": "x := " + "- " * n + "1;",
            "NOT": "x := " + "NOT " * n + "TRUE;",
            "components": "x := a" + " .b" * n + ";",
            "indices": "x := a" + " {1}" * n + ";",
            "aggregates": "x := " + "[ " * k + "1" + " ]" * k + ";",
            "calls": "x := " + "Abs( " * k + "1" + " )" * k + ";",
            "calls in a statement": "Report " + "Abs( " * k + "1" + " )" * k + ";",
            "optional arguments": "x := " + "f(\\a:= " * k + "1" + " )" * k + ";",
        }
        for name, line in chains.items():
            out[f"rapid: {name}, {n} deep"] = _module(line)
            out[f"rapid: {name}, {n} deep, over lines"] = _module(_broken(line, 7))
    return out


def _deep_lines(wrap: Callable[..., str], key: str, call: str) -> dict[str, str]:
    """V+ or URScript lines nested around the bound, on a line each."""
    out: dict[str, str] = {}
    for n in (30, 32, 33, 34, 48, 49, 50, 98, 99, 100, 101):
        chains = {
            "operators": "x = 1" + " + 1" * n,
            "right operands": "x = " + "1 + (" * min(n, 100) + "1" + ")" * min(n, 100),
            "minus signs": "x = " + "-(" * min(n, 100) + "1" + ")" * min(n, 100),
            "calls": "x = " + f"{call}(" * min(n, 100) + "1" + ")" * min(n, 100),
            "lists": "x = " + "[" * min(n, 100) + "1" + "]" * min(n, 100),
        }
        for name, line in chains.items():
            out[f"{key}: {name}, {n} deep"] = wrap(line)
    return out


def _windows(key: str, text: str, wrap: Callable[..., str], size: int, step: int) -> dict[str, str]:
    """Windows of ``text``'s lines (open and closed blocks cut apart: most are refused)."""
    lines = text.splitlines()
    return {
        f"{key}: lines {k + 1}-{k + size}": wrap(*lines[k : k + size])
        for k in range(0, len(lines), step)
    }


def corpus() -> dict[str, tuple[str, str]]:
    """Name → (language key, text) of every text the reference holds."""
    out: dict[str, tuple[str, str]] = {}
    for key, paths in _FILES.items():
        for path in paths:
            out[path] = (key, (TESTS / path).read_text(encoding="utf-8"))
        lang = language(key)
        for n, example in enumerate(lang.valid_examples + lang.invalid_examples):
            out[f"{key}: example {n}"] = (key, example.text)
    golden = {key: (TESTS / paths[0]).read_text(encoding="utf-8") for key, paths in _FILES.items()}
    wraps = {"rapid": _module, "vplus": _vplus, "urscript": _urscript}
    for key, text in golden.items():
        size, step = {"rapid": (17, 53), "vplus": (23, 97), "urscript": (19, 41)}[key]
        out |= {n: (key, t) for n, t in _windows(key, text, wraps[key], size, step).items()}
    out |= {n: ("rapid", t) for n, t in _deep_rapid().items()}
    out |= {n: ("vplus", t) for n, t in _deep_lines(_vplus, "vplus", "SIN").items()}
    out |= {n: ("urscript", t) for n, t in _deep_lines(_urscript, "urscript", "sin").items()}
    return out


LINTED_CHARS = 10_000
"""Texts shorter than this are linted too (the checker's problems at the parsed lines); the
longer ones, the golden and payload programs, parsed only (they lint clean in their own tests)."""


def outcome(key: str, text: str) -> dict[str, object]:
    """What the language's parser (and, for a short text, checker) make of ``text``."""
    found: dict[str, object] = {"parse": _parse(key, text)}
    if len(text) < LINTED_CHARS:
        found["lint"] = language(key).lint(text, "t")
    return found


def _parse(key: str, text: str) -> object:
    if key == "rapid":
        from wirecal.lang.rapid.parser import SyntaxProblem, parse_module

        try:
            return _digest(parse_module(text))
        except SyntaxProblem as e:
            return [e.line, e.message]
    if key == "vplus":
        from wirecal.lang.vplus.parser import parse_module as parse_vplus

        parse: Callable[[str, str], object] = parse_vplus
    else:
        from wirecal.lang.urscript.parser import parse_program

        parse = parse_program
    try:
        return _digest(parse(text, "t"))
    except WirecalError as e:
        return list(e.problems)


def main() -> None:
    """Write the reference (main's parsers: see the module's docstring)."""
    found = {name: outcome(key, text) for name, (key, text) in corpus().items()}
    REFERENCE.write_text(json.dumps(found, indent=1, ensure_ascii=True) + "\n", encoding="utf-8")
    print(f"{len(found)} texts written to {REFERENCE}", file=sys.stderr)


if __name__ == "__main__":
    main()
