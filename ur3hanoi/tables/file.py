"""A lab table file as a whole: its keys, and reading it as a mapping of keys (without checking any key).

What every reader and the writer share; NumPy-free (and PyYAML is imported when a file is parsed).
Checking a key's value is :mod:`~ur3hanoi.tables.read`'s.

A key that is not one of :data:`KNOWN_KEYS` but reads as one once its invisible characters are taken out and its
look-alike letters read as the Latin ones (``s\u200bim_pos`` with a zero-width space, ``ѕim_pos`` with a Cyrillic
``ѕ``: :func:`confusable_keys`) is the student's own key to ur3hanoi, and a second ``sim_pos`` next to it looks
like the same key twice. Reading a file that has both, or writing the key it imitates, warns, naming the characters
(:class:`~ur3hanoi.errors.Ur3HanoiWarning`).
"""

from __future__ import annotations

import unicodedata
import warnings
from collections.abc import Collection
from pathlib import Path
from typing import Any, NamedTuple

from ur3hanoi.errors import TableError, Ur3HanoiWarning, printable, quote
from ur3hanoi.io.reading import read_input_bytes

TABLE_KEYS: tuple[str, ...] = ("sim_pos", "real_pos")
"""The table keys: ``sim_pos`` (the course's Gazebo simulator), ``real_pos`` (the real robot)."""
BLOCK_XY_KEY = "block_xy_pos"
"""The key of the block positions ``[tower][height] -> [x, y]`` [m, world] of a flat (simulator) layout."""
WHAT = "lab table file"
"""How messages name the file kind."""
KNOWN_KEYS: tuple[str, ...] = (*TABLE_KEYS, BLOCK_XY_KEY)
"""ur3hanoi's keys (those of :data:`ur3hanoi.tables.read.LAB_FILE_SCHEMA`); any other key is the student's."""


_LOOK_ALIKE = str.maketrans("аеорсхуѕіјԁοιɑℓ", "aeopcxysijdoial")
"""Cyrillic and Greek letters (and a few Latin ones) drawn like the Latin letters of ur3hanoi's keys."""
_UNSEEN = frozenset({"Cf", "Cc", "Mn", "Me", "Zs", "Zl", "Zp"})
"""Unicode categories taken out of a key before comparing it: format (zero-width, bidi), control, combining marks,
spaces."""


def _skeleton(key: str) -> str:
    """``key`` as a reader sees it: compatibility forms folded (full-width letters), invisible characters and
    combining marks taken out, look-alike letters read as Latin ones."""
    text = unicodedata.normalize("NFD", unicodedata.normalize("NFKC", key))
    return "".join(c for c in text if unicodedata.category(c) not in _UNSEEN).translate(_LOOK_ALIKE)


def confusable_keys(data: dict[Any, Any]) -> list[tuple[str, str]]:
    """``(key, known)`` for each key of ``data`` that is not one of :data:`KNOWN_KEYS` but reads as ``known``."""
    return [(k, known) for k in data if isinstance(k, str) and k not in KNOWN_KEYS
            for known in KNOWN_KEYS if _skeleton(k) == known]


def warn_confusable(data: dict[Any, Any], source: str, twins: Collection[str]) -> bool:
    """Warn about each key of ``data`` that reads as a known key in ``twins`` (the keys present, or the keys about to
    be written); True if ``data`` has any key that reads as a known one."""
    found = confusable_keys(data)
    for key, known in found:
        if known in twins:
            odd = ", ".join(dict.fromkeys(f"U+{ord(c):04X} {unicodedata.name(c, '?')}" for c in key if not c.isascii()))
            warnings.warn(Ur3HanoiWarning(
                f"{printable(source)}: key '{printable(key, 60)}' looks like '{known}' but is another key (it has "
                f"{odd}): ur3hanoi reads and writes '{known}' only; rename or delete the look-alike"), stacklevel=2)
    return bool(found)


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
    warn_confusable(data, source, data)
    return LabFile(data=data, text=doc.text, sha256=doc.sha256, bom=doc.bom)


def check_key(key: str) -> None:
    """Refuse a table key other than :data:`TABLE_KEYS`."""
    if key not in TABLE_KEYS:
        raise TableError(f"table key {quote(key)} is invalid: expected one of {', '.join(TABLE_KEYS)}")


__all__ = ["BLOCK_XY_KEY", "KNOWN_KEYS", "TABLE_KEYS", "WHAT", "LabFile", "check_key", "confusable_keys",
           "parse_lab_file", "read_lab_file", "warn_confusable"]
