"""Reading a lab table file: the schema, strict reading, and tables as recorded (:class:`RecordedTable`).

See :mod:`ur3hanoi.labfile` for the format and what a recorded table may leave out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError, printable, quote
from ur3hanoi.io.schema import Field, ListOf, Nullable, Number, Record, Spec, Vector
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.io.yaml_loader import load_yaml_file
from ur3hanoi.robot import N_JOINTS
from ur3hanoi.station import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.waypoints import pose_label

TABLE_KEYS: tuple[str, ...] = ("sim_pos", "real_pos")
BLOCK_XY_KEY = "block_xy_pos"
WHAT = "lab table file"

JOINT_ANGLE = Number(-2 * math.pi, 2 * math.pi, unit="rad", what="a joint angle")
Q_SCHEMA: Spec = ListOf(
    Nullable(ListOf(
        Nullable(ListOf(Nullable(Vector(N_JOINTS, JOINT_ANGLE)), 1, 2, what="poses [on, above]")),
        1, MAX_HEIGHTS, what="heights")),
    1, MAX_TOWERS, what="towers",
)
"""``Q[tower][height][k]``: 1..10 towers of 1..20 heights of [on, above] poses of 6 joint angles [rad]; a tower,
a slot or a pose may be ``null`` (not recorded) and a slot may hold only ``[on]``."""

BLOCK_XY_SCHEMA: Spec = ListOf(
    ListOf(Vector(2, Number(-10.0, 10.0, unit="m", what="a coordinate")), 1, MAX_HEIGHTS, what="heights"),
    1, MAX_TOWERS, what="towers",
)
"""``block_xy_pos[tower][height] = [x, y]`` [m, world]."""

LAB_FILE_SCHEMA = Record({
    "sim_pos": Field(Q_SCHEMA, required=False),
    "real_pos": Field(Q_SCHEMA, required=False),
    BLOCK_XY_KEY: Field(BLOCK_XY_SCHEMA, required=False),
})
"""The lab table file's schema: these three keys, each optional, nothing else."""


@dataclass(frozen=True)
class LabFile:
    """A validated lab table file: ``data`` (key -> value), its ``text`` and the sha256 of its bytes."""

    data: dict[str, Any]
    text: str
    sha256: str


def validate_lab_data(data: Any, source: str) -> dict[str, Any]:
    """Check a parsed lab table file (:data:`LAB_FILE_SCHEMA`, rectangular tables); its data as a dict."""
    if data is None:
        return {}
    validate_schema(data, LAB_FILE_SCHEMA, source, TableError)
    for key in (*TABLE_KEYS, BLOCK_XY_KEY):
        if key in data:
            _check_rectangular(data[key], source, key)
    return dict(data)


def _check_rectangular(value: list[Any], source: str, key: str) -> None:
    towers = [(t, tower) for t, tower in enumerate(value) if tower is not None]
    if not towers:
        return
    t0, first = towers[0]
    for t, tower in towers[1:]:
        if len(tower) != len(first):
            raise TableError.invalid(source, f"{key}[{t}]", tower,
                                     f"{len(first)} heights like {key}[{t0}] (every tower has the same number of "
                                     "heights)")


def read_lab_file(path: str | Path, source: str | None = None) -> LabFile:
    """Read and validate a lab table file (strict YAML, :data:`LAB_FILE_SCHEMA`); ``source`` names it in messages.

    Raises:
        TableError: unreadable, not strict YAML, or not matching the schema; the message names file and field.
    """
    source = str(path) if source is None else source
    doc = load_yaml_file(path, what=WHAT, error=TableError, source=source)
    return LabFile(data=validate_lab_data(doc.data, source), text=doc.text, sha256=doc.sha256)


def parse_q(value: Any, source: str, key: str) -> FloatArray:
    """Validate ``value`` as a complete ``Q[tower][height][k][6]`` (field ``key`` of ``source``); shape (T, H, 2, 6)
    [rad].

    Raises:
        TableError: invalid, or some entry is missing (the message names them).
    """
    validate_schema(value, Q_SCHEMA, source, TableError, path=key)
    _check_rectangular(value, source, key)
    return _recorded(value, source, key, "").full()


Slot = tuple[int, int, int]
"""``(tower, height, k)``: 0-based indices into ``Q``."""


@dataclass(frozen=True)
class RecordedTable:
    """The entries of one table key as recorded, missing ones included.

    Attributes:
        q: joint angles [rad], shape (T, H, 2, 6), NaN where an entry is missing.
        present: shape (T, H, 2), True where ``Q[t][h][k]`` holds a pose.
        shared_above: groups of heights of one tower holding the same "above" pose (bit-identical values), as
            ``(tower, (h0, h1, ...))`` with at least two heights; 0-based.
        source: ``"<file>:<key>"``, used in messages.
        key: the table key.
        sha256: hex digest of the file's bytes ("" if not read from a file).
    """

    q: FloatArray
    present: npt.NDArray[np.bool_]
    shared_above: tuple[tuple[int, tuple[int, ...]], ...]
    source: str
    key: str
    sha256: str

    @property
    def n_towers(self) -> int:
        return int(self.q.shape[0])

    @property
    def n_heights(self) -> int:
        return int(self.q.shape[1])

    @property
    def missing(self) -> tuple[Slot, ...]:
        """The missing entries ``(tower, height, k)``, in ``Q`` order."""
        return tuple((int(t), int(h), int(k)) for t, h, k in np.argwhere(~self.present))

    def shared_with(self, tower: int, height: int) -> tuple[int, ...]:
        """The heights whose "above" pose is the one of ``(tower, height)`` (itself included), or ``()``."""
        for t, heights in self.shared_above:
            if t == tower and height in heights:
                return heights
        return ()

    def full(self) -> FloatArray:
        """``q`` when every entry is present.

        Raises:
            TableError: some entries are missing; the message names them.
        """
        missing = self.missing
        if missing:
            names = ", ".join(pose_label(*slot) for slot in missing[:_MAX_NAMED])
            more = f" and {len(missing) - _MAX_NAMED} more" if len(missing) > _MAX_NAMED else ""
            raise TableError(f"{printable(self.source)}: {len(missing)} of {self.present.size} entries are missing "
                             f"({names}{more}): this needs a complete table, [on, above] for every "
                             f"{self.key}[tower][height]")
        return self.q


_MAX_NAMED = 6  # missing entries named in a message; the rest are counted


def _recorded(value: list[Any], source: str, key: str, sha256: str) -> RecordedTable:
    """A validated, rectangular ``Q`` (with nulls) as a :class:`RecordedTable`."""
    n_h = next((len(tower) for tower in value if tower is not None), 0)
    if n_h == 0:
        raise TableError(f"{printable(source)}: field '{key}' holds no entry (every tower is null): nothing to use")
    q = np.full((len(value), n_h, 2, N_JOINTS), np.nan)
    for t, tower in enumerate(value):
        for h, slot in enumerate(tower or ()):
            for k, pose in enumerate(slot or ()):
                if pose is not None:
                    q[t, h, k] = pose
    present = ~np.isnan(q).any(axis=3)
    groups: list[tuple[int, tuple[int, ...]]] = []
    for t in range(q.shape[0]):
        seen: list[int] = []
        for h in range(n_h):
            if not present[t, h, 1] or h in seen:
                continue
            same = tuple(h2 for h2 in range(h, n_h) if present[t, h2, 1] and np.array_equal(q[t, h2, 1], q[t, h, 1]))
            seen.extend(same)
            if len(same) > 1:
                groups.append((t, same))
    return RecordedTable(q=q, present=present, shared_above=tuple(groups), source=f"{source}:{key}", key=key,
                         sha256=sha256)


def read_recorded_table(path: str | Path, key: str) -> RecordedTable:
    """The entries of ``key`` present in a lab table file, missing and shared ones marked (see the module
    docstring).

    Raises:
        TableError: the file is invalid (see :func:`read_lab_file`), has no ``key``, or the key holds no entry.
    """
    return recorded_table_of(read_lab_file(path), path, key)


def recorded_table_of(lab: LabFile, path: str | Path, key: str) -> RecordedTable:
    """:func:`read_recorded_table` of an already read :class:`LabFile` (read from ``path``)."""
    check_key(key)
    if key not in lab.data:
        present = ", ".join(k for k in lab.data if k in TABLE_KEYS) or "none"
        raise TableError(f"{printable(path)}: key '{key}' not found (table keys present: {present})")
    return _recorded(lab.data[key], str(path), key, lab.sha256)


def read_table(path: str | Path, key: str) -> FloatArray:
    """``Q`` of ``key`` in a lab table file as an array (T, H, 2, 6) [rad]; every entry must be present.

    Raises:
        TableError: the file is invalid (see :func:`read_lab_file`), has no ``key``, or misses entries (named).
    """
    return table_of(read_lab_file(path), path, key)


def check_key(key: str) -> None:
    """Refuse a table key other than :data:`TABLE_KEYS`."""
    if key not in TABLE_KEYS:
        raise TableError(f"table key {quote(key)} is invalid: expected one of {', '.join(TABLE_KEYS)}")


def table_of(lab: LabFile, path: str | Path, key: str) -> FloatArray:
    """The complete ``Q`` of ``key`` in an already read :class:`LabFile` (read from ``path``); see
    :func:`read_table`."""
    return recorded_table_of(lab, path, key).full()


__all__ = [
    "BLOCK_XY_KEY",
    "BLOCK_XY_SCHEMA",
    "JOINT_ANGLE",
    "LAB_FILE_SCHEMA",
    "Q_SCHEMA",
    "TABLE_KEYS",
    "WHAT",
    "LabFile",
    "RecordedTable",
    "Slot",
    "check_key",
    "parse_q",
    "read_lab_file",
    "read_recorded_table",
    "read_table",
    "recorded_table_of",
    "table_of",
    "validate_lab_data",
]
