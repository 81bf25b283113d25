"""A number's valid range (:class:`ur3hanoi.io.number.Number`): what it accepts, and how a message names it."""

from __future__ import annotations

import math
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.io.number import Number


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(), st.booleans(), st.none(),
                 st.text(max_size=5)))
def test_number_accepts_only_finite_numbers_in_range(value: Any) -> None:
    spec = Number(0.0, 0.2, lo_open=True)
    ok = (not isinstance(value, bool) and isinstance(value, int | float) and math.isfinite(value)
          and 0.0 < value <= 0.2)
    assert spec.accepts(value) == ok


@settings(max_examples=200, derandomize=True, deadline=None)
@given(st.integers(-20, 20), st.integers(-20, 20), st.booleans(), st.booleans(), st.integers(-25, 25))
def test_an_integer_range_takes_ints_between_its_ends(lo: int, hi: int, lo_open: bool, hi_open: bool,
                                                       value: int) -> None:
    spec = Number(lo, hi, lo_open=lo_open, hi_open=hi_open, integer=True)
    inside = (lo < value or (lo == value and not lo_open)) and (value < hi or (value == hi and not hi_open))
    assert spec.accepts(value) == inside
    assert not spec.accepts(float(value))  # an integer option takes no float, even a whole one


def test_an_int_too_large_for_a_float_is_outside_a_finite_range() -> None:
    assert not Number(0.0, 1e300).accepts(10**400)
    assert Number(0, 10**400, integer=True).accepts(10**399)


@pytest.mark.parametrize(("spec", "text"), [
    (Number(1.0, 10000.0, unit="Hz", what="a sample rate"), "a sample rate [Hz] in [1, 10000]"),
    (Number(0.0, 0.2, lo_open=True, unit="m", what="a length"), "a length [m] in (0, 0.2]"),
    (Number(0, 2**32 - 1, integer=True, what="a seed"), "a seed in [0, 4294967295]"),
    (Number(0.5), "a number in [0.5, inf)"),
    (Number(), "a finite number"),
    (Number(integer=True), "an integer"),
    (Number(unit="rad"), "a finite number [rad]"),
])
def test_expected_names_the_range_with_its_unit(spec: Number, text: str) -> None:
    assert spec.expected() == text


def test_a_range_is_an_immutable_value() -> None:
    spec = Number(0, 1, unit="m")
    with pytest.raises(AttributeError):
        spec.lo = 5  # type: ignore[misc]
    assert spec == Number(0, 1, unit="m") and hash(spec) == hash(Number(0, 1, unit="m"))
    assert spec != Number(0, 1, unit="mm")
