"""Gravity compliance: torques against hand-derived ones, derivatives against finite
differences, and a rigid arm unchanged by the model."""

from __future__ import annotations

import copy
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from wirecal.formats.robot_file import load_robot, robot_file_text, robot_from_dict
from wirecal.solver.distance import wire_jacobian, wire_lengths
from wirecal.solver.errors import WirecalError
from wirecal.solver.gravity import STANDARD_GRAVITY_M_S2, MassModel, default_masses
from wirecal.solver.kinematics import (
    Model,
    frames,
    gravity_torques,
    tool_gradient,
    tool_jacobian,
    tool_position,
    with_errors,
)

G = STANDARD_GRAVITY_M_S2
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
COMPLIANCE = np.array([2.0, 6.0, 8.0, 4.0, 3.0, 2.0]) * 1e-6  # rad/(N·m): issue 30's range
NAMES = ("th2", "th3", "al2", "a2", "d4", "tool_x", "c1", "c2", "c3", "c4", "c5", "c6")


def _shoulder_arm(mass_kg: float, com_mm: float, payload_kg: float = 0.0) -> Model:
    """A vertical joint 1, a horizontal joint 2 (z2 = +y at q1 = 0), a 400 mm link 2.

    At q1 = 0 link 2 points along x2 = (cos q2, 0, −sin q2): +x at q2 = 0, down at 90°.
    """
    dh = np.array([[0.0, 0.0, 0.0, 0.0], [-np.pi / 2, 0.0, 0.0, 0.0], [0.0, 400.0, 0.0, 0.0]])
    masses = MassModel(
        np.array([5.0, mass_kg, 0.0]),
        np.array([[0.0, 0.0, 0.0], [com_mm, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        payload_mass_kg=payload_kg,
        payload_com_mm=np.array([50.0, 0.0, 0.0]),
    )
    return Model(dh, np.zeros(3), masses=masses)


@pytest.mark.parametrize("q2_deg", [0.0, 30.0, 90.0, -90.0, 180.0, -135.0])
def test_torque_of_a_horizontal_link_is_m_g_h_cos(q2_deg):
    # by hand: r = h·x2 from o2 on the axis z2 = +y, F = (0, 0, −m g): τ2 = m g h cos q2
    # (N·mm → N·m); joint 1 is vertical, so gravity has no torque about it; the payload
    # sits 50 mm along x3 from o3 (400 mm from o2), and joint 3 (q3 = 0) holds it alone
    m, h, pay = 3.0, 150.0, 2.0
    model = _shoulder_arm(m, h, pay)
    q = np.radians([[20.0, q2_deg, 0.0]])
    tau = gravity_torques(model, frames(model, q))[0]
    c2 = np.cos(np.radians(q2_deg))
    assert tau[0] == pytest.approx(0.0, abs=1e-9)
    assert tau[1] == pytest.approx((m * h + pay * 450.0) * G * c2 / 1000.0, abs=1e-9)
    assert tau[2] == pytest.approx(pay * 50.0 * G * c2 / 1000.0, abs=1e-9)


def test_positive_compliance_bends_a_horizontal_link_down():
    model = _shoulder_arm(3.0, 150.0)
    bent = replace(model, compliance=np.array([0.0, 1e-4, 0.0]))
    q = np.zeros((1, 3))
    drop = tool_position(bent, q)[0, 2] - tool_position(model, q)[0, 2]
    # τ2 = 3·150·g/1000 = 4.413 N·m, δθ2 = 4.413e-4 rad, the tip 400 mm out drops 0.1765 mm
    assert drop == pytest.approx(-400.0 * np.sin(1e-4 * 3.0 * 150.0 * G / 1000.0), rel=1e-9)


def _viper_model(viper) -> Model:
    return replace(viper.nominal, masses=default_masses(viper.dh), compliance=COMPLIANCE)


def test_bent_frames_carry_the_torques_of_the_commanded_joints(viper):
    q = np.radians([[10.0, -60.0, 200.0, 20.0, -40.0, 5.0]])
    bent = frames(_viper_model(viper), q)
    rigid = frames(replace(_viper_model(viper), compliance=None), q)
    assert bent.torque_nm is not None
    assert rigid.torque_nm is None
    np.testing.assert_allclose(bent.torque_nm, gravity_torques(_viper_model(viper), rigid))


def test_masses_with_zero_compliance_leave_the_arm_rigid(viper):
    rng = np.random.default_rng(1)
    q = rng.uniform(-np.pi, np.pi, (20, 6))
    massive = replace(viper.nominal, masses=default_masses(viper.dh))
    np.testing.assert_array_equal(tool_position(massive, q), tool_position(viper.nominal, q))


configs = arrays(np.float64, st.tuples(st.integers(1, 5), st.just(6)), elements=st.floats(-3, 3))


@settings(max_examples=25, deadline=None)
@given(configs)
def test_tool_jacobian_matches_finite_differences(viper, q):
    # compliance columns: exact (τ at the commanded q does not depend on c); geometric
    # columns leave out ∂τ/∂e (kinematics docstring): within 2e-3 of the column's size
    model = _viper_model(viper)
    _, J = tool_jacobian(model, q, NAMES)
    for k, name in enumerate(NAMES):
        h = 1e-6
        up = tool_position(with_errors(model, [name], np.array([h])), q)
        down = tool_position(with_errors(model, [name], np.array([-h])), q)
        fd = (up - down) / (2 * h)
        size = max(np.abs(fd).max(), 1e-3 if name.startswith("c") else 1.0)
        tol = 1e-6 if name.startswith("c") else 2e-3
        assert np.abs(J[:, :, k] - fd).max() <= tol * size + 1e-5, name  # + round-off


@settings(max_examples=25, deadline=None)
@given(configs, arrays(np.float64, (3,), elements=st.floats(-1.0, 1.0)))
def test_tool_gradient_is_the_jacobian_along_a_direction(viper, q, direction):
    # every kind of column (θ, α, a, d, the attachment, c) of a bent arm: uᵀ·∂p/∂e from the
    # (N, 3, m) Jacobian (itself checked against finite differences above)
    model = _viper_model(viper)
    names = ("th2", "th6", "al1", "al4", "a2", "d4", "d6", "tool_y", "tool_z", "c2", "c3")
    f = frames(model, q)
    p, J = tool_jacobian(model, q, names, f)
    u = np.broadcast_to(direction, p.shape) + np.linspace(0, 1, len(p))[:, None]
    want = np.einsum("nc,ncm->nm", u, J)
    np.testing.assert_allclose(tool_gradient(model, f, p, u, names), want, rtol=1e-12, atol=1e-9)


def test_wire_jacobian_of_compliances_matches_finite_differences(viper, paper_plan):
    model = _viper_model(viper)
    q, _, _ = paper_plan.all_points()
    q, q0 = np.radians(q), np.radians(paper_plan.theta0_deg)
    names = ["c2", "c3", "c4"]
    _, dd = wire_jacobian(model, q, q0, names)
    for k, name in enumerate(names):
        h = 1e-7
        up = wire_lengths(with_errors(model, [name], np.array([h])), q, q0)
        down = wire_lengths(with_errors(model, [name], np.array([-h])), q, q0)
        np.testing.assert_allclose(dd[:, k], (up - down) / (2 * h), rtol=1e-5, atol=1e-3)


def test_batched_compliance_gives_each_model_its_own(viper):
    model = replace(viper.nominal, masses=default_masses(viper.dh))
    values = np.array([[0.0], [5e-6]])
    batch = with_errors(model, ["c2"], values)
    q = np.radians([[0.0, -45.0, 180.0, 0.0, 30.0, 0.0]] * 2)
    one = tool_position(with_errors(model, ["c2"], values[1]), q[:1])
    np.testing.assert_allclose(tool_position(batch, q)[1], one[0], atol=1e-12)
    np.testing.assert_allclose(tool_position(batch, q)[0], tool_position(model, q[:1])[0])


def _ur_standard_frames(q: np.ndarray) -> list[np.ndarray]:
    """UR's own standard-DH chain of the UR5e (its published table, metres → mm)."""
    a = [0.0, -425.0, -392.2, 0.0, 0.0, 0.0]
    d = [162.5, 0.0, 0.0, 133.3, 99.7, 99.6]
    alpha = [np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0]
    T, out = np.eye(4), []
    for i in range(6):
        ct, st, ca, sa = np.cos(q[i]), np.sin(q[i]), np.cos(alpha[i]), np.sin(alpha[i])
        T = T @ np.array(
            [
                [ct, -st * ca, st * sa, a[i] * ct],
                [st, ct * ca, -ct * sa, a[i] * st],
                [0.0, sa, ca, d[i]],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
        out.append(T)
    return out


def test_ur5e_centres_of_mass_are_urs_in_this_files_frames():
    ur5e = load_robot(EXAMPLES / "ur5e" / "robot.toml")
    # UR's published centres (m) in its standard-DH link frames, placed by UR's own chain
    ur_com_m = [
        [0, -0.02561, 0.00193],
        [0.2125, 0, 0.11336],
        [0.15, 0.0, 0.0265],
        [0, -0.0018, 0.01634],
        [0, 0.0018, 0.01634],
        [0, 0, -0.001159],
    ]
    m = ur5e.masses
    assert m is not None
    assert not m.assumed
    np.testing.assert_allclose(m.link_mass_kg, [3.761, 8.058, 2.846, 1.37, 1.3, 0.365])
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, (5, 6)):
        f = frames(ur5e.nominal, q[None])
        chain = _ur_standard_frames(q)
        for k in range(6):
            expected = chain[k] @ np.append(np.array(ur_com_m[k]) * 1000.0, 1.0)
            R = np.stack([f.x[0, k + 1], np.cross(f.z[0, k + 1], f.x[0, k + 1]), f.z[0, k + 1]], 1)
            here = f.o[0, k + 1] + R @ m.link_com_mm[k]
            np.testing.assert_allclose(here, expected[:3], atol=1e-9)


UR5E = tomllib.loads((EXAMPLES / "ur5e" / "robot.toml").read_text())


@pytest.mark.parametrize(
    ("key", "value", "problem"),
    [
        ("link_mass_kg", [1.0, 2.0], "has 2 values; expected 6"),
        ("link_mass_kg", [-1.0, 2, 2, 1, 1, 1], "value 1 is -1.0; give a number between 0"),
        ("link_com_mm", [[0, 0, 0]] * 5, "has 5 rows; expected 6"),
        ("compliance_urad_per_nm", [0, 5, 5, 5, 0, -1], "value 6 is -1"),
        ("direction", [0, 0.5, -0.5], "has length 0.7071; give gravity's direction"),
        ("stiffness", 3, "unknown key"),
    ],
)
def test_gravity_table_is_checked(key, value, problem):
    data = copy.deepcopy(UR5E)
    data["gravity"][key] = value
    with pytest.raises(WirecalError) as info:
        robot_from_dict(data, "r.toml")
    assert any(
        p.startswith(f"r.toml: gravity.{key}") and problem in p for p in info.value.problems
    ), info.value.problems


def test_masses_come_together_with_their_centres():
    data = copy.deepcopy(UR5E)
    del data["gravity"]["link_com_mm"]
    with pytest.raises(WirecalError, match=r"gravity\.link_com_mm: give link_mass_kg and link_com"):
        robot_from_dict(data, "r.toml")


@pytest.mark.parametrize("example", ["ur5e", "viper_s650"])
def test_gravity_table_reads_and_writes_back(example):
    data = tomllib.loads((EXAMPLES / example / "robot.toml").read_text())
    data["gravity"].update(
        compliance_urad_per_nm=[0.0, 5.5, 7.25, 3.0, 0.0, 0.0],
        payload_mass_kg=1.5,
        payload_com_mm=[0.0, 0.0, 40.0],
        direction=[0.0, 0.6, -0.8],
    )
    robot = robot_from_dict(data, "r.toml")
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    again = robot_from_dict(tomllib.loads(text), "again.toml")
    assert again.masses is not None
    assert robot.masses is not None
    for field in ("link_mass_kg", "link_com_mm", "payload_com_mm", "direction"):
        np.testing.assert_allclose(getattr(again.masses, field), getattr(robot.masses, field))
    assert again.masses.payload_mass_kg == 1.5
    assert again.masses.assumed is robot.masses.assumed is (example == "viper_s650")
    np.testing.assert_allclose(again.compliance_urad_per_nm, [0.0, 5.5, 7.25, 3.0, 0.0, 0.0])
    assert again.nominal.compliance is not None
    np.testing.assert_allclose(again.nominal.compliance[2], 7.25e-6)


def test_a_file_without_gravity_has_a_rigid_arm_and_writes_none(viper):
    data = tomllib.loads((EXAMPLES / "viper_s650" / "robot.toml").read_text())
    del data["gravity"]
    robot = robot_from_dict(data, "r.toml")
    assert robot.masses is None
    assert robot.nominal.masses is None
    text = robot_file_text(robot, header=[], row_notes=[""] * 6, encoder_note="")
    assert "[gravity]" not in text
