"""The URScript facts table: every confirmed fact cites a Universal Robots manual page."""

from __future__ import annotations

import pytest

from wirecal.gen.urscript import facts as F


def test_confirmed_facts_cite_a_universal_robots_manual():
    for f in F.FACTS:
        if f.confirmed:  # a UR web page, or a UR manual named with section and page
            src = f.source.lower()
            assert "universal-robots" in src or "universal robots" in src, f.name
        else:
            assert "universal-robots.com/manuals" not in f.source, f.name


def test_names_unique_and_in_the_docstring_table():
    names = [f.name for f in F.FACTS]
    assert len(names) == len(set(names))
    for name in names:
        if name.isidentifier():  # functions appear by name in the module's table
            assert name in F.__doc__, name


def test_counter_facts_the_backend_depends_on():
    tick = F.fact("encoder_get_tick_count")
    assert tick.confirmed
    assert "65536" in tick.detail
    assert "raw" in tick.detail
    assert F.fact("encoder_enable_pulse_decode").confirmed
    assert "8-11" in F.fact("encoder_enable_pulse_decode").detail
    assert not F.fact("halt").confirmed
    assert F.fact("number widths").confirmed
    assert "32-bit floating" in F.fact("number widths").detail
    with pytest.raises(KeyError, match="known"):
        F.fact("movel")
    assert F.fact("movej").confirmed
    assert "rad" in F.fact("movej").detail
