"""The keys of a lab table file as ur3hanoi generated them, ready to be written (:class:`Sections`): what
:func:`~ur3hanoi.tables.update.write_sections` writes."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, NamedTuple


class Sections(NamedTuple):
    """Keys of a lab table file as ur3hanoi generated them, ready to be written (a named tuple: it is created on
    every ``tables`` run, and defining a frozen dataclass costs a millisecond).

    Attributes:
        key: the table key they are for (``sim_pos`` or ``real_pos``; named in messages).
        text: key -> block-YAML text of ``key: value`` (unindented, ending in a newline), in the order new keys are
            added; the table key first, then ``block_xy_pos`` for a flat layout.
        headers: key -> its provenance comment line (no newline), written on the line above the key.
        values: key -> the value as nested lists of floats [rad or m]: what the text reads back as (within
            ``10**-ANGLE_DECIMALS``), and what a file whose top-level mapping is in flow style gets.
    """

    key: str
    text: Mapping[str, str]
    headers: Mapping[str, str]
    values: Mapping[str, Any]


__all__ = ["Sections"]
