"""The cable-length table reader (CSV, TSV, .xlsx), its column map, units and resolution,
and ``wirecal fit`` end to end through the command line."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import ROOT
from wirecal.cli.main import main
from wirecal.formats.cable_table import parse_map, read_cable_table, resolution
from wirecal.formats.patch import read_patch
from wirecal.formats.robot_file import load_robot
from wirecal.solver.errors import WirecalError
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.fit.synth import synthetic_table, table_text
from wirecal.solver.fit.units import check_units

VIPER_FILE = ROOT / "examples" / "viper_s650" / "robot.toml"
HEADER = "q1,q2,q3,q4,q5,q6,L\n"
MAP = "j1=q1,j2=q2,j3=q3,j4=q4,j5=q5,j6=q6,length=L"


def _write(tmp_path, text, name="t.csv"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_csv_with_a_map_comments_and_blank_lines(tmp_path):
    path = _write(
        tmp_path,
        "# pendant log, 2026-03-02\n" + HEADER + "\n1.5,-20.0,30.1,0,45.5,90,812.34\n"
        "# re-mounted\n2.5,-21.0,31.1,1,46.5,91,813.30\n",
    )
    t = read_cable_table(path, MAP)
    assert t.lines.tolist() == [4, 6]
    np.testing.assert_array_equal(t.q_deg[1], [2.5, -21.0, 31.1, 1, 46.5, 91])
    np.testing.assert_array_equal(t.length_mm, [812.34, 813.30])
    assert t.xyz_mm is None
    assert t.joint_resolution_deg == pytest.approx(0.1)
    assert t.length_resolution_mm == pytest.approx(0.01)


@pytest.mark.parametrize("sep", ["\t", ";"])
def test_tab_and_semicolon_tables(tmp_path, sep):
    text = HEADER.replace(",", sep) + sep.join(["1", "2", "3", "4", "5", "6", "700.5"]) + "\n"
    t = read_cable_table(_write(tmp_path, text, "t.tsv"), MAP)
    np.testing.assert_array_equal(t.length_mm, [700.5])


def test_default_map_and_xyz_columns(tmp_path):
    text = "j1,j2,j3,j4,j5,j6,length,x,y,z\n1,2,3,4,5,6,700.5,100.25,-20.5,300.75\n"
    t = read_cable_table(_write(tmp_path, text))
    np.testing.assert_array_equal(t.xyz_mm, [[100.25, -20.5, 300.75]])
    assert t.xyz_resolution_mm == pytest.approx(0.01)


def test_missing_column_names_the_header(tmp_path):
    with pytest.raises(WirecalError, match=r"no column 'L'.*'q1'") as err:
        read_cable_table(_write(tmp_path, "q1,q2,q3,q4,q5,q6,len\n1,2,3,4,5,6,7\n"), MAP)
    assert "--map" in str(err.value)


def test_non_numbers_are_named_by_line_and_column(tmp_path):
    text = HEADER + "1,2,3,4,5,6,700\n1,2,x3,4,5,6,700\n1,2,3,4,5,6,\n"
    with pytest.raises(WirecalError) as err:
        read_cable_table(_write(tmp_path, text), MAP)
    assert err.value.problems == [
        f"{tmp_path / 't.csv'}:3: column 'q3' is 'x3', not a number",
        f"{tmp_path / 't.csv'}:4: column 'L' is '', not a number",
    ]


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("j1=a,j2=b", "j3, j4, j5, j6, length missing"),
        ("j1=a,j1=b," + MAP[6:], "j1 is given twice"),
        (MAP + ",x=X", "x, y and z together"),
        (MAP + ",speed=S", "unknown key 'speed'"),
        (MAP + ",j7", "is not KEY=COLUMN"),
    ],
)
def test_bad_maps(spec, message):
    with pytest.raises(WirecalError, match=message):
        parse_map(spec, 6)


def test_xlsx_sheet(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    book.active.title = "notes"
    ws = book.create_sheet("data")
    ws.append(["q1", "q2", "q3", "q4", "q5", "q6", "L"])
    ws.append([1.5, -20, 30.1, 0, 45.5, 90, 812.34])
    ws.append([2.5, -21, 31.1, 1, 46.5, 91, "813.3"])
    path = tmp_path / "t.xlsx"
    book.save(path)
    t = read_cable_table(path, MAP, sheet="data")
    np.testing.assert_array_equal(t.length_mm, [812.34, 813.3])
    assert t.lines.tolist() == [2, 3]
    with pytest.raises(WirecalError, match="no sheet 'log'; the sheets are notes, data"):
        read_cable_table(path, MAP, sheet="log")


def test_ft56_ft54_a_workbook_names_its_other_sheets_and_uncalculated_formulas(tmp_path):
    """FT56: the data on the second sheet got 'name the columns with --map' only; FT54:
    formulas without cached values read as '' with no word of formulas."""
    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    book.active.title = "notes"
    book.active.append(["written by hand"])
    ws = book.create_sheet("data")
    ws.append(["q1", "q2", "q3", "q4", "q5", "q6", "L"])
    ws.append([1.5, -20, 30.1, 0, 45.5, 90, "=A2*100"])  # openpyxl caches no value
    path = tmp_path / "t.xlsx"
    book.save(path)
    with pytest.raises(
        WirecalError,
        match=r"of sheet 'notes', or read another sheet with "
        r"--sheet \('data'\)",
    ):
        read_cable_table(path, MAP)
    with pytest.raises(WirecalError, match="formula never calculated; open and save"):
        read_cable_table(path, MAP, sheet="data")


def test_sheet_on_a_text_table_is_refused(tmp_path):
    with pytest.raises(WirecalError, match=r"--sheet is for \.xlsx"):
        read_cable_table(_write(tmp_path, HEADER + "1,2,3,4,5,6,7\n"), MAP, sheet="x")


@pytest.mark.parametrize(
    ("values", "expected"),
    [([1.0, 2.5, 3.7, 4.1], 0.1), ([812.34, 1.2, 3.0], 0.01), ([10, 20, 30], 1.0)],
)
def test_resolution(values, expected):
    assert resolution(np.array(values)) == pytest.approx(expected)


def test_one_mistyped_digit_does_not_change_the_resolution():
    v = np.round(np.linspace(-100, 100, 50), 1)
    v[7] = 12.345
    assert resolution(v) == pytest.approx(0.1)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31), st.integers(20, 60))
def test_written_tables_read_back_the_same(tmp_path_factory, seed, n):
    robot = load_robot(VIPER_FILE)
    syn = synthetic_table(robot, n, seed=seed, sessions=1)
    path = tmp_path_factory.mktemp("t") / "t.csv"
    path.write_text(table_text(syn.table), encoding="utf-8")
    t = read_cable_table(path)
    np.testing.assert_allclose(t.q_deg, syn.table.q_deg, atol=1e-9)
    np.testing.assert_allclose(t.length_mm, syn.table.length_mm, atol=1e-9)
    np.testing.assert_allclose(t.xyz_mm, syn.table.xyz_mm, atol=1e-9)
    assert t.lines.tolist() == list(range(2, n + 2))


# --- units -----------------------------------------------------------------------------


def _table(robot, **change):
    from dataclasses import replace

    syn = synthetic_table(robot, 100, seed=0)
    return replace(syn.table, **change), syn


def test_joints_in_radians_are_named():
    robot = load_robot(VIPER_FILE)
    t, syn = _table(robot)
    t = type(t)(**{**t.__dict__, "q_deg": np.radians(syn.q_true_deg)})
    with pytest.raises(WirecalError, match=r"'j1', 'j2'.*look like radians; give degrees"):
        check_units(point_model(robot), t)


def test_lengths_in_metres_are_named():
    robot = load_robot(VIPER_FILE)
    t, syn = _table(robot)
    t = type(t)(**{**t.__dict__, "length_mm": syn.table.length_mm / 1000})
    with pytest.raises(WirecalError, match=r"'length': the lengths span .* look like metres"):
        check_units(point_model(robot), t)


def test_lengths_in_counts_are_named():
    robot = load_robot(VIPER_FILE)
    t, syn = _table(robot)
    t = type(t)(**{**t.__dict__, "length_mm": syn.table.length_mm / 0.025488})
    with pytest.raises(WirecalError, match="counts or µm"):
        check_units(point_model(robot), t)


def test_xyz_in_metres_is_named():
    robot = load_robot(VIPER_FILE)
    t, syn = _table(robot)
    t = type(t)(**{**t.__dict__, "xyz_mm": syn.table.xyz_mm / 1000})
    with pytest.raises(WirecalError, match=r"x, y, z span .* look like metres"):
        check_units(point_model(robot), t)


# --- the command line ------------------------------------------------------------------


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    robot = load_robot(VIPER_FILE)
    syn = synthetic_table(robot, 300, seed=11)
    path = tmp_path_factory.mktemp("fit") / "cable.csv"
    path.write_text(table_text(syn.table), encoding="utf-8")
    return syn, path


def test_cli_fit_json_and_patch(simulated, tmp_path):
    syn, path = simulated
    patch = tmp_path / "fit.toml"
    r = CliRunner().invoke(
        main, ["fit", str(VIPER_FILE), str(path), "--json", "--repeats", "2", "-o", str(patch)]
    )
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout)
    assert data["holdout"]["rms_mm"] <= 1.2 * data["floor_mm"]
    assert data["holdout"]["mae_mm"] < data["holdout"]["rms_mm"] < data["holdout"]["max_mm"]
    assert np.all(np.abs(np.array(data["sessions"]) - np.array(syn.starts[1:])) <= 2)
    rejected = {o["row"] for o in data["outliers"]}
    assert {o["line"] - o["row"] for o in data["outliers"]} <= {2}  # header on line 1
    gross = {r for r, e in syn.bad_mm.items() if abs(e) > 10 * data["floor_mm"]}
    assert gross <= rejected
    name = max(set(syn.errors) & set(data["parameters"]), key=lambda n: abs(syn.errors[n]))
    fitted = data["parameters"][name]
    assert abs(fitted["value"] - syn.errors[name]) <= 4 * fitted["std"]
    assert data["plausibility"]["passed"]
    back = read_patch(patch)
    assert back.meta.method == "fit"
    assert back.parameters[name].offset == pytest.approx(fitted["value"])
    assert (tmp_path / "fit.spec.txt").exists()


def test_ft57_gen_with_a_fits_patch_says_a_fit_has_no_plan(simulated, tmp_path):
    """FT57: 'the patch was solved from another plan; generate with the plan it came from'
    (a fit's patch has no plan)."""
    _, path = simulated
    patch = tmp_path / "fit.toml"
    r = CliRunner().invoke(
        main, ["fit", str(VIPER_FILE), str(path), "--holdout", "none", "-o", str(patch)]
    )
    assert r.exit_code == 0, r.output
    plan = VIPER_FILE.parent / "paper_plan.toml"
    r = CliRunner().invoke(
        main, ["gen", str(VIPER_FILE), str(plan), "--patch", str(patch), "-o", str(tmp_path / "g")]
    )
    assert r.exit_code == 2, r.output
    assert "the patch comes from `wirecal fit`" in r.output
    assert "export-urdf --patch" in r.output
    assert "another plan" not in r.output


def test_cli_fit_report(simulated, tmp_path):
    syn, path = simulated
    report = tmp_path / "fit.html"
    r = CliRunner().invoke(
        main, ["fit", str(VIPER_FILE), str(path), "--repeats", "2", "--report", str(report)]
    )
    assert r.exit_code == 0, r.output
    html = report.read_text(encoding="utf-8")
    assert html.count('<img src="data:image/png;base64,') == 2
    assert "RMS / floor" in html
    assert f"new ones at data rows\n{', '.join(str(s) for s in syn.starts[1:])}" in html
    # the verdict and the budget against the correction come before any figure
    verdict = html.index('Plausibility (fit): <span class="good">passed')
    assert verdict < html.index("against a correction of") < html.index("<h2>")


@pytest.mark.slow
def test_cli_fit_json_without_holdout_is_strict_json(simulated):
    _, path = simulated
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path), "--holdout", "none", "--json"])
    assert r.exit_code == 0, r.output
    data = json.loads(r.stdout, parse_constant=lambda c: pytest.fail(f"{c} in JSON"))
    assert data["holdout"]["rms_mm"] is None
    assert data["holdout"]["rows"] == 0
    assert data["floor_mm"] > 0.1  # the fit's own rows then


@pytest.mark.slow
def test_cli_fit_text(simulated):
    _, path = simulated
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path), "--holdout", "half"])
    assert r.exit_code == 0, r.output
    assert "held-out (half, 1 split(s)" in r.output
    assert "RMS/floor" in r.output
    assert "left out d3: degenerate: -1·d2 +1·d3 changes no length" in r.output


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--holdout", "random:2"], "--holdout: 'random:2'"),
        (["--map", "j1=q1"], "--map: j2, j3"),
        (["--sheet", "data"], "--sheet is for .xlsx"),
    ],
)
def test_cli_fit_bad_input_exits_2_without_traceback(simulated, args, message):
    _, path = simulated
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path), *args])
    assert r.exit_code == 2
    assert f"error: {path}" in r.output or "error: --" in r.output
    assert message in r.output
    assert "Traceback" not in r.output


def test_cli_fit_xlsx_without_openpyxl_says_what_to_install(tmp_path, monkeypatch):
    import builtins

    real = builtins.__import__

    def no_openpyxl(name, *args, **kwargs):
        if name == "openpyxl":
            raise ImportError(name)
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_openpyxl)
    path = tmp_path / "t.xlsx"
    path.write_bytes(b"PK")
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path)])
    assert r.exit_code == 2
    assert "pip install 'wirecal[xlsx]'" in r.output


def _workbook_with_a_huge_cell(path, cell_bytes):
    """An .xlsx whose first sheet's one cell holds ``cell_bytes`` characters (FT61)."""
    import io
    import zipfile

    openpyxl = pytest.importorskip("openpyxl")
    book = openpyxl.Workbook()
    book.active.append(["j1"])
    buf = io.BytesIO()
    book.save(buf)
    fast = {"compression": zipfile.ZIP_DEFLATED, "compresslevel": 1}  # 0.6 MB, half the time
    with zipfile.ZipFile(buf) as src, zipfile.ZipFile(path, "w", **fast) as out:
        for part in src.infolist():
            if part.filename != "xl/worksheets/sheet1.xml":
                out.writestr(part, src.read(part))
                continue
            with out.open(part.filename, "w") as sheet:
                sheet.write(
                    b'<?xml version="1.0" encoding="UTF-8"?><worksheet xmlns="http://schemas.'
                    b'openxmlformats.org/spreadsheetml/2006/main"><sheetData><row r="1">'
                    b'<c r="A1" t="inlineStr"><is><t>'
                )
                for _ in range(cell_bytes // 2**20):
                    sheet.write(b"a" * 2**20)
                sheet.write(b"</t></is></c></row></sheetData></worksheet>")


def test_ft61_a_workbook_unpacking_beyond_the_bound_is_refused_before_it_is_read(tmp_path):
    """FT61: a 4 MB .xlsx with a 4 GiB cell took 28.6 s and 3.8 GB before an empty reason;
    the workbooks escaped the 16 MiB input bound. 130 MiB of one cell here (130 kB packed)."""
    path = tmp_path / "bomb.xlsx"
    _workbook_with_a_huge_cell(path, 130 * 2**20)
    assert path.stat().st_size < 2**20
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path)])
    assert r.exit_code == 2
    assert "unpacks to more than 128 MiB (at part 'xl/worksheets/sheet1.xml')" in r.output
    assert len(r.output) < 1000


def test_a_workbook_over_the_input_bound_is_refused_by_size(tmp_path):
    path = tmp_path / "big.xlsx"
    path.write_bytes(b"PK" + b"\0" * (16 * 2**20))
    r = CliRunner().invoke(main, ["fit", str(VIPER_FILE), str(path)])
    assert r.exit_code == 2
    assert "more than 16 MiB" in r.output
