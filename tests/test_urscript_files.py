"""``wirecal lint`` of a URScript program with the script files it includes: one program."""

from __future__ import annotations

from .lint_together import lint

MAIN = "def main():\n  x = helper(2)\n  textmsg(x)\nend\n"
HELPER = "def twice(a):\n  return 2 * a\nend\ndef helper(a):\n  return a + 1\nend\n"


def test_an_included_file_defines_what_the_program_calls(tmp_path):
    r = lint(tmp_path, ("main.script", MAIN), ("helper.urscript", HELPER))
    assert r.exit_code == 0, r.output
    alone = lint(tmp_path, ("main.script", MAIN), args=("--separately",))
    assert alone.exit_code == 1
    assert "main.script:2: unknown function helper" in alone.output


def test_a_problem_in_an_included_file_is_reported_at_its_own_line(tmp_path):
    bad = HELPER + 'z = [1, "a"]\nmovej([0, 0, 0, 0, 0, 0, 0])\n'
    r = lint(tmp_path, ("main.script", MAIN), ("helper.urscript", bad))
    assert r.exit_code == 1
    lines = [x for x in r.output.splitlines() if "helper.urscript:" in x]
    assert len(lines) == 2, r.output
    assert lines[0].endswith(
        "helper.urscript:7: a list mixes numbers and strings: a list holds "
        "one type (unconfirmed: no manual page read states it)"
    )
    assert "helper.urscript:8: movej: q is 6 joint values, one per joint, not 7" in lines[1]


def test_the_software_applies_to_the_included_files(tmp_path):
    inc = "def now():\n  return time(0)\nend\nx = 1\n"  # a fragment: a function, a statement
    r = lint(
        tmp_path,
        ("main.script", "def m():\n  t = now()\nend\n"),
        ("t.urscript", inc),
        args=("--software", "3.15"),
    )
    assert r.exit_code == 1
    assert "t.urscript:2: time() returning struct(sec, nanosec) is documented from" in r.output
    assert "unknown function now" not in r.output


def test_whole_programs_given_together_are_each_a_program(tmp_path):
    r = lint(
        tmp_path, ("a.script", MAIN.replace("helper", "floor")), ("b.script", HELPER + "end\n")
    )
    assert r.exit_code == 1  # b.script is a fragment (two functions, then a stray end)
    progs = [
        ("p.script", "def p():\n  textmsg(1)\nend\n"),
        ("q.script", "def q():\n  sleep(1)\nend\n"),
    ]
    assert lint(tmp_path, *progs).exit_code == 0
