"""The schema validator: types, ranges, finite numbers, unknown keys with the nearest valid one suggested."""

from __future__ import annotations

from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.errors import InputError
from ur3hanoi.io.schema import Choice, Field, ListOf, Number, Record, Text, Vector, suggest, validate

SCHEMA = Record({
    "size": Field(Number(0.0, 0.2, lo_open=True, unit="m", what="a length")),
    "count": Field(Number(1, 20, integer=True)),
    "xyz": Field(Vector(3, Number()), required=False),
    "mode": Field(Choice(("flat", "stacked")), required=False),
    "name": Field(Text(), required=False),
    "points": Field(ListOf(Record({"q": Field(Vector(2, Number(-1, 1)))}), 1, 3, what="points"), required=False),
})


def _check(data: Any) -> str:
    with pytest.raises(InputError) as info:
        validate(data, SCHEMA, "f.yaml")
    return str(info.value)


def test_valid_document_passes() -> None:
    validate({"size": 0.1, "count": 3, "xyz": [0, 1.5, -2], "mode": "flat", "name": "a b",
              "points": [{"q": [0.5, -1]}]}, SCHEMA, "f.yaml")


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"count": 3}, "field 'size' is missing: expected a length [m] in (0, 0.2]"),
        ({"size": 0, "count": 3}, "field 'size' = 0 is invalid: expected a length [m] in (0, 0.2]"),
        ({"size": True, "count": 3}, "field 'size' = True is invalid"),
        ({"size": float("nan"), "count": 3}, "field 'size' = nan is invalid"),
        ({"size": 0.1, "count": 3.0}, "field 'count' = 3.0 is invalid: expected an integer in [1, 20]"),
        ({"size": 0.1, "count": 10**400}, "field 'count' = 100000000000000000...0000000000000000000 is invalid"),
        ({"size": 0.1, "count": 3, "xyz": [0, 1]}, "field 'xyz' = [0, 1] is invalid: expected a list of 3 "
                                                   "numbers, each a finite number"),
        ({"size": 0.1, "count": 3, "xyz": [0, 1, float("inf")]}, "field 'xyz[2]' = inf is invalid"),
        ({"size": 0.1, "count": 3, "mode": "Flat"}, "field 'mode' = 'Flat' is invalid: expected one of flat, stacked"),
        ({"size": 0.1, "count": 3, "points": []}, "field 'points' = [] is invalid: expected a list of 1..3 points"),
        ({"size": 0.1, "count": 3, "points": [{"q": [0, 2]}]}, "field 'points[0].q[1]' = 2 is invalid"),
        ({"size": 0.1, "count": 3, "points": [{"qq": [0, 0]}]}, "field 'points[0].qq' is unknown: did you mean "
                                                               "'points[0].q'?"),
        ({"size": 0.1, "count": 3, "sise": 1}, "field 'sise' is unknown: did you mean 'size'?"),
        ({"size": 0.1, "count": 3, 7: 1}, "field '7' is unknown: expected one of size, count, xyz, mode, name, "
                                          "points"),
        ({"size": 0.1, "count": 3, None: 1}, "field 'None' is unknown"),
        ([1, 2], "expected a mapping with keys size, count, xyz, mode, name, points, got a list"),
        (None, "expected a mapping with keys size, count, xyz, mode, name, points, got an empty document"),
    ],
)
def test_errors_name_file_field_value_and_range(data: Any, message: str) -> None:
    assert _check(data).startswith(f"f.yaml: {message}")


def test_suggestion_prefers_the_first_of_equal_candidates() -> None:
    assert suggest("home", ["home_deg", "home_rad"]) == "home_deg"
    assert suggest("base_rpy", ["base_xyz", "base_rpy_deg", "base_rpy_rad"]) == "base_rpy_deg"
    assert suggest("colour", ["layout", "grid"]) is None


@settings(max_examples=200, derandomize=True, deadline=None)
@given(st.text(min_size=1, max_size=300))
def test_unknown_key_message_is_one_short_line(key: str) -> None:
    if key in SCHEMA.fields:
        return
    msg = _check({"size": 0.1, "count": 3, key: 1})
    assert "\n" not in msg and len(msg) < 400 and "is unknown" in msg
    msg.encode("utf-8")  # printable: no lone surrogates, control characters escaped


def test_nullable_accepts_null_or_a_valid_value() -> None:
    from ur3hanoi.io.schema import Nullable

    spec = ListOf(Nullable(Vector(2, Number(0, 1))), 1, 3, what="pairs")
    validate([None, [0.5, 1], None], spec, "f.yaml")
    with pytest.raises(InputError, match=r"field 'x\[1\]\[0\]' = 2 is invalid: expected a number in \[0, 1\]"):
        validate([None, [2, 0]], spec, "f.yaml", path="x")
    assert Nullable(Number(0, 1)).expected() == "a number in [0, 1], or null"
    # a nullable number out of range says that null is allowed too (the calibration's io.vacuum_generator_output)
    with pytest.raises(InputError, match=r"field 'pin' = 18 is invalid: expected an integer in \[0, 17\], or null$"):
        validate({"pin": 18}, Record({"pin": Field(Nullable(Number(0, 17, integer=True)))}), "f.yaml")
