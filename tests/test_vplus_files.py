"""``wirecal lint`` of V+ files loaded together: a CALL resolves among every file's programs."""

from __future__ import annotations

from .lint_together import lint

MAIN = ".PROGRAM main()\n    CALL helper(1)\n.END\n"
HELPER = ".PROGRAM helper(x)\n    TYPE x\n.END\n"


def test_a_call_to_a_program_of_another_file(tmp_path):
    r = lint(tmp_path, ("a.v2", MAIN), ("b.v2", HELPER))
    assert r.exit_code == 0, r.output
    alone = lint(tmp_path, ("a.v2", MAIN), ("b.v2", HELPER), args=("--separately",))
    assert alone.exit_code == 1
    assert "a.v2:2: main: CALL helper: no such program in the module" in alone.output


def test_arguments_are_checked_across_files(tmp_path):
    r = lint(tmp_path, ("a.v2", ".PROGRAM main()\n    CALL helper(1, 2)\n.END\n"), ("b.v2", HELPER))
    assert r.exit_code == 1
    assert "a.v2:2: main: CALL helper: 2 arguments; helper takes 1" in r.output


def test_a_program_in_two_files_is_refused(tmp_path):
    r = lint(tmp_path, ("a.v2", MAIN + HELPER), ("b.v2", HELPER))
    assert r.exit_code == 1
    assert "b.v2:1: program helper is also defined in" in r.output
    assert "a.v2 (which one LOAD keeps is unconfirmed)" in r.output
