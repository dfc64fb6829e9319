"""Laser-tracker data: the public sets, their readers, the 3-D calibration, the replay, --pool."""

from __future__ import annotations

import gzip
import json
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from wirecal.cli.main import main
from wirecal.formats.robot_file import load_robot
from wirecal.formats.tracker_published import (
    DATA_ENV,
    PUBLISHED_SETS,
    PublishedSet,
    locate_set,
    tracker_data_dir,
    unpublished,
)
from wirecal.formats.tracker_sets import IPA_JOINTS, read_pool, read_tracker
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.kinematics import tool_position, with_errors
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.plan.pool import anchor_plans, greedy_rows, plan_pool
from wirecal.solver.tracker.fit import (
    _jacobian,
    calibrate,
    register,
    registered_rms_mm,
    residual_and_jacobian,
)
from wirecal.solver.tracker.replay import ZERO_MM, lottery, readings_mm, replay

ROOT = Path(__file__).resolve().parents[1]
ROBOTS = ROOT / "tests" / "data" / "tracker"  # robot files and where each set is published
DATA = tracker_data_dir(ROOT)  # the public sets themselves: not in the repository
UR10 = ROBOTS / "ur10_ipa" / "robot.toml"
# Each public file by its set and path in the publishing repository: rows, joints.
ROWS = {
    ("ur10_ipa", "Series_B/measurements_joint_configurations.csv"): (1495, 6),
    ("ur10_ipa", "Series_C/measurements_random_poses.csv"): (2773, 6),
    ("ur10_ipa", "Series_D/measurements_iso_cubes.csv"): (632, 6),
    ("ur5_jacobi", "UR5/3D_UR5_uncalibrated_grid_cleaned.csv"): (1000, 6),
    ("ur5_jacobi", "UR5/3D_UR5_uncalibrated_random_cleaned.csv"): (20, 6),
    ("wam_jacobi", "WAM/3D_WAM_uncalibrated_grid_cleaned.csv"): (216, 7),
    ("wam_jacobi", "WAM/3D_WAM_uncalibrated_random_cleaned.csv"): (20, 7),
}
# The synthetic UR10's errors (deg, mm): the truth the calibrations must find.
TRUTH = {"th2": 0.05, "th3": -0.04, "a2": 0.6, "a3": -0.4, "d4": 0.3, "al3": 0.03, "th5": 0.02}


def _located(name: str) -> dict[str, Path] | str:
    """Return the public set's files where :func:`tracker_data_dir` looks, or why not."""
    try:
        return locate_set(DATA, name, ROOT)
    except WirecalError as exc:
        return str(exc)


FOUND = {name: _located(name) for name in PUBLISHED_SETS}


def needs(name: str) -> pytest.MarkDecorator:
    """Skip unless the public set ``name`` is where :func:`tracker_data_dir` looks."""
    why = FOUND[name]
    return pytest.mark.skipif(isinstance(why, str), reason=str(why))


def public_set(name: str) -> dict[str, Path]:
    """Return public set ``name``'s files by path there (for a test that ``needs`` it)."""
    files = FOUND[name]
    assert not isinstance(files, str), files
    return files


def public(name: str, path: str) -> Path:
    """Return the file at ``path`` in set ``name``'s repository (for a test that ``needs`` it)."""
    return public_set(name)[path]


# --- the public data sets ----------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(PUBLISHED_SETS))
def test_each_set_says_where_it_is_published(name):
    """Repository URL, commit, path there, licence, citation, the clone; the data not here."""
    text = (ROBOTS / name / "PUBLISHED.md").read_text()
    published = PUBLISHED_SETS[name]
    assert re.fullmatch(r"https://github\.com/[\w-]+/[\w-]+", published.url)
    assert re.fullmatch(r"[0-9a-f]{40}", published.commit)
    assert f"git clone {published.url}" in text
    assert f"checkout {published.commit}" in text
    assert "MIT" in text
    assert "Cite:" in text
    for path, packed, _blob in published.files:
        assert f"`{published.clone}/{path}`" in text
        assert f"`{name}/{packed}`" in text
    assert sorted(p.name for p in (ROBOTS / name).iterdir()) == ["PUBLISHED.md", "robot.toml"]


@pytest.mark.parametrize(
    ("name", "path"), [pytest.param(*k, marks=needs(k[0])) for k in sorted(ROWS)]
)
def test_public_sets_read(name, path):
    table = read_tracker(public(name, path))
    assert table.q_deg.shape == ROWS[name, path]
    assert np.isfinite(table.xyz_mm).all()


def test_data_folder_from_option_env_or_beside_the_clone(tmp_path, monkeypatch):
    monkeypatch.delenv(DATA_ENV, raising=False)
    assert tracker_data_dir(tmp_path / "repo") == tmp_path / "shared" / "data" / "tracker"
    monkeypatch.setenv(DATA_ENV, str(tmp_path / "env"))
    assert tracker_data_dir(tmp_path / "repo") == tmp_path / "env"
    assert tracker_data_dir(tmp_path / "repo", tmp_path / "opt") == tmp_path / "opt"


def _ipa_text(q_rad: np.ndarray, xyz_mm: np.ndarray, temp_c: np.ndarray) -> str:
    """Return rows in the IPA layout: ``;``-separated, decimal commas, radians."""
    head = ";".join([*IPA_JOINTS, "measurement_x", "measurement_y", "measurement_z"])
    body = [
        ";".join(f"{v:.6f}".replace(".", ",") for v in (*a, *b, c))
        for a, b, c in zip(q_rad, xyz_mm, temp_c, strict=True)
    ]
    return head + ";measurement_temperature\n" + "\n".join(body) + "\n"


def _jacobi_text(q_deg: np.ndarray, target_mm: np.ndarray, dif_mm: np.ndarray) -> str:
    """Return rows in the Tsinghua layout: step, target, difference (mm), joints (deg)."""
    n = q_deg.shape[1]
    head = ",".join(["step_order", "x_t", "y_t", "z_t", "x_dif", "y_dif", "z_dif"])
    head += "".join(f",joint_{i + 1}" for i in range(n))
    body = [
        ",".join([str(k), *map(repr, map(float, r))])
        for k, r in enumerate(np.hstack([target_mm, dif_mm, q_deg]))
    ]
    return head + "\n" + "\n".join(body) + "\n"


def _synthetic_sets(seed: int) -> dict[tuple[str, str], str]:
    """Return generated text for every file of every public set, keyed as ROWS."""
    rng = np.random.default_rng(seed)
    out = {}
    for (name, path), (_rows, n) in ROWS.items():
        q, xyz = rng.uniform(-170, 170, (9, n)), rng.uniform(-900, 900, (9, 3))
        out[name, path] = (
            _ipa_text(np.radians(q), xyz, rng.uniform(19, 24, 9))
            if name == "ur10_ipa"
            else _jacobi_text(q, xyz, rng.uniform(-3, 3, (9, 3)))
        )
    return out


def _lay_out(folder: Path, texts: dict[tuple[str, str], str], layout: str) -> Path:
    """Write ``texts`` as clones in ``folder``, as if ``folder`` were a clone, or compressed."""
    for (name, path), text in texts.items():
        published = PUBLISHED_SETS[name]
        packed = {p: z for p, z, _blob in published.files}[path]
        file = {
            "clones": folder / published.clone / path,
            "clone": folder / path,
            "compressed": folder / name / packed,
        }[layout]
        file.parent.mkdir(parents=True, exist_ok=True)
        raw = text.encode()
        file.write_bytes(
            gzip.compress(raw) if packed.endswith(".gz") and layout == "compressed" else raw
        )
    return folder


@pytest.mark.parametrize("layout", ["clones", "clone", "compressed"])
def test_sets_read_as_published_or_compressed(tmp_path, layout):
    """Cloned as published, or gzip-compressed under our names: the same rows."""
    texts = _synthetic_sets(7)
    folder = _lay_out(tmp_path / layout, texts, layout)
    for (name, path), text in texts.items():
        plain = tmp_path / "plain" / name / path
        plain.parent.mkdir(parents=True, exist_ok=True)
        plain.write_text(text)
        want, got = read_tracker(plain), read_tracker(locate_set(folder, name, ROOT)[path])
        assert np.array_equal(got.q_deg, want.q_deg)
        assert np.array_equal(got.xyz_mm, want.xyz_mm)
        assert np.array_equal(got.lines, want.lines)


def test_a_clone_is_preferred_to_compressed_copies(tmp_path):
    _lay_out(tmp_path, _synthetic_sets(1), "compressed")
    _lay_out(tmp_path, _synthetic_sets(2), "clones")
    files = locate_set(tmp_path, "ur5_jacobi", ROOT)
    assert files == {
        path: tmp_path / "serial_robots_datasets" / path
        for path, *_ in PUBLISHED_SETS["ur5_jacobi"].files
    }


def test_a_set_not_found_names_the_files_and_the_clone(tmp_path):
    texts = _synthetic_sets(3)
    grid = ("ur5_jacobi", "UR5/3D_UR5_uncalibrated_grid_cleaned.csv")
    _lay_out(tmp_path, {grid: texts[grid]}, "clones")
    with pytest.raises(WirecalError) as err:
        locate_set(tmp_path, "ur5_jacobi", ROOT)
    why = str(err.value)
    assert "missing UR5/3D_UR5_uncalibrated_random_cleaned.csv of" in why
    assert "grid_cleaned" not in why
    clone = tmp_path / "serial_robots_datasets"
    assert (
        f"git clone https://github.com/pauljac7700/serial_robots_datasets {clone} && git -C"
        f" {clone} checkout 759068d85a8b95183cd71ff96d9dfc5173bc57fc" in why
    )
    assert DATA_ENV in why
    assert str(ROBOTS / "ur5_jacobi" / "PUBLISHED.md") in why
    with pytest.raises(WirecalError, match="public tracker set 'wam_jacobi' is not in"):
        locate_set(tmp_path / "none", "wam_jacobi", ROOT)


@pytest.mark.parametrize("name", [pytest.param(n, marks=needs(n)) for n in sorted(PUBLISHED_SETS)])
def test_public_files_are_the_published_bytes(name):
    """git's blob ids at the commit PUBLISHED.md names, in either layout."""
    assert unpublished(name, public_set(name)) == []


def test_bytes_not_published_are_named(tmp_path, monkeypatch):
    texts = _synthetic_sets(5)
    _lay_out(tmp_path, texts, "compressed")
    files = locate_set(tmp_path, "wam_jacobi", ROOT)
    assert sorted(unpublished("wam_jacobi", files)) == sorted(
        f"{path} ({file})" for path, file in files.items()
    )
    # `printf 'hello\n' | git hash-object --stdin`, compressed or not
    hello = "ce013625030ba8dba906f756967f9e9ca394464a"
    packed = PublishedSet("https://github.com/o/r", "0" * 40, (("a.csv", "a.csv.gz", hello),))
    monkeypatch.setitem(PUBLISHED_SETS, "hello", packed)
    (tmp_path / "hello").mkdir()
    (tmp_path / "hello" / "a.csv.gz").write_bytes(gzip.compress(b"hello\n"))
    assert unpublished("hello", locate_set(tmp_path, "hello", ROOT)) == []
    (tmp_path / "r").mkdir()
    (tmp_path / "r" / "a.csv").write_bytes(b"hello\r\n")  # line endings converted
    assert unpublished("hello", locate_set(tmp_path, "hello", ROOT)) == [
        f"a.csv ({tmp_path / 'r' / 'a.csv'})"
    ]


@needs("ur10_ipa")
def test_ipa_row_in_degrees_and_mm():
    t = read_tracker(public("ur10_ipa", "Series_B/measurements_joint_configurations.csv"))
    # the file's first data row: −3,14159;−1,5708;0;−1,5708;0;0 rad, measurement_x 383,76294 mm
    assert t.q_deg[0] == pytest.approx([-180.0, -90.0, 0.0, -90.0, 0.0, 0.0], abs=1e-3)
    assert t.xyz_mm[0] == pytest.approx([383.76294, -3240.8734, 201.93157])
    assert t.temperature_c is not None
    assert t.temperature_c[0] == pytest.approx(21.86750031)
    assert t.where(0).endswith(":2")


@needs("ur5_jacobi")
def test_jacobi_measured_is_target_less_difference():
    t = read_tracker(public("ur5_jacobi", "UR5/3D_UR5_uncalibrated_random_cleaned.csv"))
    # first row: x_t −495.48014933320513, x_dif −2.382049666794785
    assert t.xyz_mm[0, 0] == pytest.approx(-495.48014933320513 + 2.382049666794785)
    assert t.q_deg[0, 0] == pytest.approx(17.272893800633657)


# --- the generic reader ------------------------------------------------------------------


def _generic(path: Path, q: np.ndarray, xyz: np.ndarray, delimiter: str = ",") -> Path:
    n = q.shape[1]
    head = delimiter.join([*(f"j{i + 1}" for i in range(n)), "x", "y", "z", "note"])
    body = [
        delimiter.join([*map(repr, map(float, a)), *map(repr, map(float, b)), "ok"])
        for a, b in zip(q, xyz, strict=True)
    ]
    path.write_text("# a comment\n" + head + "\n" + "\n".join(body) + "\n")
    return path


@settings(max_examples=40)
@given(
    n=st.integers(2, 7),
    rows=st.integers(10, 30),
    seed=st.integers(0, 2**32 - 1),
    delimiter=st.sampled_from([",", ";", "\t"]),
)
def test_generic_table_round_trip(tmp_path_factory, n, rows, seed, delimiter):
    rng = np.random.default_rng(seed)
    q = rng.uniform(-170, 170, (rows, n))
    q[0, 0] = 100.0  # not every joint within ±2π: degrees
    xyz = rng.uniform(-1500, 1500, (rows, 3))
    path = _generic(tmp_path_factory.mktemp("t") / "t.csv", q, xyz, delimiter)
    t = read_tracker(path)
    assert np.array_equal(t.q_deg, q)
    assert np.array_equal(t.xyz_mm, xyz)
    assert t.lines[0] == 3
    source, _lines, pool = read_pool(path)
    assert np.array_equal(pool, q)
    assert source == str(path)


def test_generic_table_gzip(tmp_path):
    q = np.tile([[10.0, -90.0, 45.0]], (12, 1))
    xyz = np.arange(36.0).reshape(12, 3) * 10
    plain = _generic(tmp_path / "t.csv", q, xyz)
    packed = tmp_path / "t.csv.gz"
    packed.write_bytes(gzip.compress(plain.read_bytes()))
    assert np.array_equal(read_tracker(packed).xyz_mm, xyz)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("j1,j2,x,y\n1,2,3,4\n", "no column 'z'"),
        ("a,b,x,y,z\n1,2,3,4,5\n", "no joint columns j1, j2"),
        ("j1,j2,x,y,z\n1,2,3,4,5\n1,oops,3,4,5\n", "t.csv:3: column 'j2' is 'oops'"),
        ("j1,j2,x,y,z\n1,2,3,4,nan\n", "column 'z' is 'nan', not a number"),
        ("j1,j2,x,y,z\n", "header but no data rows"),
        ("j1,j2,x,y,z\n" + "0.1,-1.2,100,200,300\n" * 12, "radians, not degrees?"),
        ("j1,j2,x,y,z\n" + "".join(f"{k}0,20,0.{k},0.5,1.{k}\n" for k in range(12)), "metres"),
    ],
)
def test_malformed_tables_are_refused_by_name(tmp_path, text, message):
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(WirecalError, match=re.escape(message)):
        read_tracker(path)


def test_gzip_bomb_and_broken_gzip_refused(tmp_path):
    bomb = tmp_path / "bomb.csv.gz"
    bomb.write_bytes(gzip.compress(b"j1,j2,x,y,z\n" + b"0" * (17 * 2**20)))
    with pytest.raises(WirecalError, match="inflates to more than 16 MiB"):
        read_tracker(bomb)
    broken = tmp_path / "broken.csv.gz"
    broken.write_bytes(b"j1,j2,x,y,z\n1,2,3,4,5\n")
    with pytest.raises(WirecalError, match="not a readable gzip file"):
        read_tracker(broken)


@settings(max_examples=30)
@given(rows=st.integers(1, 12), seed=st.integers(0, 2**32 - 1))
def test_ipa_layout_round_trip(tmp_path_factory, rows, seed):
    """Radians with decimal commas in, degrees out; mm and °C as written."""
    rng = np.random.default_rng(seed)
    q = np.round(rng.uniform(-6.2, 6.2, (rows, 6)), 6)
    xyz = np.round(rng.uniform(-3000, 3000, (rows, 3)), 5)
    temp = np.round(rng.uniform(15, 30, rows), 4)
    path = tmp_path_factory.mktemp("ipa") / "ipa.csv"
    path.write_text(_ipa_text(q, xyz, temp))
    t = read_tracker(path)
    assert np.allclose(t.q_deg, q * 180 / np.pi, atol=1e-9)
    assert np.allclose(t.xyz_mm, xyz, atol=1e-9)
    assert t.temperature_c is not None
    assert np.allclose(t.temperature_c, temp, atol=1e-9)


def test_ipa_layout_with_a_bad_cell_names_its_line(tmp_path):
    path = tmp_path / "ipa.csv"
    head = "shoulder_pan_joint;shoulder_lift_joint;elbow_joint;wrist_1_joint;wrist_2_joint;"
    head += "wrist_3_joint;measurement_x;measurement_y;measurement_z;measurement_temperature"
    path.write_text(head + "\n0,1;0;0;0;0;0;1;2;3;21\n0,1;0;0;0;x;0;1;2;3;21\n")
    with pytest.raises(WirecalError, match=re.escape("ipa.csv:3: column 'wrist_2_joint' is 'x'")):
        read_tracker(path)


# --- the 3-D calibration and the registration ----------------------------------------------


@settings(max_examples=30)
@given(seed=st.integers(0, 2**32 - 1))
def test_registration_undoes_a_rigid_motion(seed):
    rng = np.random.default_rng(seed)
    p = rng.uniform(-1000, 1000, (20, 3))
    rot = Rotation.random(random_state=seed % 2**31).as_matrix()
    t = rng.uniform(-3000, 3000, 3)
    x = p @ rot.T + t
    r, tt = register(p, x)
    assert np.allclose(r, rot, atol=1e-9)
    assert np.allclose(tt, t, atol=1e-6)
    assert registered_rms_mm(p, x) < 1e-6
    bent = x.copy()
    bent[0] += [3.0, 0.0, 0.0]  # one point 3 mm off: the RMS sees it
    assert 0.1 < registered_rms_mm(p, bent) < 3.0


def _ur10_pool(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo = np.array([-90.0, -150.0, 30.0, -150.0, 30.0, -90.0])
    hi = np.array([90.0, -40.0, 140.0, -30.0, 150.0, 90.0])
    return rng.uniform(lo, hi, (n, 6))


def _measured(
    q_deg: np.ndarray, noise_mm: float, seed: int, bent: dict | None = None
) -> tuple[np.ndarray, object]:
    robot = load_robot(UR10)
    truth = robot.model({**TRUTH, **(bent or {})})
    rot = Rotation.from_rotvec([0.1, -0.2, 1.3]).as_matrix()
    p = tool_position(truth, np.radians(q_deg)) @ rot.T + [1200.0, -2500.0, 300.0]
    return p + np.random.default_rng(seed).normal(0, noise_mm, p.shape), robot


def test_tracker_jacobian_matches_finite_differences():
    robot = load_robot(UR10)
    base = point_model(robot)
    q = np.radians(_ur10_pool(5, 1))
    names = ("th2", "a3", "al4", "d5", "tool_x")
    rot = Rotation.from_rotvec([0.3, 0.1, -0.7]).as_matrix()
    _, j = _jacobian(base, q, names, rot)
    h = 1e-6
    fd = []
    for k in range(len(names)):
        e = np.zeros(len(names))
        e[k] = h
        up = tool_position(with_errors(base, names, e), q) @ rot.T
        down = tool_position(with_errors(base, names, -e), q) @ rot.T
        fd.append(((up - down) / (2 * h)).reshape(-1))
    for k in range(3):  # the rotation: exp([δω]×)·R
        w = np.zeros(3)
        w[k] = h
        turn = [Rotation.from_rotvec(s * w).as_matrix() @ rot for s in (1, -1)]
        p = tool_position(base, q)
        fd.append(((p @ turn[0].T - p @ turn[1].T) / (2 * h)).reshape(-1))
    fd.extend(np.tile(np.eye(3)[k], len(q)) for k in range(3))
    assert np.allclose(j, np.array(fd).T, atol=1e-5)


def test_tracker_residual_jacobian_matches_finite_differences_away_from_the_start():
    """At a turn ω of 0.4 rad from the start R0 (the left Jacobian of the rotations)."""
    robot = load_robot(UR10)
    base = point_model(robot)
    q = np.radians(_ur10_pool(5, 4))
    names = ("th3", "a2", "al2", "tool_z")
    rot0 = Rotation.from_rotvec([0.2, -0.5, 0.9]).as_matrix()
    x = np.random.default_rng(5).normal(0, 500, (5, 3))
    v = np.array([0.001, 0.3, 0.002, -0.5, 0.3, -0.2, 0.15, 10.0, -4.0, 2.0])
    _, j = residual_and_jacobian(base, q, x, names, rot0, v)
    h = 1e-6
    fd = []
    for k in range(len(v)):
        dv = np.zeros(len(v))
        dv[k] = h
        up = residual_and_jacobian(base, q, x, names, rot0, v + dv)[0]
        down = residual_and_jacobian(base, q, x, names, rot0, v - dv)[0]
        fd.append((up - down) / (2 * h))
    assert np.allclose(j, np.array(fd).T, atol=1e-5)


def test_tracker_calibration_finds_the_truth():
    q = _ur10_pool(120, 2)
    x, robot = _measured(q, 0.01, 3)
    base = point_model(robot)
    qr = np.radians(q)
    fit = calibrate(base, qr[:60], x[:60])
    nominal = calibrate(base, qr[:60], x[:60], ("tool_x", "tool_y", "tool_z"))
    held = registered_rms_mm(tool_position(fit.model, qr[60:]), x[60:])
    assert held < 0.03  # noise 0.01 mm per axis: 0.017 mm in 3-D
    assert registered_rms_mm(tool_position(nominal.model, qr[60:]), x[60:]) > 0.5
    assert {"th2", "a2", "d4"} <= set(fit.names)
    assert "th6" not in fit.names  # the tool point on its axis: θ6 moves nothing


# --- the pool planner and the replay --------------------------------------------------------


@settings(max_examples=30)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 12))
def test_greedy_rows_are_distinct(seed, n):
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(15, 5))
    W = np.diag(rng.uniform(0, 1, 5))
    rows, _ = greedy_rows(J, W, n)
    assert len(rows) == min(n, 15)
    assert len(set(rows.tolist())) == len(rows)


@pytest.fixture(scope="module")
def pool_plan():
    """The UR10's plan from a pool of 300 (row 0 beyond the joint limits), planned once."""
    robot = load_robot(UR10)
    q = _ur10_pool(300, 4)
    q[0, 5] = 400.0  # beyond the joint limits: left out, counted
    return robot, q, plan_pool(robot, q, 30, PlanOptions())


def test_pool_plan_keeps_the_wire_range_and_the_joint_limits(pool_plan):
    robot, q, plan = pool_plan
    assert len(plan.rows) == 30
    assert plan.theta0_row not in plan.rows
    assert 0 not in plan.rows
    assert plan.outside == 1
    assert plan.theta0_tried == 24
    p = tool_position(point_model(robot), np.radians(q))
    wire = np.linalg.norm(p[plan.rows] - p[plan.theta0_row], axis=1)
    assert wire.min() >= 40.0
    assert wire.max() <= robot.encoder.range_mm - 50.0


def test_pool_plan_is_the_least_predicted_of_the_anchors_tried(pool_plan):
    robot, q, chosen = pool_plan  # row 0 beyond the joint limits: no θ0, no pose
    plans = anchor_plans(robot, q, 30, PlanOptions())
    assert 1 < len(plans) <= 24
    assert len({pl.theta0_row for pl in plans}) == len(plans)
    assert all(0 not in pl.rows and pl.theta0_row != 0 and pl.outside == 1 for pl in plans)
    assert chosen.predicted_mm == min(pl.predicted_mm for pl in plans)
    assert chosen.theta0_row in {pl.theta0_row for pl in plans}


def test_readings_are_whole_counts_with_an_unknown_zero():
    xyz = np.array([[0.0, 0.0, 100.0], [30.0, 40.0, 0.0]])
    r = readings_mm(xyz, np.zeros(3), 0.025488)
    counts = (r - ZERO_MM) / 0.025488
    assert np.allclose(counts, np.round(counts))
    assert abs(r[1] - ZERO_MM - 50.0) <= 0.013


def test_replay_of_a_synthetic_ur10():
    """A geometric truth and 0.01 mm noise: both calibrations near the noise, nominal not."""
    from wirecal.solver.tracker.data import TrackerTable

    q = _ur10_pool(240, 5)
    x, robot = _measured(q, 0.01, 6)
    table = TrackerTable("synthetic", "synthetic", np.arange(240) + 2, q, x)
    r = replay(robot, table, seed=0, points=40)
    assert r.nominal_mm > 0.5
    assert r.tracker_mm < 0.03
    assert r.wire_mm < 0.1
    assert r.wire_compliance_mm is not None
    assert r.wire_compliance_mm < 0.1
    assert r.points == 40


def test_replay_of_a_ur10_bent_by_gravity():
    """Joints 2 and 3 yield 8 and 5 µrad/(N·m) (issue 30's model): the rigid fits cannot
    follow, the wire fitted with them can."""
    from wirecal.solver.tracker.data import TrackerTable

    q = _ur10_pool(240, 8)
    x, robot = _measured(q, 0.01, 9, {"c2": 8.0, "c3": 5.0})
    table = TrackerTable("synthetic", "synthetic", np.arange(240) + 2, q, x)
    r = replay(robot, table, seed=1, points=40)
    assert r.wire_mm > 0.1
    assert r.wire_compliance_mm is not None
    assert r.wire_compliance_mm < 0.1
    assert r.wire_compliance_mm < 0.5 * r.wire_mm


@pytest.mark.slow
def test_anchor_lottery_of_a_synthetic_ur10():
    """Every θ0 tried and every pose: on a geometric truth at 0.01 mm, all near the noise."""
    from wirecal.solver.tracker.data import TrackerTable

    q = _ur10_pool(200, 5)
    x, robot = _measured(q, 0.01, 6)
    table = TrackerTable("synthetic", "synthetic", np.arange(200) + 2, q, x)
    r = lottery(robot, table, seed=0, points=30)
    assert len(r.wire_mm) == len(r.predicted_mm) > 1
    assert r.predicted_mm[r.chosen] == r.predicted_mm.min()
    assert np.median(r.wire_mm) < 0.1  # nominal: > 0.5 mm (test_replay_of_a_synthetic_ur10)
    assert r.every_pose_mm < 0.05
    assert r.tracker_mm < 0.03
    assert r.tracker_every_pose_mm < 0.03
    assert r.wire_mm[r.chosen] == replay(robot, table, seed=0, points=30).wire_mm


# --- the command ---------------------------------------------------------------------------


def test_plan_pool_cli_writes_the_choice(tmp_path):
    q = _ur10_pool(200, 7)
    pool = tmp_path / "pool.csv"
    pool.write_text("j1,j2,j3,j4,j5,j6\n" + "".join(",".join(map(str, r)) + "\n" for r in q))
    out = tmp_path / "chosen.csv"
    args = ["plan", str(UR10), "--pool", str(pool), "--points", "25", "-o", str(out), "--json"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    doc = json.loads(r.output)
    assert doc["points"] == 25
    assert len(doc["lines"]) == 25
    assert doc["outside_limits"] == 0
    lines = [s for s in out.read_text().splitlines() if not s.startswith("#")]
    assert lines[0] == "role,pool_line,j1,j2,j3,j4,j5,j6"
    assert lines[1].startswith(f"theta0,{doc['theta0_line']},")
    assert len(lines) == 27
    again = CliRunner().invoke(main, args)  # never overwritten silently
    assert again.exit_code != 0
    assert "exists" in again.output


@pytest.mark.parametrize(
    ("extra", "text", "message"),
    [
        (["--theta0", "0,-90,90,-90,90,0"], None, "leave out --theta0"),
        ([], "j1,j2,j3,j4,j5\n" + "10,-90,90,-90,90\n" * 3, "5 joint columns; the robot"),
        ([], "j1,j2,j3,j4,j5,j6\n" + "0.1,-1.5,1.5,-1.5,1.5,0.2\n" * 12, "radians, not degrees"),
        (
            [],
            "j1,j2,j3,j4,j5,j6\n" + "10,-90,90,-90,90,0\n" * 5,
            "tried leaves enough poses of the pool",
        ),
    ],
)
def test_plan_pool_cli_refusals(tmp_path, extra, text, message):
    pool = tmp_path / "pool.csv"
    pool.write_text(text or "j1,j2,j3,j4,j5,j6\n10,-90,90,-90,90,0\n")
    r = CliRunner().invoke(main, ["plan", str(UR10), "--pool", str(pool), *extra])
    assert r.exit_code == 2
    assert message in r.output
    assert "Traceback" not in r.output


def _ur5e_pool(path: Path) -> None:
    """The UR5e example plan's θ0 and points, twice more each moved by a few degrees."""
    from wirecal.formats.plan_file import load_plan

    robot = load_robot(UR5E)
    plan = load_plan(ROOT / "examples" / "ur5e" / "plan.toml", robot)
    q = plan.all_points()[0]
    rng = np.random.default_rng(0)
    pool = np.vstack([plan.theta0_deg[None], q, q + rng.normal(0, 4, q.shape)])
    path.write_text("j1,j2,j3,j4,j5,j6\n" + "".join(",".join(map(str, r)) + "\n" for r in pool))


UR5E = ROOT / "examples" / "ur5e" / "robot.toml"


@pytest.mark.slow
def test_plan_pool_writes_a_plan_gen_takes(tmp_path):
    """-o PLAN.toml: θ0 and the poses as a plan; the pre-flight of gen passes; gen writes."""
    from wirecal.formats.plan_file import load_plan

    pool = tmp_path / "pool.csv"
    _ur5e_pool(pool)
    out = tmp_path / "pool_plan.toml"
    args = ["plan", str(UR5E), "--pool", str(pool), "--points", "20", "-o", str(out), "--json"]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    doc = json.loads(r.output)
    plan = load_plan(out, load_robot(UR5E))
    assert plan.n_points == 20
    assert plan.order == load_robot(UR5E).parameters
    q = np.loadtxt(pool, delimiter=",", skiprows=1)
    assert np.allclose(plan.theta0_deg, q[doc["theta0_line"] - 2], atol=1e-6)
    chosen = {tuple(np.round(q[line - 2], 6)) for line in doc["lines"]}
    assert {tuple(np.round(p, 6)) for p in plan.all_points()[0]} == chosen
    prog = tmp_path / "prog"
    g = CliRunner().invoke(main, ["gen", str(UR5E), str(out), "-o", str(prog)])
    assert g.exit_code == 0, g.output
    assert "def wc_solve" not in (prog / "wc_run.script").read_text()  # stepwise: no
    assert "step-by-step solver does not apply and is left out" in g.output


def test_plan_pool_refuses_a_plan_the_preflight_refuses(tmp_path):
    """Every pose within gen's 1° margin of a limit: nothing written, exit 2, the reason."""
    pool = tmp_path / "pool.csv"
    pool.write_text("j1,j2,j3,j4,j5,j6\n" + "354.5,-90,90,-90,90,0\n" * 30)
    out = tmp_path / "p.toml"
    r = CliRunner().invoke(main, ["plan", str(UR5E), "--pool", str(pool), "-o", str(out)])
    assert r.exit_code == 2
    assert "within 1 deg of a joint or body limit" in r.output
    assert "nothing written" in r.output
    assert not out.exists()
    assert "Traceback" not in r.output


def test_plan_pool_file_needs_a_pose_per_step(tmp_path):
    """A plan file has a step per [calibration] parameter (10 here): 5 poses are refused."""
    pool = tmp_path / "pool.csv"
    _ur5e_pool(pool)
    out = tmp_path / "p.toml"
    args = ["plan", str(UR5E), "--pool", str(pool), "--points", "5", "-o", str(out)]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2, r.output
    assert "a plan file needs a pose per step; give --points of at least 10" in r.output
    assert not out.exists()


@pytest.mark.slow
def test_bench_replays_any_generic_table(tmp_path):
    """``bench_tracker_replay.py --robot R --table T --json``: the keys the issue names."""
    import subprocess
    import sys

    q = _ur10_pool(160, 10)
    x, _ = _measured(q, 0.01, 11)
    table = _generic(tmp_path / "t.csv", q, x)
    bench = ROOT / "bench" / "bench_tracker_replay.py"
    args = [sys.executable, str(bench), "--robot", str(UR10), "--table", str(table)]
    r = subprocess.run(
        [*args, "--seeds", "1", "--points", "30", "--json"], capture_output=True, text=True
    )
    assert r.returncode == 0, r.stderr
    (doc,) = json.loads(r.stdout).values()
    for key in ("nominal_mm", "tracker_mm", "wire_mm", "wire_compliance_mm", "anchor_mm"):
        assert key in doc
    assert doc["tracker_mm"] < 0.03
    assert doc["nominal_mm"] > 0.5
    assert doc["points"] == 30

    def bench_json(flag: str) -> dict:
        r = subprocess.run(
            [*args, "--seeds", "1", "--points", "30", flag, "--json"],
            capture_output=True,
            text=True,
        )
        assert r.returncode == 0, r.stderr
        (doc,) = json.loads(r.stdout).values()
        return doc

    doc = bench_json("--anchors")
    for key in ("chosen_wire_mm", "best_wire_mm", "every_pose_wire_mm", "spearman"):
        assert len(doc[key]) == 1
    assert doc["best_wire_mm"][0] <= doc["chosen_wire_mm"][0] <= doc["worst_wire_mm"][0]
    assert doc["tracker_every_pose_mm"][0] < 0.03
    doc = bench_json("--preflight")
    assert doc["points"] == 30
    assert doc["wire_mm"] < 0.1  # the user's plan file, the same fit
    bad = subprocess.run([*args[:2], "--table", str(table)], capture_output=True, text=True)
    assert bad.returncode == 2
    assert "give --robot and --table together" in bad.stderr
    absent = [*args[:2], "--data", str(tmp_path / "none"), "--set", "wam_jacobi"]
    gone = subprocess.run(absent, capture_output=True, text=True)
    assert gone.returncode == 2
    assert "public tracker set 'wam_jacobi' is not in" in gone.stderr
    assert "git clone https://github.com/pauljac7700/serial_robots_datasets" in gone.stderr
    assert "Traceback" not in gone.stderr


def test_a_pool_plan_file_says_it_is_for_the_joint_method(tmp_path):
    """``plan --pool -o PLAN.toml`` writes ``joint_only = true``; read back it keeps it, and
    the fingerprint (θ0, order, points) is that of the same plan without the mark."""
    from wirecal.cli.plan_pool_file import as_plan
    from wirecal.formats.plan_file import load_plan, plan_to_toml
    from wirecal.solver.plan.pool import PoolPlan

    robot = load_robot(UR5E)
    q = load_plan(ROOT / "examples" / "ur5e" / "plan.toml", robot).all_points()[0]
    rows = np.arange(1, 1 + len(robot.parameters))
    pp = PoolPlan(0, rows, robot.parameters, np.zeros(3), 0.1, 1, 0)
    plan = as_plan(robot, q, pp, "pool.csv")
    path = tmp_path / "pool_plan.toml"
    path.write_text(plan_to_toml(plan))
    assert "\njoint_only = true\n" in path.read_text()
    back = load_plan(path, robot)
    assert back.joint_only
    path.write_text(path.read_text().replace("joint_only = true\n", ""))
    assert not load_plan(path, robot).joint_only
    assert load_plan(path, robot).fingerprint() == back.fingerprint()


def test_solve_says_the_stepwise_estimate_does_not_apply_to_a_pool_plan(tmp_path):
    """A plan written from a pool printed a stepwise column, budget and steps beside the
    joint ones, though its header says the step-by-step estimate does not apply: now the
    joint method alone, the reason said, and --method stepwise refused naming the mark."""
    viper = ROOT / "examples" / "viper_s650"
    plan = tmp_path / "pool_plan.toml"
    plan.write_text("joint_only = true\n" + (viper / "paper_plan.toml").read_text())
    log = tmp_path / "run.csv"
    runner = CliRunner()
    r = runner.invoke(main, ["simulate", str(viper / "robot.toml"), str(plan), "-o", str(log)])
    assert r.exit_code == 0, r.output
    args = ["solve", str(viper / "robot.toml"), str(plan), str(log)]
    r = runner.invoke(main, args)
    assert r.exit_code == 0, r.output
    assert "the step-by-step estimate does not apply; the joint method alone" in r.output
    assert not re.search(r"^(parameter|source) .*stepwise", r.output, re.M), r.output
    assert "Step-by-step (paper)" not in r.output
    assert re.search(r"^parameter unit +joint +± σ \(joint\) +σ/prior$", r.output, re.M), r.output
    assert "recommended: joint" in r.output
    r = runner.invoke(main, [*args, "--json"])
    assert list(json.loads(r.output)["methods"]) == ["joint"]
    r = runner.invoke(main, [*args, "--method", "stepwise"])
    assert r.exit_code == 2, r.output
    assert f"{plan.name}: joint_only = true: the plan was written from a pool" in r.output
    assert "estimate does not apply: solve by the joint method (--method joint)" in r.output
    r = runner.invoke(main, [*args, "--method", "controller"])
    assert r.exit_code == 2, r.output
    assert "the controller's solver starts step by step, which does not apply" in r.output
    r = runner.invoke(main, ["gen", *args[1:3], "-o", str(tmp_path / "programs")])
    assert r.exit_code == 0, r.output
    assert "the controller's step-by-step solver does not apply and is left out" in r.output
    assert ".PROGRAM wc.solve" not in (tmp_path / "programs" / "WIRECAL.V2").read_text()
    r = runner.invoke(main, ["report", *args[1:], "-o", str(tmp_path / "r.html")])
    assert r.exit_code == 0, r.output
    html = (tmp_path / "r.html").read_text()
    assert 'alt="step residuals"' not in html
    assert "<th>source</th><th>joint</th>" in html
