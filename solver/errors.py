"""One error type for every problem a user can fix: bad files, bad options, bad logs."""

from __future__ import annotations


class WirecalError(Exception):
    """A problem the user can act on; ``problems`` holds one line per problem.

    Each line already names where the problem is (``file: key: problem`` or
    ``file:line: problem``) and, where possible, what to do about it.
    """

    exit_status = 2

    def __init__(self, problems: str | list[str]):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))


def first_problems(problems: list[str], n: int = 12) -> list[str]:
    """Return the first ``n`` problems and a count of the rest.

    A wrong file (another format, a log pasted twice) should not bury its cause under
    thousands of lines of the same kind.
    """
    if len(problems) <= n:
        return problems
    return [*problems[:n], f"… and {len(problems) - n} more problems of the same kinds"]


class Implausible(WirecalError):
    """Refuse an implausible identification.

    An identification that passed every format check but that the plausibility gate
    (:mod:`wirecal.solver.plausibility`) refuses: nothing is written; exit status 3.
    """

    exit_status = 3


class Problems:
    """Collects problems about one file so that all are reported at once."""

    def __init__(self, source: str):
        self.source = source
        self.items: list[str] = []

    def add(self, key: str, message: str) -> None:
        """Add a problem about ``key`` (the file itself when empty)."""
        where = f"{self.source}: {key}" if key else self.source
        self.items.append(f"{where}: {message}")

    def raise_if_any(self) -> None:
        """Raise every problem collected, if any."""
        if self.items:
            raise WirecalError(self.items)
