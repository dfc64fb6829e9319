"""``wirecal demo``: the whole chain on a shipped robot, in the digital twin.

The Viper s650 (V+, the default): generate the V+ module (calibration and validation
programs) for the paper's corrected plan; run it on a twin robot with random true errors;
identify the parameters on the PC and with the controller solver; write the patch; run
both validation procedures before and after calibration (the controller believing the
patch), with unmodelled errors on; write the report. The validation before calibration runs
in a second process beside the rest.

The UR5e (URScript, ``robot=examples/ur5e/robot.toml``): generate the ``.script`` programs for
the shipped plan; run wc_mount and wc_run on a twin UR whose log travels over a loopback
socket to ``wirecal receive``; identify on the PC; write the patch and UR's deltas; run
the measurement program again over new points (unmodelled errors on) and compare the wire
lengths with those the nominal and the calibrated model predict; write the report. wc_run
ends with wc_solve, the step-by-step solver on the controller, whose result arrives in the
log; it is compared with the PC's stepwise estimate. (The URScript backend generates no
joint polish and no Cartesian validation programs.)

Every output goes to one folder and none is overwritten unless asked.
"""

from __future__ import annotations

import multiprocessing as mp
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace
from functools import partial
from importlib import resources
from pathlib import Path
from typing import NamedTuple

import numpy as np

from wirecal import __version__
from wirecal.app.compare import compare_controller
from wirecal.app.languages import gate
from wirecal.app.report import Validation, render_report
from wirecal.app.twin_runs import measure_in_twin, measure_ur_in_twin
from wirecal.gen.urscript.program import UrOptions, scripts
from wirecal.gen.vplus.program import GenOptions, module_text
from wirecal.solver.accuracy import error_vs_truth_mm, workspace
from wirecal.solver.errors import WirecalError
from wirecal.solver.formats.controller_result import parse_result, result_in_log
from wirecal.solver.formats.fileio import Outputs
from wirecal.solver.formats.log import read_log
from wirecal.solver.formats.patch import put_patch
from wirecal.solver.formats.plan_file import load_plan
from wirecal.solver.formats.robot_file import load_robot
from wirecal.solver.formats.truth import random_errors, truth_text
from wirecal.solver.formats.validation_files import load_setup, read_validation_log
from wirecal.solver.measurements import check_log
from wirecal.solver.plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import Unmodelled, realistic_encoder
from wirecal.solver.solve import SolveResult, solve
from wirecal.solver.validation import Setup, distance_plan, distance_residuals
from wirecal.solver.validation_analysis import Stats, config_discrepancy, plane_residuals
from wirecal.solver.verdict import Plausibility
from wirecal.twin.vplus.runs import run_validation

UR_OUTPUTS = (
    "truth.toml",
    "wc_mount.script",
    "wc_check.script",
    "wc_run.script",
    "run.csv",
    "patch.toml",
    "patch.spec.txt",
    "patch.ur_calibration.conf",
    "validation.csv",
    "report.html",
)
OUTPUTS = (
    "truth.toml",
    "WIRECAL.V2",
    "WCLOG.CSV",
    "patch.toml",
    "patch.spec.txt",
    "WCVCFG1.CSV",
    "WCVPLN1.CSV",
    "WCVCFG2.CSV",
    "WCVPLN2.CSV",
    "report.html",
)


@dataclass
class DemoResult:
    """What the demo wrote and measured: its folder and the validations."""

    folder: Path
    validations: list[Validation]
    tool_error_mm: dict[str, float]  # mean over the workspace: before, after
    controller_difference: float  # controller solver vs the PC's estimate (deg, mm)
    seconds: dict[str, float]  # each stage's own time (two of them ran side by side)
    outputs: tuple[str, ...] = OUTPUTS
    wall_s: float | None = None  # the whole demo, start to end (None: the sum of seconds)
    predicted_mm: float | None = None  # the error budget's total for the recommended method
    bound_mm: float | None = None  # the error budget's 95 % bound for the recommended method
    encoder_scale_ppm: float | None = None  # the twin encoder's true scale error (V+ twin)

    @property
    def total_s(self) -> float:
        """The demo's time, start to end."""
        return sum(self.seconds.values()) if self.wall_s is None else self.wall_s


def example_files(robot: str = "viper_s650") -> dict[str, Path]:
    """Return the shipped example: robot, corrected paper plan, validation setup."""
    here = Path(__file__).resolve().parents[1] / "examples" / robot
    if not here.is_dir():  # an installed wheel: the examples travel as package data
        here = Path(str(resources.files("wirecal.examples").joinpath(robot)))
    return {
        "robot": here / "robot.toml",
        "plan": here / "paper_plan.toml",
        "validation": here / "validation.toml",
    }


def run_demo(
    folder: str | Path,
    *,
    robot: str | Path | None = None,
    seed: int = 1,
    scale: float = 1.0,
    force: bool = False,
    progress: Callable[[str], None] = lambda s: None,
) -> DemoResult:
    """Run the demo into ``folder``: every output written, or none (``force`` to replace).

    ``robot``: the Viper s650 when not given; a URScript robot file (the UR5e's) runs the
    URScript chain with the plan beside it (``plan.toml``).
    """
    folder = Path(folder)
    if robot is not None:
        rb = load_robot(robot)
        if rb.controller.language != "urscript":
            raise WirecalError(
                f"{robot}: the demo runs the Viper s650 (give no --robot) or a URScript robot"
            )
        plan = Path(robot).with_name("plan.toml")
        if not plan.is_file():
            raise WirecalError(f"{robot}: no plan.toml beside it; design one with wirecal plan")
        with Outputs([folder / n for n in UR_OUTPUTS], force=force, folder=folder) as out:
            return _run_ur(out, folder, rb, load_plan(plan, rb), seed, scale, progress)
    with Outputs([folder / n for n in OUTPUTS], force=force, folder=folder) as out:
        return _run(out, folder, seed, scale, progress)


def _run(
    out: Outputs,
    folder: Path,
    seed: int,
    scale: float,
    progress: Callable[[str], None],
) -> DemoResult:
    """Do the demo's work; every output goes into ``out``, published when all are there.

    The validation before calibration needs only the generated module, so it runs in a
    second process (:func:`_second_process`) while this one measures, identifies and
    validates after calibration: the two twin runs are the demo's longest stages.
    """
    files = example_files()
    robot = load_robot(files["robot"])
    plan = load_plan(files["plan"], robot)
    setup = load_setup(files["validation"])
    seconds: dict[str, float] = {}
    truth = random_errors(robot, scale, np.random.default_rng([seed, 1]))
    wall = time.perf_counter()

    def step(n, text):
        progress(f"[{n}/7] {text} …")
        return time.perf_counter()

    t = step(1, "generating the V+ module (calibration and validation programs)")
    options = GenOptions(validation=setup)
    text = module_text(robot, plan, options)
    seconds["generate"] = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as tmp, _second_process() as pool:
        disk = Path(tmp)
        step(2, "validation before calibration (wc.vcfg, wc.vpln), in a second process")
        validate = partial(_validation_logs, robot, plan, truth, setup, text, seed=seed + 7)
        before = pool.submit(validate, disk / "before", controller={}, run=1)
        t = step(3, "measurement run in the digital twin (wc.mount, wc.run)")
        # a realistic encoder: its scale off within the robot file's tolerance, 0.5 K
        encoder = realistic_encoder(robot.encoder, np.random.default_rng([seed, 4]))
        run = measure_in_twin(
            robot,
            plan,
            truth,
            disk / "cal",
            options=options,
            text=text,
            seed=seed,
            encoder_truth=encoder,
        )
        if run.run is None or run.run.status != "completed":
            raise WirecalError(f"the twin's measurement run stopped: {run.run or run.mount}")
        seconds["measure"] = time.perf_counter() - t
        t = step(4, "identification on the PC (step-by-step and joint)")
        _, result, verdict = _identify(out, folder, "WCLOG.CSV", run.log, robot, plan)
        seconds["solve"] = time.perf_counter() - t
        t = step(5, "identification on the controller (wc.solve, wc.solve2 in the twin)")
        controller = compare_controller(result, disk / "ctl", text=text)
        seconds["controller"] = time.perf_counter() - t
        polished_difference = controller.polished_max_difference
        assert polished_difference is not None, "a V+ comparison always runs wc.solve2"
        identified = result.estimates[result.recommended].as_dict()
        step(6, "validation after calibration (wc.vcfg, wc.vpln)")
        logs = {"after": validate(disk / "after", controller=identified, run=2)}
        logs["before"] = before.result()
        for name in ("before", "after"):
            seconds[f"validate {name}"] = logs[name].seconds
        validations = [
            Validation(
                "configuration",
                *(
                    config_discrepancy(
                        read_validation_log(logs[k].configuration, "configuration"),
                        robot.encoder.counter,
                    )
                    for k in ("before", "after")
                ),
            ),
            Validation(
                "plane",
                *(
                    plane_residuals(read_validation_log(logs[k].plane, "plane"))[0]
                    for k in ("before", "after")
                ),
            ),
        ]
        t = step(7, "report")
        html = render_report(
            result, validations, controller, truth, plausibility=verdict.patch_field()
        )
        seconds["report"] = time.perf_counter() - t
        for name, path in (
            ("WCVCFG1.CSV", logs["before"].configuration),
            ("WCVPLN1.CSV", logs["before"].plane),
            ("WCVCFG2.CSV", logs["after"].configuration),
            ("WCVPLN2.CSV", logs["after"].plane),
        ):
            out.put(folder / name, path.read_text(encoding="ascii"))
    out.put(folder / "WIRECAL.V2", text)
    _put_truth_and_patch(out, folder, robot, plan, truth, seed, result, verdict, "WCLOG.CSV")
    out.put(folder / "report.html", html)
    return DemoResult(
        folder,
        validations,
        _tool_errors(robot, truth, identified),
        polished_difference,
        seconds,
        wall_s=time.perf_counter() - wall,
        predicted_mm=result.predicted[result.recommended]["mean"],
        bound_mm=_bound(result),
        encoder_scale_ppm=encoder.scale_ppm,
    )


class ValidationLogs(NamedTuple):
    """A validation run's two logs (wc.vcfg, wc.vpln) and its own duration."""

    configuration: Path
    plane: Path
    seconds: float


def _second_process() -> ProcessPoolExecutor:
    """One worker process, forked where the platform forks safely.

    A forked worker inherits every import and the module that ``module_text`` parsed and
    checked (the parser keeps the last few); elsewhere it starts afresh.
    """
    fork = sys.platform.startswith("linux") and "fork" in mp.get_all_start_methods()
    return ProcessPoolExecutor(max_workers=1, mp_context=mp.get_context("fork" if fork else None))


def _validation_logs(
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    setup: Setup,
    text: str,
    disk: Path,
    *,
    controller: dict[str, float],
    run: int,
    seed: int,
) -> ValidationLogs:
    """Run both validation programs in the twin: their logs and the seconds it took.

    ``controller``: the offsets the controller believes ({} before calibration).
    """
    t = time.perf_counter()
    v = run_validation(
        robot, plan, truth, setup, disk, text, controller=controller, run=run, seed=seed
    )
    for outcome in (v.configuration, v.plane):
        if outcome.status != "completed":
            raise WirecalError(f"the twin's validation run stopped: {outcome}")
    return ValidationLogs(v.configuration_log, v.plane_log, time.perf_counter() - t)


def _identify(
    out: Outputs, folder: Path, name: str, path: Path, robot: Robot, plan: Plan
) -> tuple[str, SolveResult, Plausibility]:
    """Publish the twin's log as ``name``, read it back and identify; the gate's verdict.

    The verdict comes before anything acts on the result.
    """
    log_text = path.read_text(encoding="ascii")
    out.put(folder / name, log_text)
    log = replace(read_log(path), source=str(folder / name))
    result = solve(robot, plan, check_log(log, plan, robot))
    return log_text, result, gate(result, result.recommended)


def _run_ur(
    out: Outputs,
    folder: Path,
    robot: Robot,
    plan: Plan,
    seed: int,
    scale: float,
    progress: Callable[[str], None],
) -> DemoResult:
    """Do the URScript demo's work (module docstring); every output goes into ``out``."""
    seconds: dict[str, float] = {}
    truth = random_errors(robot, scale, np.random.default_rng([seed, 1]))

    def step(n, text):
        progress(f"[{n}/6] {text} …")
        return time.perf_counter()

    t = step(1, "generating the URScript programs (wc_mount, wc_check, wc_run)")
    texts = scripts(robot, plan)
    seconds["generate"] = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as tmp:
        disk = Path(tmp)
        t = step(2, "measurement run in the digital twin (wc_mount, wc_run → wirecal receive)")
        run = measure_ur_in_twin(robot, plan, truth, disk / "cal", texts=texts, seed=seed)
        if run.programs.run is None or run.programs.run.status != "completed":
            raise WirecalError(f"the twin's measurement run stopped: {run.programs.run}")
        if not run.received.complete:
            raise WirecalError(f"wirecal receive got no complete log: {run.received.stopped}")
        seconds["measure"] = time.perf_counter() - t
        t = step(3, "identification on the PC (step-by-step and joint)")
        log_text, result, verdict = _identify(out, folder, "run.csv", run.log, robot, plan)
        identified = result.estimates[result.recommended].as_dict()
        on_controller = parse_result(result_in_log(log_text) or "", "run.csv (wc_solve)")
        controller = max(
            abs(on_controller[n] - v) for n, v in result.estimates["stepwise"].as_dict().items()
        )
        seconds["solve"] = time.perf_counter() - t
        t = step(4, "validation: the run again over new points, with unmodelled errors")
        vplan = distance_plan(robot, plan, seed=seed)
        check = measure_ur_in_twin(
            robot,
            vplan,
            truth,
            disk / "val",
            texts=scripts(robot, vplan, UrOptions(solver=False)),
            seed=seed + 7,
            unmodelled=Unmodelled(),
        )
        if not check.received.complete:
            raise WirecalError(f"the twin's validation run stopped: {check.programs.run}")
        vm = check_log(read_log(check.log), vplan, robot)
        validation = Validation(
            "distance",
            Stats.of(distance_residuals(robot, vm, {})),
            Stats.of(distance_residuals(robot, vm, identified)),
        )
        out.put(folder / "validation.csv", check.log.read_text(encoding="ascii"))
        seconds["validate"] = time.perf_counter() - t
    t = step(5, "patch and Universal Robots' deltas")
    for name, text in texts.items():
        out.put(folder / name, text)
    _put_truth_and_patch(out, folder, robot, plan, truth, seed, result, verdict, "run.csv")
    seconds["patch"] = time.perf_counter() - t
    t = step(6, "report")
    out.put(
        folder / "report.html",
        render_report(result, [validation], None, truth, plausibility=verdict.patch_field()),
    )
    seconds["report"] = time.perf_counter() - t
    return DemoResult(
        folder,
        [validation],
        _tool_errors(robot, truth, identified),
        controller,
        seconds,
        UR_OUTPUTS,
        predicted_mm=result.predicted[result.recommended]["mean"],
        bound_mm=_bound(result),
    )


def _bound(result: SolveResult) -> float | None:
    """Return the recommended method's 95 % bound (None: the tool error is unbounded)."""
    best = result.budgets.get(result.recommended)
    return None if best is None else best.bound


def _put_truth_and_patch(
    out: Outputs,
    folder: Path,
    robot: Robot,
    plan: Plan,
    truth: dict[str, float],
    seed: int,
    result: SolveResult,
    verdict: Plausibility,
    log_name: str,
) -> None:
    """Queue the truth file and the recommended estimate's patch (solved from ``log_name``)."""
    out.put(folder / "truth.toml", truth_text(robot, truth, seed))
    put_patch(
        out,
        folder / "patch.toml",
        robot,
        result.estimates[result.recommended],
        plan_fingerprint=plan.fingerprint(),
        log_path=log_name,
        log_sha256=result.measurements.sha256,
        version=__version__,
        plausibility=verdict.patch_field(),
        unchecked=result.unchecked,
    )


def _tool_errors(robot: Robot, truth: dict[str, float], identified: dict[str, float]):
    """Return the mean tool-point error against the truth over the workspace, before/after."""
    q = workspace(robot)
    return {
        name: error_vs_truth_mm(robot, truth, believed, q)
        for name, believed in (("before", {}), ("after", identified))
    }
