"""The lab's table file ``lab2_data.yaml``: reading one key strictly, and writing one key in place.

File format (the course's): top-level keys ``sim_pos`` / ``real_pos``, each ``Q[tower][height][k]`` with six joint
angles [rad] (controller convention), ``k = 0`` the contact ("on") pose and ``k = 1`` the pose above it; plus
``block_xy_pos[tower][height] = [x, y]`` [m, world] for the flat simulator layout. The file is the student's: any
other key is theirs and may hold anything (:data:`LAB_FILE_SCHEMA` is open). A reader checks only the key it reads
(:func:`lab_key`: shape, range, no key given twice); a malformed ``real_pos`` does not stop anyone reading
``sim_pos``. The list indices are 0-based, as the lab defines them; everything ur3hanoi shows people numbers towers
and heights from 1 (``Q[0][2][1]`` is "tower 1 height 3 above").

Tables recorded by hand are often incomplete, and the schema accepts what students write:

- a missing entry: ``null`` for a pose (``Q[t][h][k]``), a slot (``Q[t][h]``) or a whole tower (``Q[t]``);
- a slot with only its contact pose, ``Q[t][h] = [on]`` (the "above" pose left out);
- one "above" pose shared by the heights of a tower: the same six numbers in ``Q[t][h][1]`` for several ``h``
  (copied, or one YAML anchor ``&above_A`` used through aliases ``*above_A``). Shared means bit-identical values in
  one tower; the file is represented as it is (one entry per slot) and :attr:`RecordedTable.shared_above` names
  the groups.

:func:`read_recorded_table` returns what is present (:class:`RecordedTable`, a masked array); every table reader
uses it. :meth:`RecordedTable.for_solve` is the rule of the table followers (``solve --table``, ``ros-solve
--table``): the entries the solve visits must be present, the others may be missing (:mod:`~ur3hanoi.tables.visits`).
:func:`read_table` is for consumers that need every entry and refuses an incomplete table, naming the missing
entries.

Writing (:func:`write_table`) replaces one key's text and keeps every other byte of the file (see
:mod:`~ur3hanoi.tables.splice`); angles are written with :data:`ANGLE_DECIMALS` decimals so the file is the same on
every CPU; the read-modify-write holds a lock and ends in an atomic replace (:mod:`ur3hanoi.io.atomic`), so
concurrent writers of different keys never lose one. :func:`write_sections` writes keys already formatted
(:class:`Sections`) and needs no NumPy.

Module map: :mod:`~ur3hanoi.tables.file` (the keys, reading the file as a mapping), :mod:`~ur3hanoi.tables.read`
(schema, reading a key, :class:`RecordedTable`), :mod:`~ur3hanoi.tables.visits` (the entries a solve visits),
:mod:`~ur3hanoi.tables.format` (the text of numbers and keys), :mod:`~ur3hanoi.tables.splice` (replacing keys in
the file's text), :mod:`~ur3hanoi.tables.sections` (generated keys ready to write), :mod:`~ur3hanoi.tables.update`
(the locked atomic update, NumPy-free), :mod:`~ur3hanoi.tables.write` (a generated table's keys, then the
update) and :mod:`~ur3hanoi.tables.ik_table` (the table itself, by IK). A name is imported from its module on first
use (the package itself imports none), so what needs no NumPy does not load it.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ur3hanoi.tables.file import BLOCK_XY_KEY, TABLE_KEYS, LabFile, read_lab_file
    from ur3hanoi.tables.format import ANGLE_DECIMALS, FILE_HEADER, format_number, format_q, format_xy
    from ur3hanoi.tables.read import (
        LAB_FILE_SCHEMA,
        RecordedTable,
        Slot,
        lab_key,
        parse_q,
        read_recorded_table,
        read_table,
        recorded_table_of,
        table_of,
    )
    from ur3hanoi.tables.sections import Sections
    from ur3hanoi.tables.splice import splice_yaml
    from ur3hanoi.tables.update import write_sections
    from ur3hanoi.tables.visits import entries_visited, entry_label, missing_entries, require_entries
    from ur3hanoi.tables.write import table_sections, write_table

_MODULE_OF: dict[str, str] = {
    **dict.fromkeys(("BLOCK_XY_KEY", "TABLE_KEYS", "LabFile", "read_lab_file"), "file"),
    **dict.fromkeys(("ANGLE_DECIMALS", "FILE_HEADER", "format_number", "format_q", "format_xy"), "format"),
    **dict.fromkeys(("LAB_FILE_SCHEMA", "RecordedTable", "Slot", "lab_key", "parse_q", "read_recorded_table",
                     "read_table", "recorded_table_of", "table_of"), "read"),
    "splice_yaml": "splice",
    "Sections": "sections",
    "write_sections": "update",
    **dict.fromkeys(("entries_visited", "entry_label", "missing_entries", "require_entries"), "visits"),
    **dict.fromkeys(("table_sections", "write_table"), "write"),
}
"""The module of this package that defines each public name."""


def __getattr__(name: str) -> Any:
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'ur3hanoi.tables' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"ur3hanoi.tables.{module}"), name)
    globals()[name] = value  # found directly from now on
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


__all__ = [
    "ANGLE_DECIMALS",
    "BLOCK_XY_KEY",
    "FILE_HEADER",
    "LAB_FILE_SCHEMA",
    "TABLE_KEYS",
    "LabFile",
    "RecordedTable",
    "Sections",
    "Slot",
    "entries_visited",
    "entry_label",
    "format_number",
    "format_q",
    "format_xy",
    "lab_key",
    "missing_entries",
    "parse_q",
    "read_lab_file",
    "read_recorded_table",
    "read_table",
    "recorded_table_of",
    "require_entries",
    "splice_yaml",
    "table_of",
    "table_sections",
    "write_sections",
    "write_table",
]
