"""``wirecal lint`` on RAPID tasks as a controller loads them, end to end through the CLI.

A task's modules (.mod .modx .sys .sysx .prg) are checked together, with the signals of the
I/O configuration (EIO.cfg) beside them; --language names the language of other suffixes;
the bounds on nesting answer with a message, never a traceback.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from wirecal.cli.main import main

SHARED = """MODULE Shared(SYSMODULE)
  RECORD point2
    num x;
    num y;
  ENDRECORD
  PERS point2 origin := [0, 0];
  CONST num n_points := 3;
  PROC report(point2 p)
    TPWrite "x " \\Num:=p.x;
  ENDPROC
ENDMODULE
"""

MAIN = """MODULE MainModule
  VAR point2 path{n_points};
  PROC main()
    path{1} := origin;
    report path{1};
    IF di_ready = 1 SetDO do_busy, 1;
  ENDPROC
ENDMODULE
"""

EIO = """EIO:CFG_1.0:6:1::
#
EIO_SIGNAL:

      -Name "di_ready" -SignalType "DI" -Device "d652"\\
      -DeviceMap "0"

      -Name "do_busy" -SignalType "DO" -Device "d652" -DeviceMap "1"
"""


def lint(*args) -> object:
    return CliRunner().invoke(main, ["lint", *map(str, args)])


def write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("suffix", [".sys", ".sysx", ".mod", ".modx", ".prg"])
def test_a_task_lints_clean_together_whatever_the_suffix(tmp_path, suffix):
    shared = write(tmp_path, f"shared{suffix}", SHARED)
    main_mod = write(tmp_path, "main.mod", MAIN)
    eio = write(tmp_path, "EIO.cfg", EIO)
    r = lint(shared, main_mod, eio)
    assert r.exit_code == 0, r.output
    assert f"{main_mod}: ABB RAPID (IRC5, RobotWare 6), no problems" in r.output


def test_alone_the_module_misses_the_tasks_names(tmp_path):
    shared = write(tmp_path, "shared.sys", SHARED)
    main_mod = write(tmp_path, "main.mod", MAIN)
    r = lint("--separately", shared, main_mod)
    assert r.exit_code == 1
    assert f"{main_mod}:2: unknown data type point2" in r.output
    assert f"{main_mod}:2: an array size must be a positive integer" in r.output
    assert "error: " in r.output


def test_without_the_io_configuration_a_signal_name_is_unknown(tmp_path):
    shared = write(tmp_path, "shared.sys", SHARED)
    main_mod = write(tmp_path, "main.mod", MAIN)
    r = lint(shared, main_mod)
    assert r.exit_code == 1
    assert f"{main_mod}:6: unknown data name di_ready" in r.output


def test_a_signal_of_the_wrong_kind_is_refused(tmp_path):
    eio = write(tmp_path, "EIO.cfg", EIO)
    bad = write(
        tmp_path,
        "bad.mod",
        "MODULE B\n  PROC main()\n    SetDO di_ready, 1;\n  ENDPROC\nENDMODULE\n",
    )
    r = lint(bad, eio)
    assert r.exit_code == 1
    assert f"{bad}:3: SetDO's Signal is the name of a digital output signal" in r.output


# A task of the shape of a ROS-Industrial driver's (two system modules and a motion module;
# written here, not copied): a RECORD of robjoint and extjoint with PERS arrays of it and a
# lock in one .sys, routines taking the record in another, and a .mod that copies the path
# under the lock in a TRAP, moves through it and logs each point.

CELL_COMMON = """MODULE Cell_common(SYSMODULE)
  RECORD cell_point
    robjoint joints;
    extjoint axes;
    num duration_s;
  ENDRECORD
  CONST num MAX_POINTS := 50;
  PERS bool cell_lock := FALSE;
  PERS cell_point cell_path{MAX_POINTS};
  PERS num cell_size := 0;
  PERS bool cell_new := FALSE;
ENDMODULE
"""

CELL_LOG = """MODULE Cell_log(SYSMODULE)
  PROC log_point(cell_point p, num index)
    TPWrite "point " \\Num:=index;
    TPWrite "j1 " \\Num:=p.joints.rax_1;
  ENDPROC
  FUNC bool is_stopped(num tolerance_deg)
    VAR jointtarget now;
    now := CJointT();
    RETURN ABS(now.robax.rax_1) < tolerance_deg;
  ENDFUNC
ENDMODULE
"""

CELL_MOTION = """MODULE Cell_motion
  LOCAL CONST zonedata CORNER := z10;
  LOCAL VAR cell_point path{MAX_POINTS};
  LOCAL VAR num size := 0;
  LOCAL VAR intnum new_path;
  PROC main()
    VAR jointtarget target;
    VAR zonedata zone;
    IDelete new_path;
    CONNECT new_path WITH on_new_path;
    IPers cell_new, new_path;
    WHILE TRUE DO
      IF size > 0 THEN
        FOR i FROM 1 TO size DO
          target.robax := path{i}.joints;
          target.extax := path{i}.axes;
          log_point path{i}, i;
          zone := CORNER;
          IF i = size zone := fine;
          MoveAbsJ target, v100, \\T:=path{i}.duration_s, zone, tool0;
        ENDFOR
        size := 0;
      ENDIF
      IF is_stopped(0.1) WaitTime 0.05;
    ENDWHILE
  ERROR
    ErrWrite \\W, "Motion error", "Aborting the path.";
    size := 0;
    ExitCycle;
  ENDPROC
  LOCAL PROC take_path()
    WaitTestAndSet cell_lock;
    path := cell_path;
    size := cell_size;
    cell_new := FALSE;
    cell_lock := FALSE;
  ENDPROC
  LOCAL TRAP on_new_path
    take_path;
  ENDTRAP
ENDMODULE
"""


def test_a_drivers_task_of_system_modules_and_a_motion_module_lints_clean(tmp_path):
    files = [
        write(tmp_path, name, text)
        for name, text in (
            ("Cell_common.sys", CELL_COMMON),
            ("Cell_log.sys", CELL_LOG),
            ("Cell_motion.mod", CELL_MOTION),
        )
    ]
    together = lint(*files)
    assert together.exit_code == 0, together.output
    assert f"{files[2]}: ABB RAPID (IRC5, RobotWare 6), no problems" in together.output
    alone = lint("--separately", *files)
    assert alone.exit_code == 1
    unknown = [
        (3, "unknown data type cell_point"),
        (17, "unknown instruction log_point"),
        (24, "unknown function is_stopped"),
        (32, "unknown data name cell_lock"),
        (33, "unknown data name cell_path"),
        (34, "unknown data name cell_size"),
    ]
    for line, what in unknown:
        assert f"{files[2]}:{line}: {what}" in alone.output, (line, what)
    assert f"{files[0]}: ABB RAPID (IRC5, RobotWare 6), no problems" in alone.output


def test_two_modules_of_one_name_are_two_tasks(tmp_path):
    one = write(tmp_path, "one.mod", MAIN.replace("path{n_points}", "path{3}"))
    two = write(tmp_path, "two.mod", MAIN.replace("path{n_points}", "path{3}"))
    r = lint(one, two, write(tmp_path, "shared.sys", SHARED), write(tmp_path, "EIO.cfg", EIO))
    assert r.exit_code == 1
    assert f"{two}:1: a second module MainModule in the task (the first: {one})" in r.output


def test_language_names_the_language_of_another_suffix(tmp_path):
    text = write(tmp_path, "main.txt", SHARED)
    r = lint("--language", "rapid", text)
    assert r.exit_code == 0, r.output
    guessed = lint(text)
    assert guessed.exit_code == 1
    assert f"{text}: no language has this suffix: read as Adept/Omron V+ and eV+" in (
        guessed.output
    )
    unknown = lint("--language", "karel", text)
    assert unknown.exit_code == 2
    assert "unknown controller language 'karel'" in unknown.output


def test_an_encrypted_module_is_named_as_such(tmp_path):
    path = tmp_path / "lib.sys"
    path.write_bytes(bytes(range(256)) * 8)
    r = lint(path)
    assert r.exit_code == 1
    assert f"{path}:1: not RAPID text (control bytes): an encrypted or encoded module" in r.output


@pytest.mark.parametrize(
    ("terms", "message"),
    [
        (800, ":4: an expression nested more than 100 levels deep"),
        (1_500_000, ":4: more than 10000 operators in a row: wirecal reads at most 10000"),
    ],
    ids=["800 terms", "1.5 M terms"],
)
def test_a_long_sum_is_refused_with_a_message(tmp_path, terms, message):
    body = "x := " + "+".join(["1"] * terms) + ";"
    path = write(
        tmp_path,
        "sum.mod",
        f"MODULE S\n  PROC p()\n    VAR num x;\n    {body}\n  ENDPROC\nENDMODULE\n",
    )
    r = lint(path)
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    assert r.exit_code == 1
    assert f"{path}{message}" in r.output


def test_help_names_every_language_and_its_suffixes():
    from wirecal.lang.registry import languages

    r = CliRunner().invoke(main, ["lint", "--help"])
    text = " ".join(r.output.split())
    for lang in languages().values():
        for suffix in lang.all_suffixes():
            if suffix != ".cfg":
                assert suffix in text, (lang.key, suffix)
    for name in ("RAPID", "URScript", "V+"):
        assert name in text
