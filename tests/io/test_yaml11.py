"""A YAML 1.1 reading kept with its source text (:class:`ur3hanoi.io.yaml11.Yaml11Reading`): a value, not a tuple."""

from __future__ import annotations

from collections.abc import Sequence

import pytest

from ur3hanoi.io.yaml11 import Yaml11Reading


def test_a_reading_is_compared_and_hashed_by_value() -> None:
    a = Yaml11Reading("010", 8, "the octal number 8", 2)
    assert a == Yaml11Reading("010", 8, "the octal number 8", 2)
    assert hash(a) == hash(Yaml11Reading("010", 8, "the octal number 8", 2))
    for other in (Yaml11Reading("010", 8, "the octal number 8", 3), Yaml11Reading("10", 8, "the octal number 8", 2),
                  ("010", 8, "the octal number 8", 2), 8, "010"):
        assert a != other
    assert len({a, Yaml11Reading("010", 8, "the octal number 8", 2), Yaml11Reading("on", True, "x", 1)}) == 2


def test_a_reading_is_immutable_and_shows_its_source_text() -> None:
    a = Yaml11Reading("on", True, "the boolean true", 4)
    with pytest.raises(AttributeError):
        a.value = False  # type: ignore[misc]
    with pytest.raises(AttributeError):
        del a.text
    assert (a.text, a.value, a.meaning, a.line) == ("on", True, "the boolean true", 4)
    assert repr(a) == "on" and f"{[a]}" == "[on]"


def test_a_reading_is_not_a_sequence() -> None:
    """A schema takes lists and tuples for sequences: a reading must stay a scalar to it."""
    assert not isinstance(Yaml11Reading("1:30", 90, "90 (a base-60 number)", 1), Sequence | tuple | list)
