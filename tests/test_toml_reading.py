"""Reading TOML inputs again: the same bytes give an equal, independent document; other
bytes are read anew; a refusal stays a refusal. The UTF-16 check against its definition."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from wirecal.formats import fileio
from wirecal.solver.errors import WirecalError

from .conftest import VIPER


def test_the_same_bytes_read_again_give_an_equal_independent_document(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_bytes((VIPER / "robot.toml").read_bytes())
    first = fileio.read_toml(path, "robot file")
    first["name"] = "changed by a caller"
    first["cell"]["box"].clear()
    again = fileio.read_toml(path, "robot file")
    assert again != first
    assert again["name"] != "changed by a caller"
    assert again["cell"]["box"]
    assert again == fileio.read_toml(VIPER / "robot.toml", "robot file")
    assert again is not fileio.read_toml(path, "robot file")


def test_a_file_rewritten_is_read_anew(tmp_path):
    path = tmp_path / "a.toml"
    path.write_text("x = 1.5\n")
    assert fileio.read_toml(path, "plan file") == {"x": 1.5}
    path.write_text("x = -0.0\ny = nan\n")
    got = fileio.read_toml(path, "plan file")
    assert str(got["x"]) == "-0.0"
    assert got["y"] != got["y"]
    path.write_text("x = 1.5\n")
    assert fileio.read_toml(path, "plan file") == {"x": 1.5}


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("x = " + "[" * 17 + "]" * 17 + "\n", "nested 17 deep (more than 16"),
        ("x = = 1\n", "not valid TOML"),
    ],
)
def test_a_refused_input_is_refused_every_time_naming_its_file(tmp_path, text, message):
    for name in ("a.toml", "b.toml", "a.toml"):
        path = tmp_path / name
        path.write_text(text)
        with pytest.raises(WirecalError) as info:
            fileio.read_toml(path, "plan file")
        assert str(info.value).startswith(f"{path}: ")
        assert message in str(info.value)


def _utf16_by_definition(raw: bytes) -> bool:
    """A byte-order mark, or NULs in nine of ten high (or low) bytes of the first 2048 pairs."""
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return True
    pairs = [raw[i : i + 2] for i in range(0, min(len(raw), 4096) - 1, 2)]
    if not pairs:
        return False
    return any(sum(p[k] == 0 for p in pairs) / len(pairs) >= 0.9 for k in (0, 1))


@settings(max_examples=50)
@given(
    st.lists(
        st.sampled_from([b"\x00", b"a", b"\xff", b"\xfe", b"\x00a", b"a\x00", b"\x00\x00"]),
        max_size=40,
    ).map(b"".join)
    | st.binary(max_size=64)
)
def test_is_utf16_is_its_definition(raw):
    """Short texts; the 2048 pairs read of a long one: the test below."""
    assert fileio.is_utf16(raw) == _utf16_by_definition(raw)


@pytest.mark.parametrize("nul_first", [True, False])
@pytest.mark.parametrize(("nuls", "utf16"), [(9, True), (8, False)])
def test_is_utf16_at_nine_of_ten_counts_every_pair_up_to_the_2048th(nul_first, nuls, utf16):
    pair, plain = (b"\x00a", b"aa") if nul_first else (b"a\x00", b"aa")
    raw = plain * (10 - nuls) + pair * nuls  # the NULs last: the last pair counts
    assert fileio.is_utf16(raw) is utf16
    assert fileio.is_utf16(raw + b"a") is utf16  # an odd byte at the end is not a pair
    head = pair * 1844 + plain * 204  # 2048 pairs, 1844 (90.04 %) with a NUL
    assert fileio.is_utf16(head + plain * 5000)  # the pairs after them are not read


BOUND = st.none() | st.floats(-1e3, 1e3)


@given(
    st.lists(
        st.floats()
        | st.integers(-(2**64), 2**64)
        | st.booleans()
        | st.sampled_from(["1", None, [1.0], math.nan, math.inf, -math.inf]),
        max_size=8,
    ),
    st.data(),
)
@settings(max_examples=50)
def test_a_row_is_passed_at_once_only_when_each_value_passes_its_own_check(row, data):
    """The fast pass over a row of numbers agrees with the per-value rule of every file."""
    from wirecal.formats import toml_fields

    each_bound = data.draw(st.booleans())
    lo, hi = (
        data.draw(st.lists(BOUND, min_size=len(row), max_size=len(row)) if each_bound else BOUND)
        for _ in range(2)
    )

    def at(b, k):
        return b[k] if isinstance(b, list) else b

    passes = [
        toml_fields._number_problem(v, at(lo, k), at(hi, k)) is None for k, v in enumerate(row)
    ]
    plain = all(type(v) in (int, float) for v in row)
    assert toml_fields._all_within(row, lo, hi) == (all(passes) and plain)


@pytest.mark.parametrize(
    ("row", "lo", "hi", "fast"),
    [
        ([1.0, 2], 1.0, 2.0, True),  # on the bounds
        ([1, 2.5], [1, 2], [1, 3], True),
        ([1, 2.5], [1, 2], [1, 2], False),
        ([1.0], None, 0.5, False),
        ([0.0], 0.5, None, False),
        ([math.nan], None, None, False),
        ([math.inf], None, None, False),
        ([-math.inf], None, None, False),
        ([True], None, None, False),  # a boolean is never a number
        ([1.0, 1.0], [0.0], None, False),  # fewer bounds than values: the per-value check
    ],
)
def test_a_row_is_passed_at_once_on_its_bounds_and_never_past_them(row, lo, hi, fast):
    from wirecal.formats import toml_fields

    assert toml_fields._all_within(row, lo, hi) is fast
