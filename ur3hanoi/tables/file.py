"""A lab table file as a whole: its keys, and reading it as a mapping of keys (without checking any key).

What every reader and the writer share; NumPy-free (and PyYAML is imported when a file is parsed).
Checking a key's value is :mod:`~ur3hanoi.tables.read`'s.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, NamedTuple

from ur3hanoi.errors import TableError, quote
from ur3hanoi.io.reading import read_input_bytes

TABLE_KEYS: tuple[str, ...] = ("sim_pos", "real_pos")
"""The table keys: ``sim_pos`` (the course's Gazebo simulator), ``real_pos`` (the real robot)."""
BLOCK_XY_KEY = "block_xy_pos"
"""The key of the block positions ``[tower][height] -> [x, y]`` [m, world] of a flat (simulator) layout."""
WHAT = "lab table file"
"""How messages name the file kind."""
KNOWN_KEYS: tuple[str, ...] = (*TABLE_KEYS, BLOCK_XY_KEY)
"""ur3hanoi's keys (those of :data:`ur3hanoi.tables.read.LAB_FILE_SCHEMA`); any other key is the student's."""


class LabFile(NamedTuple):
    """A lab table file whose top level is a mapping: ``data`` (key -> value, not checked), its ``text`` (without
    a byte-order mark; ``bom`` says whether the file had one) and the sha256 of its bytes. Immutable (a NamedTuple,
    like :class:`~ur3hanoi.io.yaml_loader.YamlFile`, for the start-up time of ``tables``)."""

    data: dict[Any, Any]
    text: str
    sha256: str
    bom: bool = False


def read_lab_file(path: str | Path, source: str | None = None) -> LabFile:
    """Read a lab table file (strict YAML); ``source`` names it in messages. Only the top level is checked (a
    mapping, or an empty file): each key is checked when it is read (:func:`ur3hanoi.tables.read.lab_key`).

    Raises:
        TableError: unreadable, not strict YAML, or its top level is not a mapping; the message names the file.
    """
    source = str(path) if source is None else source
    return parse_lab_file(read_input_bytes(path, what=WHAT, error=TableError, source=source), source)


def parse_lab_file(raw: bytes, source: str) -> LabFile:
    """A lab table file from its bytes ``raw`` as read from the file (:func:`read_lab_file`, which reads them with
    :func:`ur3hanoi.io.reading.read_input_bytes`). Imports PyYAML on first use.

    Raises:
        TableError: not UTF-8, not strict YAML, or its top level is not a mapping; the message names ``source``.
    """
    from ur3hanoi.io.yaml_loader import parse_yaml_bytes

    doc = parse_yaml_bytes(raw, source, what=WHAT, error=TableError)
    data = {} if doc.data is None else doc.data
    if not isinstance(data, dict):
        from ur3hanoi.io.schema import describe_type

        raise TableError.file(source, f"the top level is {describe_type(data)}, not a mapping of keys "
                                      f"({', '.join(KNOWN_KEYS)}, or your own): not a {WHAT}")
    return LabFile(data=data, text=doc.text, sha256=doc.sha256, bom=doc.bom)


def check_key(key: str) -> None:
    """Refuse a table key other than :data:`TABLE_KEYS`."""
    if key not in TABLE_KEYS:
        raise TableError(f"table key {quote(key)} is invalid: expected one of {', '.join(TABLE_KEYS)}")


__all__ = ["BLOCK_XY_KEY", "KNOWN_KEYS", "TABLE_KEYS", "WHAT", "LabFile", "check_key", "parse_lab_file",
           "read_lab_file"]
