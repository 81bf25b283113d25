"""The lab's table file ``lab2_data.yaml``: strict reading, and in-place updates of one key.

File format (the course's): top-level keys ``sim_pos`` / ``real_pos``, each ``Q[tower][height][k]`` with six joint
angles [rad] (controller convention), ``k = 0`` the contact ("on") pose and ``k = 1`` the pose above it; plus
``block_xy_pos[tower][height] = [x, y]`` [m, world] for the flat simulator layout. Any other key, a key given twice,
or a value of the wrong shape or range is refused (:data:`LAB_FILE_SCHEMA`). The list indices are 0-based, as the
lab defines them; everything ur3hanoi shows people numbers towers and heights from 1 (``Q[0][2][1]`` is "tower 1
height 3 above").

Tables recorded by hand are often incomplete, and the schema accepts what students write:

- a missing entry: ``null`` for a pose (``Q[t][h][k]``), a slot (``Q[t][h]``) or a whole tower (``Q[t]``);
- a slot with only its contact pose, ``Q[t][h] = [on]`` (the "above" pose left out);
- one "above" pose shared by the heights of a tower: the same six numbers in ``Q[t][h][1]`` for several ``h``
  (copied, or one YAML anchor ``&above_A`` used through aliases ``*above_A``). Shared means bit-identical values in
  one tower; the file is represented as it is (one entry per slot) and :attr:`RecordedTable.shared_above` names
  the groups.

:func:`read_recorded_table` returns what is present (:class:`RecordedTable`, a masked array); :func:`read_table` is
for consumers that need every entry and refuses an incomplete table, naming the missing entries.

Writing (:func:`write_table`) replaces only the keys it generates: every other key keeps its exact text, the bytes
are a pure function of the inputs, and the read-modify-write holds a lock and ends in an atomic replace
(:mod:`ur3hanoi.io.atomic`), so concurrent writers of different keys never lose one.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from ur3hanoi import __version__
from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError, printable, quote
from ur3hanoi.grid import block_xy_pos
from ur3hanoi.io.atomic import locked_output
from ur3hanoi.io.schema import Field, ListOf, Nullable, Number, Record, Spec, Vector
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.io.yaml_loader import load_yaml_file, parse_yaml
from ur3hanoi.resources import station_file
from ur3hanoi.robot import N_JOINTS
from ur3hanoi.station import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.waypoints import Table, pose_label

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


# ---------------------------------------------------------------------------------------------------- reading


@dataclass(frozen=True)
class LabFile:
    """A validated lab table file: ``data`` (key -> value), its ``text`` and the sha256 of its bytes."""

    data: dict[str, Any]
    text: str
    sha256: str


def _validate(data: Any, source: str) -> dict[str, Any]:
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
    return LabFile(data=_validate(doc.data, source), text=doc.text, sha256=doc.sha256)


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
    _check_key(key)
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


def _check_key(key: str) -> None:
    if key not in TABLE_KEYS:
        raise TableError(f"table key {quote(key)} is invalid: expected one of {', '.join(TABLE_KEYS)}")


def table_of(lab: LabFile, path: str | Path, key: str) -> FloatArray:
    """The complete ``Q`` of ``key`` in an already read :class:`LabFile` (read from ``path``); see
    :func:`read_table`."""
    return recorded_table_of(lab, path, key).full()


# ---------------------------------------------------------------------------------------------------- writing


def _num(x: float) -> str:
    return repr(float(x)) if x != 0.0 else "0.0"


def format_q(q: FloatArray, key: str) -> str:
    """Block-YAML text of ``key: Q[tower][height][k]`` with one commented 6-vector per line."""
    lines = [f"{key}:"]
    for t in range(q.shape[0]):
        for h in range(q.shape[1]):
            for k in (0, 1):
                prefix = ("- " if h == 0 and k == 0 else "  ") + ("- " if k == 0 else "  ") + "- "
                vec = ", ".join(_num(v) for v in q[t, h, k])
                lines.append(f"{prefix}[{vec}]  # {pose_label(t, h, k)}")
    return "\n".join(lines) + "\n"


def format_xy(xy: Sequence[Sequence[Sequence[float]]]) -> str:
    """Block-YAML text of ``block_xy_pos[tower][height] = [x, y]`` [m, world]."""
    lines = [f"{BLOCK_XY_KEY}:"]
    for t, tower in enumerate(xy):
        for h, p in enumerate(tower):
            prefix = "- " if h == 0 else "  "
            # Rounded to 1e-10 m: exact enough, and reads 0.3 rather than 0.30000000000000004.
            x, y = (round(float(v), 10) for v in p[:2])
            lines.append(f"{prefix}- [{_num(x)}, {_num(y)}]  # tower {t + 1} height {h + 1} [m, world]")
    return "\n".join(lines) + "\n"


# A top-level key, plain or quoted (`sim_pos:`, `"sim_pos":`, `'sim_pos':`).
_TOP_KEY = re.compile(r"""^(["']?)([A-Za-z_][\w\-]*)\1\s*:""")
_HEADER = re.compile(r"^# ur3hanoi .*?: (\S+) generated from ")


def _split_sections(text: str) -> tuple[list[str], list[tuple[str | None, str]]]:
    """Split a block-mapping YAML document into (leading comment lines, [(top-level key, text)...])."""
    lines = text.splitlines(keepends=True)
    header: list[str] = []
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        header.append(lines[i])
        i += 1
    sections: list[tuple[str | None, str]] = []
    for line in lines[i:]:
        m = _TOP_KEY.match(line)
        if m:
            sections.append((m.group(2), line))
        elif sections:
            k, body = sections[-1]
            sections[-1] = (k, body + line)
        else:
            sections.append((None, line))
    return header, sections


def splice_yaml(old_text: str, new_sections: Mapping[str, str], header_lines: Mapping[str, str]) -> str:
    """Replace (or append) the given top-level sections, keeping every other key's text byte for byte.

    ``header_lines`` maps a key to its provenance comment; provenance lines of other keys are kept if their key
    still exists.
    """
    header, sections = _split_sections(old_text)
    out_sections: list[str] = []
    seen: set[str] = set()
    for key, body in sections:
        if key is not None and key in new_sections:
            out_sections.append(new_sections[key])
            seen.add(key)
        else:
            if body and not body.endswith("\n"):
                body += "\n"
            out_sections.append(body)
    for key, body in new_sections.items():
        if key not in seen:
            out_sections.append(body)
    present = {k for k, _ in sections if k} | set(new_sections)
    kept_header: dict[str, str] = {}
    other_header: list[str] = []
    for line in header:
        m = _HEADER.match(line)
        if m:
            if m.group(1) in present and m.group(1) not in header_lines:
                kept_header[m.group(1)] = line.rstrip("\n")
        elif line.strip() and not line.startswith("# Generated by ur3hanoi") and not line.startswith("# Q["):
            other_header.append(line.rstrip("\n"))
    kept_header.update(header_lines)
    head = [
        "# Generated by ur3hanoi: lab2_data.yaml waypoint table (course format).",
        "# Q[tower][height][k]: 6 joint angles [rad], controller/DH convention; k = 0 on (contact), k = 1 above.",
        *other_header,
        *(kept_header[k] for k in sorted(kept_header)),
    ]
    return "\n".join(head) + "\n" + "".join(out_sections)


def _provenance(key: str, table: Table, label: str, with_solver: bool) -> str:
    st = table.station
    # The label is a path given by the user: never let it break the comment line (newlines, control characters).
    what = f"sha256 {st.sha256 or 'n/a'}" + (f", {table.solver} IK" if with_solver else "")
    return f"# ur3hanoi {__version__}: {key} generated from {printable(label, 4096)} ({what})"


def write_table(path: str | Path, table: Table, key: str, calibration_label: str | None = None,
                inputs: Sequence[str | Path] = ()) -> str:
    """Write ``table`` under ``key`` into ``path`` (created or updated in place; see the module docstring).

    Args:
        path: the lab table file (a symlink is written through to its target).
        table: the generated table.
        key: ``sim_pos`` or ``real_pos``.
        calibration_label: how the calibration is named in the provenance comment (default: its source).
        inputs: files the output must not be (the station's own file is always one).

    Returns:
        The text written.

    Raises:
        TableError: ``key`` is not a table key, or the existing file is invalid or cannot be updated exactly.
        OutputError: ``path`` cannot be written (an input file, a directory, a device, no space...).
        In both cases the file is left byte-identical.
    """
    _check_key(key)
    st = table.station
    label = calibration_label or st.source
    sections = {key: format_q(table.q, key)}
    headers = {key: _provenance(key, table, label, with_solver=True)}
    if st.layout == "flat":
        sections[BLOCK_XY_KEY] = format_xy(block_xy_pos(st))
        headers[BLOCK_XY_KEY] = _provenance(BLOCK_XY_KEY, table, label, with_solver=False)
    with locked_output(path, inputs=(*inputs, station_file(st.source))) as out:
        old = read_lab_file(out.path, out.shown) if out.exists() else LabFile(data={}, text="", sha256="")
        text = splice_yaml(old.text, sections, headers)
        _check_read_back(text, old, sections, key, table, str(path))
        out.write(text)
    return text


def _check_read_back(text: str, old: LabFile, sections: Mapping[str, str], key: str, table: Table,
                     source: str) -> None:
    """Refuse to write anything that does not read back exactly: other keys equal, ours as generated."""
    try:
        new_data = _validate(parse_yaml(text, source, what=WHAT, error=TableError), source)
    except TableError as exc:
        raise TableError(f"{printable(source)}: cannot update '{key}' in place (unusual YAML layout: {exc}); file "
                         "left unchanged") from None
    for k, v in old.data.items():
        if k not in sections and new_data.get(k) != v:
            raise TableError(f"{printable(source)}: key '{k}' would change when updating '{key}'; file left "
                             "unchanged")
    if not np.array_equal(np.array(new_data[key], dtype=float), table.q):
        raise TableError(f"{printable(source)}: '{key}' does not read back exactly; file left unchanged")


__all__ = [
    "BLOCK_XY_KEY",
    "LAB_FILE_SCHEMA",
    "TABLE_KEYS",
    "LabFile",
    "RecordedTable",
    "Slot",
    "format_q",
    "format_xy",
    "parse_q",
    "read_lab_file",
    "read_recorded_table",
    "read_table",
    "recorded_table_of",
    "splice_yaml",
    "table_of",
    "write_table",
]
