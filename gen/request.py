"""What ``wirecal gen`` can ask of a generator, whatever the language: one :class:`GenRequest`.

Each field names the ``wirecal gen`` option that sets it (``metadata["option"]``); a
generator lists the fields it does not take (``Generator.refuses``) and
:func:`refuse_unsupported` names the options given for them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace

from wirecal.solver.errors import WirecalError
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.run_parameters import RunParameters
from wirecal.solver.validation.design import Setup
from wirecal.solver.wire_range import RANGE_MARGIN_MM
from wirecal.solver.zero_reading import slip_tolerance_mm


def _option(name: str) -> dict[str, str]:
    """Return the field metadata naming the ``wirecal gen`` option that sets it."""
    return {"option": name}


@dataclass(frozen=True)
class GenRequest:
    """One generation: the run, the checks' tolerances and the language-specific extras."""

    run: RunParameters | None = None  # speed, accel, settle, readings (None: the language's)
    zero_tol_mm: float = 0.1  # a zero reading further from the previous: the wire slipped
    # (the floor: an arm of declared repeatability is given more, with_slip_tolerance)
    spread_tol_mm: float = 0.1  # a point's samples spread wider: the robot still moved
    margin_deg: float = 1.0  # every generated target at least this far inside a limit
    range_margin_mm: float = RANGE_MARGIN_MM  # every wire length this far inside range_mm
    solver: bool = field(default=True, metadata=_option("--no-solver"))  # the controller solver
    patch: dict[str, float] | None = field(default=None, metadata=_option("--patch"))
    patch_warning: str | None = None  # the patch's overridden plausibility gate, if so
    validation: Setup | None = field(default=None, metadata=_option("--validation"))
    host: str | None = field(default=None, metadata=_option("--host"))  # the PC's address
    port: int | None = field(default=None, metadata=_option("--port"))  # its port
    log_file: str = field(default="WCLOG.CSV", metadata=_option("--log-name"))
    echo_log: bool = field(default=False, metadata=_option("--echo-log"))
    crlf: bool = field(default=True, metadata=_option("--lf"))  # CRLF line ends


DEFAULT = GenRequest()


def refuse_unsupported(request: GenRequest, refuses: frozenset[str], title: str) -> None:
    """Raise a WirecalError naming the options given for fields the language does not take.

    Given: the field differs from its default. ``title`` names the language.
    """
    given = [
        f.metadata["option"]
        for f in fields(GenRequest)
        if f.name in refuses and getattr(request, f.name) != getattr(DEFAULT, f.name)
    ]
    if given:
        raise WirecalError(
            f"{', '.join(given)}: not taken by the {title} programs (wirecal gen --help says "
            "which language each option is for)"
        )


def with_slip_tolerance(robot: Robot, plan: Plan, request: GenRequest) -> GenRequest:
    """Return ``request`` with the zero readings' slip tolerance the robot file's arm needs.

    :func:`~wirecal.solver.zero_reading.slip_tolerance_mm` at the plan's θ0, ``zero_tol_mm``
    its floor: the same tolerance the log reader checks; unchanged without a declared
    ``[calibration] repeatability_mm``.
    """
    tol = slip_tolerance_mm(
        robot.nominal, plan.theta0_deg, robot.repeatability_mm, request.zero_tol_mm
    )
    return replace(request, zero_tol_mm=tol)
