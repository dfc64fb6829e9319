"""What a generation costs, per language: the pre-flight, the rendering, the checker.

``Generator.programs()`` = the pre-flight (limits, wire range, cell, software line) +
the language's rendering + its own checker over the output (issue 33). For each shipped
example, the CPU time of each part and of the whole, each part once warmed (its grammars
built), then timed with every memory of texts parsed or checked and of frames computed
forgotten, as a generation of another plan meets it (V+'s rendering parses its module, the
checker then finds it parsed). With ``--before`` (a
checkout of the code before), each run a fresh process per tree, the two trees' runs
interleaved (:mod:`interleaved`), medians and the ratio now / before, and whether the two
generated the same programs (and cell checks' answers), byte for byte. Last, per example,
the cell check of 200 short moves (:func:`short_moves`), the pre-flight's check as a twin
runs it move by move; the run timing a plan's consumers ask for (:func:`timelines`) and two
runs of its programs on the twin (:func:`twin_runs`), and where it ships a validation
setup, its plate's grid asked for twice (:func:`plate_grids`), with the logs, timelines and
grids among what must be the same.

    python bench/bench_generation.py [--runs N] [--before CHECKOUT]
"""

from __future__ import annotations

import hashlib
import json
import time
from collections.abc import Callable
from itertools import pairwise
from pathlib import Path

from interleaved import bench_main

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SHIPPED = ("viper_s650", "ur5e", "abb_irb120")
"""The examples timed, each with its shipped plan (the demo's, :func:`plan_beside`)."""


def forget() -> None:
    """Forget every text checked or parsed and every configuration's frames kept."""
    from wirecal.gen.preflight import _lint
    from wirecal.lang.rapid import parser as rapid
    from wirecal.lang.urscript import parser as urscript
    from wirecal.lang.vplus import parser as vplus
    from wirecal.solver import kinematics, run_parameters
    from wirecal.solver.validation import design

    if hasattr(run_parameters, "_KEPT_MOVES"):  # the moves' profiles kept (not before)
        run_parameters._KEPT_MOVES = type(run_parameters._KEPT_MOVES)(run_parameters.KEPT_MOVES)
    if hasattr(design, "_KEPT_GRIDS"):  # the plates' grids kept (not before)
        design._KEPT_GRIDS = type(design._KEPT_GRIDS)(design.KEPT_GRIDS)
    for cache in (_lint, rapid._parse_long, rapid._parse_short, urscript._parse_program):
        cache.cache_clear()
    vplus._parse_module.cache_clear()
    kinematics._kept_frames.cache_clear()


def cpu_s(work: Callable[[], object], repeat: int = 4) -> float:
    """CPU time (s) of a call of ``work`` (the mean of ``repeat``), all memory forgotten first."""
    spent = 0.0
    for _ in range(repeat):
        forget()
        t0 = time.process_time()
        work()
        spent += time.process_time() - t0
    return spent / repeat


def _parts(name: str) -> tuple[dict[str, Callable[[], object]], str]:
    """Return an example's parts to time (once warmed) and its language's key."""
    from wirecal.app.languages import registered
    from wirecal.gen.preflight import output_problems, preflight
    from wirecal.gen.request import GenRequest

    robot, plan = _example(name)
    gen, request = registered(robot).generator, GenRequest()
    out = gen.programs(robot, plan, request)  # warm: grammars, tables
    return {
        "pre-flight": lambda: preflight(robot, plan, request, gen.language),
        "render": lambda: gen.render(robot, plan, request),
        "checker": lambda: output_problems(robot, out, gen.language),
        "programs()": lambda: gen.programs(robot, plan, request),
    }, gen.key


def _example(name: str):
    """Return an example's robot and its shipped plan (the demo's)."""
    from wirecal.app.demo import plan_beside
    from wirecal.formats.plan_file import load_plan
    from wirecal.formats.robot_file import load_robot

    robot = load_robot(EXAMPLES / name / "robot.toml")
    plan_path = plan_beside(EXAMPLES / name / "robot.toml")
    assert plan_path is not None
    return robot, load_plan(plan_path, robot)


def short_moves(name: str) -> Callable[[], object]:
    """Return the cell checks of 200 short moves (0.05–3°) of an example's arm, as a twin's.

    Each :func:`~wirecal.solver.cell.check.move_sweep` of a random walk from a random pose
    (seed 0), every gap exact: the check ``wirecal gen``'s pre-flight runs over a plan's
    moves, of a few configurations each.
    """
    import numpy as np

    from wirecal.formats.robot_file import load_robot
    from wirecal.solver.cell.check import move_sweep
    from wirecal.solver.kinematics import tool_position

    robot = load_robot(EXAMPLES / name / "robot.toml")
    rng = np.random.default_rng(0)
    lo, hi = robot.limits_deg(body=False)
    p0 = tool_position(robot.nominal, np.radians(rng.uniform(lo, hi))[None])[0]
    walk = [rng.uniform(lo, hi)]
    for _ in range(200):
        step = rng.normal(0.0, rng.choice([0.05, 0.5, 3.0]), robot.n_joints)
        walk.append(np.clip(walk[-1] + step, lo, hi))
    return lambda: [move_sweep(robot, robot.nominal, p0, a, b) for a, b in pairwise(walk)]


def timelines(robot, plan) -> Callable[[], object]:
    """Return the run timing of a plan as its consumers ask for it, each its own timeline.

    The program's SPEEDs and the simulated log's ``t_s`` (the default run), the log's timer
    check (the fastest run), the paper's run: three timelines of the same moves.
    """
    from wirecal.solver.log.checks import FASTEST_RUN
    from wirecal.solver.run_parameters import DEFAULT_RUN, PAPER_RUN, run_timeline

    return lambda: [run_timeline(robot, plan, run) for run in (DEFAULT_RUN, FASTEST_RUN, PAPER_RUN)]


def twin_runs(robot, plan) -> Callable[[], list[str]]:
    """Return two runs of a plan's programs on the twin (offsets of 0.3 deg or mm): their logs.

    The same programs run again on the same arm, as a rerun or another check of one plan
    meets them.
    """
    import tempfile

    from wirecal.app.twin_runs import measure_in_twin

    truth = {name: 0.3 for name in plan.order}

    def run() -> str:
        with tempfile.TemporaryDirectory() as folder:
            r = measure_in_twin(robot, plan, truth, Path(folder), seed=1)
            return Path(r.log).read_text()

    return lambda: [run(), run()]


def plate_grids(robot, name: str) -> Callable[[], list] | None:
    """Return the plate's grid of an example's validation setup asked for twice (None: none).

    A validation module's generation and a check of the same setup ask for it again.
    """
    from wirecal.formats.validation_files import load_setup
    from wirecal.solver.validation.design import plate_grid

    path = EXAMPLES / name / "validation.toml"
    if not path.exists():
        return None
    return lambda: [plate_grid(robot, load_setup(path)) for _ in range(2)]


def child() -> None:
    """One run in this process: print each example's parts' CPU seconds and digests as JSON."""
    found: dict[str, dict] = {"cpu_s": {}, "digest": {}}
    for name in SHIPPED:
        parts, key = _parts(name)
        for part, work in parts.items():
            found["cpu_s"][f"{name} {key} {part}"] = cpu_s(work)
        moves = short_moves(name)
        found["cpu_s"][f"{name} 200 short moves' cell checks"] = cpu_s(moves)
        robot, plan = _example(name)
        timing, twin = timelines(robot, plan), twin_runs(robot, plan)
        found["cpu_s"][f"{name} three timelines of its plan"] = cpu_s(timing)
        found["cpu_s"][f"{name} two twin runs of its programs"] = cpu_s(twin, repeat=1)
        text = json.dumps(parts["programs()"](), sort_keys=True).encode() + repr(moves()).encode()
        text += repr(timing()).encode() + json.dumps(twin()).encode()
        if (grids := plate_grids(robot, name)) is not None:
            found["cpu_s"][f"{name} its plate's grid twice"] = cpu_s(grids, repeat=2)
            text += b"".join(
                json.dumps(i).encode() + p.tobytes() + t.tobytes() for i, p, t in grids()
            )
        found["digest"][name] = hashlib.sha256(text).hexdigest()[:16]
    print(json.dumps(found))


def main() -> None:
    """Time this tree and ``--before``'s alternately; print the medians and ratios."""
    bench_main("bench_generation", child, __doc__, "programs and answers")


if __name__ == "__main__":
    main()
