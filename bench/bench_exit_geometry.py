"""What the encoder's wire exit costs: an eyelet's cone and edge, a guide pulley modelled.

Prints (Viper s650 example, the paper's θ0; about three minutes on one core):

1. the edge wrap ρ(φ − sin φ) of a 1 mm eyelet edge at a few exit angles;
2. what ``wirecal plan`` can still plan when an eyelet keeps the wire within ±max_exit_deg
   of an axis near the paper plan's mean wire direction;
3. the paper plan (historical, its wire up to 85° off that axis) simulated with the eyelet
   edge the model leaves out: mean tool-point error after calibration against the truth;
4. a robot with a 5 mm swivel guide pulley, simulated and solved with the pulley model,
   and with the point model (the pulley ignored); then a plan designed for the pulley.

Run: python bench/bench_exit_geometry.py
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np

import wirecal
from wirecal.formats.fileio import read_toml
from wirecal.formats.plan_file import load_plan
from wirecal.formats.robot_file import robot_from_dict
from wirecal.solver.accuracy import workspace
from wirecal.solver.errors import WirecalError
from wirecal.solver.exit_geometry import far_field_edge_wrap_mm
from wirecal.solver.kinematics import tool_position
from wirecal.solver.plan.exit import unmodelled_exit_mm

VIPER = Path(__file__).resolve().parents[1] / "examples" / "viper_s650"
THETA0 = np.array([0.0, -90.0, 210.0, -90.0, 0.0, -90.0])
AXIS = [-0.64, 0.0, 0.768]  # about the paper plan's mean wire direction
TRUTH = {"th2": 0.3, "th3": -0.2, "a2": 0.1, "d4": -0.1}
SEEDS = range(5)


def robot(**encoder) -> wirecal.Robot:
    data = copy.deepcopy(read_toml(VIPER / "robot.toml", "robot file"))
    data["encoder"].update(encoder)
    if encoder:  # no assumed sag (the simulations have none): over an eyelet edge or a
        # pulley the sagged θ0 point lies inside the bend's circle and solve refuses
        data["calibration"]["gravity_sag_deg_per_m"] = 0.0
    return robot_from_dict(data, "viper")


def tool_error_mm(rb, plan, solve_with=None) -> dict[str, float]:
    """Mean tool-point error over 1000 workspace configurations, mean over the seeds."""
    solve_with = solve_with or rb
    q = np.radians(workspace(rb, 1000))
    true_p = tool_position(rb.model(TRUTH), q)
    out: dict[str, list[float]] = {}
    for seed in SEEDS:
        text = wirecal.simulate_log(rb, plan, TRUTH, seed=seed)
        m = wirecal.check_log(wirecal.parse_log(text, "sim.csv"), plan, solve_with)
        for method, est in wirecal.solve(solve_with, plan, m).estimates.items():
            p = tool_position(solve_with.model(est.as_dict()), q)
            out.setdefault(method, []).append(float(np.linalg.norm(p - true_p, axis=1).mean()))
    return {k: float(np.mean(v)) for k, v in out.items()}


def main() -> None:
    print("1. edge wrap of a 1 mm eyelet edge, far from the exit: rho*(phi - sin phi)")
    for phi in (3, 10, 30, 45, 60, 75, 85):
        print(f"   {phi:3d} deg: {far_field_edge_wrap_mm(phi, 1.0):.4f} mm")

    print("2. wirecal plan at the paper's theta0 with an eyelet cone (10 parameters asked)")
    for cone in (90, 75, 60, 45, 30, 3):
        rb = robot(exit="eyelet", axis=AXIS, max_exit_deg=float(cone), exit_edge_radius_mm=1.0)
        try:
            d = wirecal.design(rb, THETA0)
            print(
                f"   ±{cone:2d} deg: {len(d.plan.order):2d} planned, predicted joint "
                f"{d.predicted['joint']:.4f} mm, step-by-step {d.predicted['stepwise']:.4f} mm"
            )
        except WirecalError:
            print(f"   ±{cone:2d} deg:  0 planned (no parameter can be isolated)")
    point = robot()
    d = wirecal.design(point, THETA0)
    print(
        f"   point exit: {len(d.plan.order)} planned, predicted joint "
        f"{d.predicted['joint']:.4f} mm, step-by-step {d.predicted['stepwise']:.4f} mm"
    )

    print("3. the paper plan with an eyelet edge the model leaves out (mean tool error, mm)")
    plan = load_plan(VIPER / "paper_plan.toml", point)
    print(f"   point exit:        {tool_error_mm(point, plan)}")
    for rho in (0.25, 0.5, 1.0):
        rb = robot(exit="eyelet", axis=AXIS, max_exit_deg=90.0, exit_edge_radius_mm=rho)
        wrap = unmodelled_exit_mm(rb, plan)
        print(
            f"   edge {rho:4.2f} mm (wrap mean {wrap.mean():.3f}, max {wrap.max():.3f} mm): "
            f"{tool_error_mm(rb, plan)}"
        )

    print("4. a 5 mm swivel guide pulley, the paper plan (mean tool error, mm)")
    rb = robot(exit="pulley", axis=AXIS, pulley_radius_mm=5.0)
    plan = load_plan(VIPER / "paper_plan.toml", rb)
    print(f"   solved with the pulley model: {tool_error_mm(rb, plan)}")
    print(f"   solved with the point model:  {tool_error_mm(rb, plan, solve_with=point)}")
    d = wirecal.design(rb, THETA0)
    print(
        f"   plan designed for the pulley ({len(d.plan.order)} planned, predicted joint "
        f"{d.predicted['joint']:.4f} mm): {tool_error_mm(rb, d.plan)}"
    )


if __name__ == "__main__":
    main()
