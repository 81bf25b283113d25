"""Reading a lab table file's keys: the schema, strict reading of one key, and tables as recorded
(:class:`RecordedTable`).

See :mod:`ur3hanoi.tables` for the format and what a recorded table may leave out; reading the file as a mapping of
keys is :mod:`~ur3hanoi.tables.file`'s (its names are re-exported here).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError, printable
from ur3hanoi.hanoi import solve_hanoi, validate_instance
from ur3hanoi.io.schema import Field, ListOf, Nullable, Number, Record, Spec, Vector, suggest
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.station.grid import pose_label
from ur3hanoi.tables.file import BLOCK_XY_KEY, TABLE_KEYS, WHAT, LabFile, check_key, read_lab_file
from ur3hanoi.tables.visits import require_entries

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
}, others=True)
"""The lab table file's schema: a mapping; ur3hanoi's three keys, each optional; any other key is the student's
and may hold anything. A reader checks only the key it reads (:func:`lab_key`): a malformed ``real_pos`` does not
stop anyone from reading ``sim_pos``."""


def lab_key(data: dict[Any, Any], key: str, source: str) -> Any:
    """The value of ``key`` in a lab file's data, checked against its schema in :data:`LAB_FILE_SCHEMA` (only
    that key: the others may hold anything).

    Raises:
        TableError: ``key`` is absent (the nearest key present is suggested) or its value is invalid.
    """
    if key not in data:
        present = [k for k in data if isinstance(k, str)]
        near = suggest(key, present)
        hint = f"; is '{printable(near, 60)}' a misspelling of it?" if near is not None else ""
        known = ", ".join(k for k in present if k in TABLE_KEYS) or "none"
        raise TableError(f"{printable(source)}: key '{key}' not found (table keys present: {known}){hint}")
    value = data[key]
    validate_schema(value, LAB_FILE_SCHEMA.fields[key].spec, source, TableError, path=key)
    _check_rectangular(value, source, key)
    return value


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


def parse_q(value: Any, source: str, key: str) -> FloatArray:
    """Validate ``value`` as a complete ``Q[tower][height][k][6]`` (field ``key`` of ``source``); shape (T, H, 2, 6)
    [rad].

    Raises:
        TableError: invalid, or some entry is missing (the message names them).
    """
    value = lab_key({key: value}, key, source)
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

    def for_solve(self, start: int, end: int, n_blocks: int) -> FloatArray:
        """``q`` for solving ``n_blocks`` from tower ``start`` to ``end`` (0-based): every entry the solve visits
        must be present; entries it never visits may be missing (NaN). The rule of every table follower
        (:func:`ur3hanoi.tables.visits.require_entries`).

        Raises:
            PuzzleError: the instance does not fit the table's towers x heights.
            TableError: entries the solve visits are missing (all of them are named).
        """
        validate_instance(n_blocks, start, end, self.n_towers, self.n_heights)
        require_entries(self.q, solve_hanoi(n_blocks, start, end, self.n_towers, self.n_heights), self.source)
        return self.q

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
    return _recorded(lab_key(lab.data, key, str(path)), str(path), key, lab.sha256)


def read_table(path: str | Path, key: str) -> FloatArray:
    """``Q`` of ``key`` in a lab table file as an array (T, H, 2, 6) [rad]; every entry must be present.

    Raises:
        TableError: the file is invalid (see :func:`read_lab_file`), has no ``key``, or misses entries (named).
    """
    return table_of(read_lab_file(path), path, key)


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
    "lab_key",
    "parse_q",
    "read_lab_file",
    "read_recorded_table",
    "read_table",
    "recorded_table_of",
    "table_of",
]
