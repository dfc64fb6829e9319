"""Parameter types shared by every command, so each numeric option is checked the same way."""

from __future__ import annotations

import math
from typing import Any

import click
from click.core import ParameterSource


class Number(click.FloatRange):
    """A finite number within optional bounds.

    click's ``FloatRange`` lets NaN through (every comparison with NaN is false), so
    ``--zero-tol nan`` would switch a check off; this type refuses NaN and ±inf first.
    """

    name = "number"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        """Return ``value`` as a float, failing unless finite and within the bounds."""
        rv = click.FLOAT.convert(value, param, ctx)
        if not math.isfinite(rv):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return super().convert(rv, param, ctx)

    def _describe_range(self) -> str:
        """Describe the bounds in the help; nothing for a number without any."""
        return "" if self.min is None and self.max is None else super()._describe_range()


def given(name: str) -> bool:
    """Whether the current command's option ``name`` (its parameter name) was given.

    Given, not left at its default: an option that only acts with another is refused
    without it, never ignored.
    """
    source = click.get_current_context().get_parameter_source(name)
    return source not in (None, ParameterSource.DEFAULT, ParameterSource.DEFAULT_MAP)


def number(
    min: float | None = None,
    max: float | None = None,
    *,
    min_open: bool = False,
    max_open: bool = False,
) -> Number:
    """Return a type for a finite number in [min, max] (open ends as asked); None: no bound."""
    return Number(min, max, min_open=min_open, max_open=max_open)


POSITIVE = number(0.0, min_open=True)  # tolerances, bounds, sizes: > 0
NON_NEGATIVE = number(0.0)  # noises, margins, scales: ≥ 0
SEED = click.IntRange(0, 2**63 - 1)  # numpy's generators take non-negative seeds


class OutputFile(click.Path):
    """An output file's name: not a folder, and not ``-``.

    ``-`` means standard input or output elsewhere; an output written atomically beside
    its companions is a file, so ``-o -`` is refused rather than written to a file named
    ``-``.
    """

    def __init__(self) -> None:
        super().__init__(dir_okay=False)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        """Return the name, failing for ``-``."""
        if value == "-":
            self.fail(
                "'-' (standard output) cannot take this output: it is written as a file "
                "(with the files beside it); give a file name",
                param,
                ctx,
            )
        return super().convert(value, param, ctx)


OUTPUT_FILE = OutputFile()
"""The type of every ``-o, --output FILE`` option."""

PATCH_OUTPUT = click.option(
    "-o",
    "--output",
    "patch_path",
    type=OUTPUT_FILE,
    help="Write the patch (TOML) here, and the SPEC table beside it.",
)
"""``-o PATCH`` of the commands that identify parameters (solve, fit)."""

ACCEPT_IMPLAUSIBLE = click.option(
    "--accept-implausible",
    is_flag=True,
    help="Show and write a result the plausibility gate refuses; the patch records it.",
)
"""The plausibility gate's override, recorded in the patch (solve, fit)."""

PATCH_FORCE = click.option(
    "--force", is_flag=True, help="Replace an existing patch and SPEC table."
)
"""Replace the outputs of ``-o PATCH`` (solve, fit)."""

ROBOT = click.argument("robot", type=click.Path(dir_okay=False))
"""The robot file argument (simulate, solve)."""

PLAN = click.argument("plan", type=click.Path(dir_okay=False))
"""The plan file argument (simulate, solve)."""


def positional(value: str | None, alias: str | None, name: str, option: str) -> str:
    """Return a positional argument given either in place or by its older option spelling.

    ``receive`` and ``validate`` took the robot file and plan as options; they are
    positionals now, like every other command's, and the options are kept as aliases.
    """
    if value is not None and alias is not None and value != alias:
        raise click.UsageError(f"{name} given twice ({value} and {option} {alias}); give it once")
    if value is None and alias is None:
        raise click.UsageError(f"missing {name} (or its older spelling {option} {name})")
    return value if value is not None else alias  # type: ignore[return-value]
