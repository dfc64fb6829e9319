"""``wirecal demo``: the whole chain on a shipped robot, in the digital twin.

One pipeline for every registered language (:func:`wirecal.app.languages.registered`):
generate the robot's programs for the plan beside its robot file; run them in the twin on a
robot with random true errors (the log on the controller's disk, or sent over a loopback
socket to ``wirecal receive``); identify on the PC; the controller solver's result (from
the log when the measurement program ends with it, else the language's controller solver
run in the twin on the log's readings); validate; write the patch with the language's
companion; write the report.

Validation: where the language's generator takes a validation setup, a ``validation.toml``
lies beside the robot file and its twin adapter offers ``paper_validation`` (V+: the
Viper s650, the default), the paper's two procedures run before and after calibration
(§3.6.1 configuration change, §3.6.2 plane fit; unmodelled errors on, the controller
believing the patch after), the one before calibration in a second process beside the
rest. Otherwise the measurement programs run again over new points (unmodelled errors on)
and their wire lengths are compared with those the nominal and the calibrated model predict.
The controller solver's runs go to a third process, forked once the identification is
done (it inherits the identification's imports, scipy's optimiser among them, instead of
importing them again), beside the validation after calibration; the report's figures (the
identification's, the validations' histograms) to two drawing processes forked before the
generation, which import matplotlib meanwhile on the other core (:func:`_workers`): the
demo's own process never imports matplotlib.

Every output goes to one folder and none is overwritten unless asked.
"""

from __future__ import annotations

import gc
import multiprocessing as mp
import os
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple, TypeVar

import numpy as np

from wirecal import __version__
from wirecal.app.compare import ControllerComparison, compare_controller
from wirecal.app.gate import gate
from wirecal.app.languages import Registered, registered
from wirecal.app.report import (
    Validation,
    histogram_figure,
    ready_to_draw,
    render_report,
    result_figures,
)
from wirecal.formats.controller_result import parse_result, result_in_log
from wirecal.formats.fileio import Outputs
from wirecal.formats.log import read_log
from wirecal.formats.patch import companion_paths, put_patch
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import load_robot
from wirecal.formats.truth import random_errors, truth_text
from wirecal.formats.validation_files import load_setup, read_validation_log
from wirecal.gen.request import GenRequest
from wirecal.solver.accuracy import error_vs_truth_mm, workspace
from wirecal.solver.counter import Counter
from wirecal.solver.errors import WirecalError
from wirecal.solver.log.measurements import check_log
from wirecal.solver.plan.calibration_plan import Plan
from wirecal.solver.robot import Robot
from wirecal.solver.simulate import EncoderTruth, Unmodelled, realistic_encoder
from wirecal.solver.solve import SolveResult, solve
from wirecal.solver.validation.analysis import Stats, config_discrepancy, plane_residuals
from wirecal.solver.validation.design import Setup, distance_plan, distance_residuals
from wirecal.solver.verdict import Plausibility
from wirecal.twin.adapters import adapter

PLANS = ("paper_plan.toml", "plan.toml")
"""The plan the demo takes beside a robot file: the first of these that exists."""
SOCKET_LOG = "run.csv"
"""The log's name when the programs name no log file (it travels over a socket)."""
PAPER_LOGS = ("WCVCFG1.CSV", "WCVPLN1.CSV", "WCVCFG2.CSV", "WCVPLN2.CSV")
"""The paper's validation logs, before (1) and after (2) calibration."""
DISTANCE_LOG = "validation.csv"
"""The log of the run over new points (the validation without the paper's set-up)."""


@dataclass
class DemoResult:
    """What the demo wrote and measured: its folder and the validations."""

    folder: Path
    validations: list[Validation]
    tool_error_mm: dict[str, float]  # mean over the workspace: before, after
    controller_difference: float  # controller solver vs the PC's estimate (deg, mm)
    seconds: dict[str, float]  # each stage's own time (two of them may run side by side)
    outputs: tuple[str, ...]
    wall_s: float  # the whole demo, start to end
    predicted_mm: float | None = None  # the error budget's total for the recommended method
    bound_mm: float | None = None  # the error budget's 95 % bound for the recommended method
    encoder_scale_ppm: float | None = None  # the twin encoder's true scale error, if modelled

    @property
    def total_s(self) -> float:
        """The demo's time, start to end."""
        return self.wall_s


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


@dataclass(frozen=True)
class Chain:
    """What one demo runs: the robot, its language, the plan, the programs, the file names."""

    robot: Robot
    reg: Registered
    plan: Plan
    setup: Setup | None  # the paper's validation set-up (None: validation over new points)
    request: GenRequest
    log_name: str

    def outputs(self, programs: dict[str, str]) -> tuple[str, ...]:
        """Return every output's name, in the order the demo lists them."""
        patch = [p.name for p in companion_paths(self.robot, "patch.toml")]
        checks = PAPER_LOGS if self.setup is not None else (DISTANCE_LOG,)
        return (
            "truth.toml",
            *programs,
            self.log_name,
            "patch.toml",
            *patch,
            *checks,
            "report.html",
        )


def chain(robot_path: str | Path | None) -> Chain:
    """Read the robot file (the Viper s650's by default), its language and the plan beside it."""
    path = Path(robot_path) if robot_path is not None else example_files()["robot"]
    rb = load_robot(path)
    reg = registered(rb)
    plan = plan_beside(path)
    if plan is None:
        raise WirecalError(
            f"{path}: no {' or '.join(PLANS)} beside it; design one with wirecal plan"
        )
    setup_path = path.with_name("validation.toml")
    paper = (
        setup_path.is_file()
        and "validation" not in reg.generator.refuses
        and reg.adapter.capabilities.paper_validation
    )
    setup = load_setup(setup_path) if paper else None
    request = GenRequest(validation=setup)
    log_name = SOCKET_LOG if "log_file" in reg.generator.refuses else request.log_file
    return Chain(rb, reg, load_plan(plan, rb), setup, request, log_name)


def plan_beside(robot_path: Path) -> Path | None:
    """Return the plan the demo takes beside a robot file: the first of :data:`PLANS` there."""
    return next((p for n in PLANS if (p := robot_path.with_name(n)).is_file()), None)


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

    ``robot``: a robot file with its plan beside it (``paper_plan.toml`` or ``plan.toml``);
    the Viper s650 when not given.
    """
    folder = Path(folder)
    wall = time.perf_counter()
    ch = chain(robot)
    # the names known before the programs are generated: refused before any work
    Outputs([folder / n for n in ch.outputs({})], force=force, folder=folder).check()
    step = _Steps(progress)
    with _fewer_collections(), _workers(DRAWERS) as drawer:
        for _ in range(DRAWERS):  # on the other core, while generating
            drawer.submit(_yielding, _nice(), ready_to_draw)
        t = step(f"generating the {ch.reg.language.title} programs")
        programs = ch.reg.generator.programs(ch.robot, ch.plan, ch.request)
        step.seconds["generate"] = time.perf_counter() - t
        gc.freeze()  # the parsed module and the parser's lines too, before the twin's workers fork
        names = ch.outputs(programs)
        with Outputs([folder / n for n in names], force=force, folder=folder) as out:
            r = _run(out, folder, ch, programs, seed, scale, step, drawer)
    r.outputs, r.wall_s = names, time.perf_counter() - wall
    return r


GC_THRESHOLDS = (10_000, 50, 1_000)
"""The cyclic garbage collector's thresholds during the demo (Python's: 700, 10, 10). The
twin's runs allocate millions of short-lived objects; with Python's thresholds the
collector ran about 150 times per paper validation, a full collection of every object
among them (0.1 s each). Young cycles are still collected, every 10,000 allocations."""


@contextmanager
def _fewer_collections() -> Iterator[None]:
    """Collect cyclic garbage less often during the demo, never the objects it started with.

    The objects alive at the start (and those frozen later: :func:`gc.freeze`) are left
    out of every collection, in the demo's process and its forked workers (whose copies
    of them then stay shared with the demo's: a collection writes to every object it
    visits); :data:`GC_THRESHOLDS` meanwhile. Both undone at the end.
    """
    thresholds = gc.get_threshold()
    gc.freeze()
    gc.set_threshold(*GC_THRESHOLDS)
    try:
        yield
    finally:
        gc.set_threshold(*thresholds)
        gc.unfreeze()


class _Steps:
    """The demo's numbered progress lines and each stage's time."""

    COUNT = 7

    def __init__(self, progress: Callable[[str], None]):
        self.progress = progress
        self.n = 0
        self.seconds: dict[str, float] = {}

    def __call__(self, text: str) -> float:
        self.n += 1
        self.progress(f"[{self.n}/{self.COUNT}] {text} …")
        return time.perf_counter()


def _run(
    out: Outputs,
    folder: Path,
    ch: Chain,
    programs: dict[str, str],
    seed: int,
    scale: float,
    step: _Steps,
    drawer: ProcessPoolExecutor,
) -> DemoResult:
    """Do the demo's work (module docstring) into ``out``; ``drawer``: the drawing workers."""
    robot, plan, reg, seconds = ch.robot, ch.plan, ch.reg, step.seconds
    truth = random_errors(robot, scale, np.random.default_rng([seed, 1]))
    encoder = _true_encoder(reg, robot, seed)
    options = {"seed": seed, **({} if encoder is None else {"encoder_truth": encoder})}
    with tempfile.TemporaryDirectory() as tmp, _workers(1, (drawer,)) as pool, ExitStack() as later:
        disk = Path(tmp)
        before = _start_before(pool, ch, truth, programs, disk / "before", seed)
        beside = "" if before is None else ", the validation before calibration in a second process"
        t = step("measurement run in the digital twin" + beside)
        run = _measure(ch, truth, disk / "cal", programs, options)
        seconds["measure"] = time.perf_counter() - t
        t = step("identification on the PC (step-by-step and joint)")
        log_text, result, verdict = _identify(out, folder, ch.log_name, run.log, robot, plan)
        identified = result.estimates[result.recommended].as_dict()
        seconds["solve"] = time.perf_counter() - t
        t = step("the controller solver's result and the report's figures, in another process")
        solver = later.enter_context(_workers(1, (drawer, pool)))  # forked now: the imports
        controller, figures = _submit_controller(
            solver, drawer, result, log_text, ch, programs, disk
        )
        t = step("validation before and after calibration, with unmodelled errors")
        validations = _validations(
            out, folder, ch, (truth, identified), programs, disk, seed, before
        )
        drawn = [drawer.submit(histogram_figure, v) for v in validations]  # side by side
        seconds |= {} if before is None else {"validate before": before.result().seconds}
        seconds["validate"] = time.perf_counter() - t
        comparison, difference, seconds["controller"] = controller.result()
    companion = reg.language.patch_companion
    t = step("patch" + (f" and patch{companion}" if companion else ""))
    _put_outputs(out, folder, ch, programs, (truth, seed), result, verdict)
    seconds["patch"] = time.perf_counter() - t
    t = step("report")
    drawings: dict[str, Any] = {"figures": figures.result(), "drawn": [d.result() for d in drawn]}
    html = render_report(result, validations, comparison, truth, verdict.patch_field(), **drawings)
    out.put(folder / "report.html", html)
    seconds["report"] = time.perf_counter() - t
    return DemoResult(
        folder,
        validations,
        _tool_errors(robot, truth, identified),
        difference,
        seconds,
        outputs=(),  # run_demo sets them and the wall time once the outputs are published
        wall_s=0.0,
        predicted_mm=result.predicted[result.recommended]["mean"],
        bound_mm=_bound(result),
        encoder_scale_ppm=None if encoder is None else encoder.scale_ppm,
    )


def _submit_controller(
    pool: ProcessPoolExecutor,
    drawer: ProcessPoolExecutor,
    result: SolveResult,
    log_text: str,
    ch: Chain,
    programs: dict[str, str],
    disk: Path,
) -> tuple[Future, Future]:
    """Start the controller solver's runs (a twin worker) and the identification's figures.

    The figures in a drawing worker; both yield to the demo's process (niced). Returns
    the two futures.
    """
    nice = _nice()
    controller = pool.submit(
        _yielding, nice, _controller, result, log_text, ch, programs, disk / "ctl"
    )
    return controller, drawer.submit(_yielding, nice, result_figures, result)


def _measure(
    ch: Chain,
    truth: dict[str, float],
    disk: Path,
    programs: dict[str, str],
    options: dict[str, Any],
) -> Any:
    """Return the twin's measurement run of the programs; refuse one that stopped."""
    run = ch.reg.measure(ch.robot, ch.plan, truth, disk, programs, **options)
    if not run.complete:
        raise WirecalError(f"the twin's measurement run stopped: {run.stopped}")
    return run


def _true_encoder(reg: Registered, robot: Robot, seed: int) -> EncoderTruth | None:
    """Return a realistic encoder (its scale off within tolerance) where the twin takes one."""
    if not reg.adapter.capabilities.encoder_truth:
        return None
    return realistic_encoder(robot.encoder, np.random.default_rng([seed, 4]))


def _start_before(
    pool: ProcessPoolExecutor,
    ch: Chain,
    truth: dict[str, float],
    programs: dict[str, str],
    disk: Path,
    seed: int,
) -> Future[ValidationLogs] | None:
    """Start the paper's validation before calibration in ``pool`` (None without a setup)."""
    if ch.setup is None:
        return None
    return pool.submit(_paper_logs, ch.reg.language.key, ch, truth, programs, disk, {}, 1, seed)


def _validations(
    out: Outputs,
    folder: Path,
    ch: Chain,
    errors: tuple[dict[str, float], dict[str, float]],
    programs: dict[str, str],
    disk: Path,
    seed: int,
    before: Future[ValidationLogs] | None,
) -> list[Validation]:
    """Validate before and after calibration; ``errors``: the truth and the identified.

    The paper's validation (its run ``before`` calibration started in a second process) or,
    without a validation setup, the distance validation. Writes the logs into ``out``.
    """
    truth, identified = errors
    if before is None:
        return [_distance_validation(out, folder, ch, truth, disk, identified, seed)]
    key = ch.reg.language.key
    # after calibration first, here, while the run before calibration ends in its process
    after = _paper_logs(key, ch, truth, programs, disk / "after", identified, 2, seed)
    logs = {"before": before.result(), "after": after}
    for name, path in zip(PAPER_LOGS, (p for k in logs for p in logs[k][:2]), strict=True):
        out.put(folder / name, path.read_text(encoding="ascii"))
    return _paper_validations(logs, ch.robot.encoder.counter)


def _controller(
    result: SolveResult, log_text: str, ch: Chain, programs: dict[str, str], disk: Path
) -> tuple[ControllerComparison | None, float, float]:
    """Return the controller solver's comparison (if run here), its largest difference, seconds.

    From the log when the measurement program ends with the solver (against the PC's
    stepwise estimate); else the language's solvers in the twin on the log's readings
    (:func:`~wirecal.app.compare.compare_controller`).
    """
    t = time.perf_counter()
    found = result_in_log(log_text)
    if found is not None:
        on_controller = parse_result(found, f"{ch.log_name} (controller solver)")
        pc = result.estimates["stepwise"].as_dict()
        difference = max(abs(on_controller[n] - v) for n, v in pc.items())
        return None, difference, time.perf_counter() - t
    comparison = compare_controller(result, disk, programs=programs)
    differences = (comparison.stepwise_max_difference, comparison.polished_max_difference)
    return comparison, max(d for d in differences if d is not None), time.perf_counter() - t


class ValidationLogs(NamedTuple):
    """A paper validation run's two logs (configuration, plane) and its own duration."""

    configuration: Path
    plane: Path
    seconds: float


T = TypeVar("T")

YIELD_NICE = 5
"""How far the work with the most slack (the controller solver's runs, the report's figures
of the identification: the report needs them last) yields to the validations on the
processor (nice): on two cores, the validation after calibration, on the path of the
demo's end, keeps a core of its own."""


def _yielding(parent_nice: int | None, work: Callable[..., T], *args: Any) -> T:
    """Do ``work`` in a worker niced :data:`YIELD_NICE` below the demo (where it can)."""
    if parent_nice is not None:
        behind = parent_nice + YIELD_NICE - os.nice(0)
        if behind > 0:
            os.nice(behind)
    return work(*args)


def _nice() -> int | None:
    """Return the demo's own nice value (None where the platform has none)."""
    return os.nice(0) if hasattr(os, "nice") else None


DRAWERS = 2
"""The demo's drawing workers, forked before the programs are generated: they import
matplotlib on the other core while the demo generates, then draw the report's figures —
the identification's, then the two validations' histograms side by side (the report
waits for them last)."""


@contextmanager
def _workers(
    count: int, beside: tuple[ProcessPoolExecutor, ...] = ()
) -> Iterator[ProcessPoolExecutor]:
    """Start ``count`` worker processes now, forked where it is safe.

    :func:`_start_method` decides, ``beside`` being the demo's pools already running; a
    first task starts the workers at once, so they fork in the state it checked. A forked
    worker inherits every import and, forked after the generation, the module the
    generator parsed and checked (the parser keeps the last few); elsewhere it starts
    afresh. When the demo stops (Ctrl-C, an error), the workers are ended at once instead
    of finishing their runs.
    """
    context = mp.get_context(_start_method(beside))
    pool = ProcessPoolExecutor(max_workers=count, mp_context=context)
    pool.submit(int)  # fork now (a fork context starts every worker at the first task)
    try:
        yield pool
    except BaseException:
        for worker in list((pool._processes or {}).values()):
            worker.kill()  # SIGKILL: a forked worker inherits the SIGTERM handler
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def _start_method(beside: tuple[ProcessPoolExecutor, ...] = ()) -> str | None:
    """Return "fork" where the platform forks and no thread but ``beside``'s own runs.

    A fork copies the calling thread alone: a lock another thread holds stays held in the
    child, which may deadlock (Python 3.12+ warns of a fork beside threads). An executor's
    own threads (its manager, its call queue's feeder) take only that executor's locks,
    which the workers of another pool never take (they have their own queues), and the
    interpreter resets its own locks in the child. Any other thread — a receiver's, a BLAS
    pool's (the OS's thread count tells) — makes it "forkserver", whose single-threaded
    server forks the workers. None (the platform's default) where fork is not the rule.
    """
    if not sys.platform.startswith("linux") or "fork" not in mp.get_all_start_methods():
        return None
    known = {threading.current_thread().ident}
    for pool in beside:  # CPython's attribute names (3.9-3.13); absent: not known, no fork
        queue = getattr(pool, "_call_queue", None)
        for thread in (
            getattr(pool, "_executor_manager_thread", None),
            getattr(queue, "_thread", None),
        ):
            if thread is not None:
                known.add(thread.ident)
    running = {t.ident for t in threading.enumerate()}
    alone = running <= known and len(os.listdir("/proc/self/task")) == len(running)
    return "fork" if alone else "forkserver"


def _paper_logs(
    key: str,
    ch: Chain,
    truth: dict[str, float],
    programs: dict[str, str],
    disk: Path,
    controller: dict[str, float],
    run: int,
    seed: int,
) -> ValidationLogs:
    """Run the paper's validation programs in the twin: their logs and the seconds it took.

    ``key``: the language, whose twin adapter offers ``paper_validation``; ``controller``:
    the offsets the controller believes ({} before calibration).
    """
    t = time.perf_counter()
    if ch.setup is None:
        raise WirecalError("the paper's validation needs validation.toml beside the robot file")
    v = adapter(key).paper_validation(
        ch.robot,
        ch.plan,
        truth,
        ch.setup,
        disk,
        programs,
        controller=controller,
        run=run,
        seed=seed + 7,
    )
    for outcome in (v.configuration, v.plane):
        if outcome.status != "completed":
            raise WirecalError(f"the twin's validation run stopped: {outcome}")
    return ValidationLogs(v.configuration_log, v.plane_log, time.perf_counter() - t)


def _paper_validations(logs: dict[str, ValidationLogs], counter: Counter) -> list[Validation]:
    """Return both procedures' before and after from the logs (§3.6.1, §3.6.2)."""
    return [
        Validation(
            "configuration",
            *(
                config_discrepancy(
                    read_validation_log(logs[k].configuration, "configuration"), counter
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


def _distance_validation(
    out: Outputs,
    folder: Path,
    ch: Chain,
    truth: dict[str, float],
    disk: Path,
    identified: dict[str, float],
    seed: int,
) -> Validation:
    """Run the measurement programs again over new points; wire lengths vs both models."""
    robot, reg = ch.robot, ch.reg
    vplan = distance_plan(robot, ch.plan, seed=seed)
    request = ch.request
    if "solver" not in reg.generator.refuses:
        request = replace(request, solver=False)  # no controller solve on the new points
    programs = reg.generator.programs(robot, vplan, request)
    check = reg.measure(
        robot, vplan, truth, disk / "val", programs, seed=seed + 7, unmodelled=Unmodelled()
    )
    if not check.complete:
        raise WirecalError(f"the twin's validation run stopped: {check.stopped}")
    vm = check_log(read_log(check.log), vplan, robot)
    out.put(folder / DISTANCE_LOG, check.log.read_text(encoding="ascii"))
    return Validation(
        "distance",
        Stats.of(distance_residuals(robot, vm, {})),
        Stats.of(distance_residuals(robot, vm, identified)),
    )


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


def _bound(result: SolveResult) -> float | None:
    """Return the recommended method's 95 % bound (None: the tool error is unbounded)."""
    best = result.budgets.get(result.recommended)
    return None if best is None else best.bound


def _put_outputs(
    out: Outputs,
    folder: Path,
    ch: Chain,
    programs: dict[str, str],
    truth_seed: tuple[dict[str, float], int],
    result: SolveResult,
    verdict: Plausibility,
) -> None:
    """Queue the programs, the truth file (errors, seed) and the recommended patch."""
    for name, program in programs.items():
        out.put(folder / name, program)
    log_sha256 = result.measurements.sha256
    out.put(folder / "truth.toml", truth_text(ch.robot, *truth_seed, log_sha256))
    put_patch(
        out,
        folder / "patch.toml",
        ch.robot,
        result.estimates[result.recommended],
        plan_fingerprint=ch.plan.fingerprint(),
        log_path=ch.log_name,
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
