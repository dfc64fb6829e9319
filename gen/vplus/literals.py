"""V+ literals written exactly, the joint-limit margin, and the line-length rule.

The language rules a controller checks on load (program format, declarations first,
15-character names, keywords, labels, type prefixes) are checked by the V+ front end
(:mod:`wirecal.lang.vplus.parser`, the twin's parser too), which the generator runs on its
own output.
wirecal also keeps lines within 80 characters (the terminal line limit, User's Guide
p. 202).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from wirecal.gen.targets import joint_literal

MAX_LINE = 80


PPOINT_PREFIX = "    SET #wc.p = "
"""The line every #PPOINT literal is written in (the templates' moves to θ0 and the points)."""

PPOINT_FORMS = ((4, ", "), (4, ","), (3, ","), (2, ","))
"""Decimals and separator of a #PPOINT literal, tried in turn until its line fits."""


def ppoint(q: Iterable[float]) -> str:
    """Write a #PPOINT(...) literal of joint angles within the line limit.

    Four decimals and ", " as the operator reads them; where that line would pass
    :data:`MAX_LINE` (six angles of four decimals and three digits before the point, as a
    pose recorded to 0.0001° in a pool can be) the first of :data:`PPOINT_FORMS` that
    fits: the pose commanded is then within 0.0005° (three decimals) or 0.005° (two) of
    the plan's, well inside the log's joint tolerance, and the log records the joints
    reached, which the solve uses.
    """
    values = [float(x) for x in q]
    for decimals, sep in PPOINT_FORMS:
        text = "#PPOINT(" + sep.join(joint_literal(x, decimals) for x in values) + ")"
        if len(PPOINT_PREFIX) + len(text) <= MAX_LINE:
            break
    return text


MAX_MANTISSA = 2**53
"""The largest ``^D`` integer written: a 64-bit IEEE double holds it exactly (UG p. 102)."""


def double_literal(x: float) -> str:
    """Write a DOUBLE constant to 16 significant digits (relative error < 1.2e-15).

    A ``^D`` integer (UG p. 102) of at most 2^53 (:data:`MAX_MANTISSA`) divided by a power
    of ten held in ``wc.p10[]``.
    """
    x = float(x)
    if x == 0:
        return "0"
    k = 15 - int(np.floor(np.log10(abs(x))))
    k = max(0, min(k, 22))
    m = round(x * 10.0**k)
    while abs(m) > MAX_MANTISSA and k > 0:  # keep the mantissa a whole double
        k -= 1
        m = round(x * 10.0**k)
    while m % 10 == 0 and k > 0:
        m //= 10
        k -= 1
    sign = "-" if m < 0 else ""
    if k == 0 and abs(m) < 2**24:
        return str(m)  # a whole number a REAL holds exactly
    return f"{sign}^D{abs(m)}/wc.p10[{k}]" if k else f"{sign}^D{abs(m)}"


def long_lines(text: str, source: str) -> list[str]:
    """Lines over :data:`MAX_LINE` characters."""
    return [
        f"{source}:{n}: line has {len(line)} characters (> {MAX_LINE})"
        for n, line in enumerate(text.split("\n"), 1)
        if len(line) > MAX_LINE
    ]
