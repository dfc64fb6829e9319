"""The operand forms of the instructions the digital twin executes.

Every V+ instruction parses as a generic :class:`~wirecal.lang.vplus.nodes.Instruction`;
the twin executes the instructions below in the form given here, and refuses any other
instruction, or another form of these, at run time naming it. The generator's
self-check (``parse_module(..., twin=True)``) requires every instruction of a generated
module to match its form, so that the twin runs all of it; ``wirecal lint`` does not.

A form lists the comma-separated clauses; in a clause, the operands written next to each
other. Codes: ``n`` number, ``s`` string, ``e`` a value of the target's kind, ``l`` a
location (precision point or transformation), ``L`` a location variable, ``V`` a variable,
``B`` a belt variable (``%b``), ``W`` a bare word; an upper-case word stands for itself;
``(…)`` a parenthesised group; a trailing ``?`` an operand that may be left out.
"""

from __future__ import annotations

import re

from wirecal.lang.vplus.nodes import Clause, Expr, Group, Instruction, Paren, Var

FORMS: dict[str, str] = {
    "move": "l",
    "moves": "l",
    "here": "L",
    "set": "L = e",
    "decompose": "V = L",
    "break": "",
    "speed": "n ALWAYS?",
    "accel": "(n) n, n",
    "above": "",
    "below": "",
    "flip": "",
    "noflip": "",
    "lefty": "",
    "righty": "",
    "type": "*",
    "prompt": "s, V",
    "wait.event": ", n",
    "timer": "n = n",
    "attach": "(V n) s",
    "detach": "(n)",
    "fopenw": "(n) s",
    "fopena": "(n) s",
    "fopenr": "(n) s",
    "fclose": "(n)",
    "write": "(n) s",
    "enable": "W",
    "defbelt": "B = NULL, n, n",
    "tool": "NULL",
    "halt": "",
    "pause": "",
    "return": "",
}

_TOKEN = re.compile(r"\([^)]*\)\??|\S+")


class FormError(Exception):
    """The instruction is valid V+ but not in the form the twin executes."""


def operands(ins: Instruction) -> list[tuple[str, Expr | None]]:
    """Return the operands of an executed instruction with their codes.

    In the order of its form (``None`` for a left-out optional operand);
    :class:`FormError` if the instruction is not in a form the twin executes.
    """
    spec = FORMS.get(ins.name)
    if spec is None:
        raise FormError(f"{ins.name.upper()} is not executed by the twin")
    if spec == "*":
        return [("*", e) for c in ins.clauses if c is not None for e in c.items]
    wanted = [c.strip() for c in spec.split(",")] if spec else []
    if len(wanted) != len(ins.clauses):
        raise _mismatch(ins, spec)
    out: list[tuple[str, Expr | None]] = []
    for want, clause in zip(wanted, ins.clauses, strict=True):
        if not want:
            if clause is not None:
                raise _mismatch(ins, spec)
            continue
        if clause is None or clause.formats:
            raise _mismatch(ins, spec)
        out += _clause(ins, spec, want, clause)
    return out


def _clause(ins: Instruction, spec: str, want: str, clause: Clause):
    """Match one clause against its part of the form: the operands with their codes."""
    left, eq, right = want.partition("=")
    out = _left_operands(ins, spec, left, list(clause.items))
    right = right.strip()
    if eq:
        if clause.value is None:
            raise _mismatch(ins, spec)
        if _is_word(right):
            if not _word_is(clause.value, right):
                raise _mismatch(ins, spec)
        else:
            out.append((right, clause.value))
    elif clause.value is not None:
        raise _mismatch(ins, spec)
    return out


def _left_operands(ins: Instruction, spec: str, left: str, items: list[Expr | None]):
    """Match the items before ``=`` of a clause against the tokens of the form."""
    out: list[tuple[str, Expr | None]] = []
    for token in _TOKEN.findall(left):
        optional = token.endswith("?")
        token = token.rstrip("?")
        if not items:
            if not optional:
                raise _mismatch(ins, spec)
            if not _is_word(token):
                out.append((token, None))
            continue
        item = items[0]
        if token.startswith("("):
            out += _group(ins, spec, token, item)
        elif _is_word(token):
            if not _word_is(item, token):
                if optional:
                    continue
                raise _mismatch(ins, spec)
        else:
            out.append((token, item))
        items.pop(0)
    if items:
        raise _mismatch(ins, spec)
    return out


def _group(ins: Instruction, spec: str, token: str, item: Expr | None):
    """Match a parenthesised group of the form, e.g. ``(n n)``, against an item."""
    codes = token[1:-1].split()
    group = (
        item.items if isinstance(item, Group) else [item.expr] if isinstance(item, Paren) else None
    )
    if group is None or len(group) != len(codes) or None in group:
        raise _mismatch(ins, spec)
    return list(zip(codes, group, strict=True))


def _is_word(token: str) -> bool:
    return len(token) > 1 and token.isupper()


def _word_is(e: Expr | None, word: str) -> bool:
    return isinstance(e, Var) and e.index is None and e.name == word.lower()


def _mismatch(ins: Instruction, spec: str) -> FormError:
    return FormError(
        f"{ins.name.upper()} in a form the twin does not execute "
        f"(it executes {ins.name.upper()} {spec})"
    )
