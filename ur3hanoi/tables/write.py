"""Writing a generated table into a lab table file: its keys' text (:func:`table_sections`), then the locked
in-place update (:func:`~ur3hanoi.tables.update.write_sections`); see :mod:`ur3hanoi.tables`.

The formatting is :mod:`~ur3hanoi.tables.format`'s and the splice :mod:`~ur3hanoi.tables.splice`'s; this module
adds what a :class:`~ur3hanoi.tables.ik_table.Table` brings: its angles in the chosen joint convention, the block
positions of a flat layout, and each key's provenance comment.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ur3hanoi.errors import printable
from ur3hanoi.io.resources import station_file
from ur3hanoi.station.grid import block_xy_pos
from ur3hanoi.tables.file import BLOCK_XY_KEY, check_key
from ur3hanoi.tables.format import format_q, format_xy
from ur3hanoi.tables.ik_table import Table
from ur3hanoi.tables.sections import Sections
from ur3hanoi.tables.update import write_sections
from ur3hanoi.version import __version__


def _provenance(key: str, table: Table, label: str, with_solver: bool, convention: str = "controller") -> str:
    from ur3hanoi.robot.convention import DESCRIPTION
    from ur3hanoi.robot.registry import DEFAULT_ROBOT

    st = table.station
    # The label is a path given by the user: never let it break the comment line (newlines, control characters).
    what = f"sha256 {st.sha256 or 'n/a'}" + (f", {table.solver} IK" if with_solver else "")
    if with_solver and (st.robot != DEFAULT_ROBOT or convention != "controller"):
        what += f", {st.robot.title}, {DESCRIPTION[convention]}"
    return f"# ur3hanoi {__version__}: {key} generated from {printable(label, 4096)} ({what})"


def write_table(path: str | Path, table: Table, key: str, calibration_label: str | None = None,
                inputs: Sequence[str | Path] = (), convention: str = "controller") -> str:
    """Write ``table`` under ``key`` into ``path`` (created or updated in place; see the module docstring).

    Args:
        path: the lab table file (a symlink is written through to its target).
        table: the generated table.
        key: ``sim_pos`` or ``real_pos``.
        calibration_label: how the calibration is named in the provenance comment (default: its source).
        inputs: files the output must not be (the station's own file is always one).
        convention: joint convention of the written values (:mod:`ur3hanoi.robot.convention`; ``table.q`` is in the
            controller's); any other than ``controller`` is named in the key's provenance line.

    Returns:
        The text written.

    Raises:
        TableError: ``key`` is not a table key, or the existing file is not valid YAML or its top level is not
            a mapping (see :func:`~ur3hanoi.tables.update.write_sections`).
        OutputError: ``path`` cannot be written (an input file, a directory, a device, no space...).

    In both cases the file is left byte-identical.
    """
    check_key(key)
    sections = table_sections(table, key, calibration_label, convention)
    return write_sections(path, sections, inputs=(*inputs, station_file(table.station.source)))


def table_sections(table: Table, key: str, calibration_label: str | None = None,
                   convention: str = "controller") -> Sections:
    """The keys :func:`write_table` writes for ``table`` under ``key`` (same arguments): ``key`` itself, and
    ``block_xy_pos`` for a flat layout, each with its provenance comment; the values as nested lists of floats.

    Raises:
        TableError: ``key`` is not a table key.
    """
    from dataclasses import replace

    from ur3hanoi.robot.convention import from_controller

    check_key(key)
    st = table.station
    label = calibration_label or st.source
    if convention != "controller":
        table = replace(table, q=from_controller(table.q, convention))
    text = {key: format_q(table.q, key)}
    values: dict[str, Any] = {key: table.q.tolist()}
    headers = {key: _provenance(key, table, label, with_solver=True, convention=convention)}
    if st.layout == "flat":
        xy = block_xy_pos(st)
        text[BLOCK_XY_KEY] = format_xy(xy)
        values[BLOCK_XY_KEY] = [[[float(v) for v in p[:2]] for p in tower] for tower in xy]
        headers[BLOCK_XY_KEY] = _provenance(BLOCK_XY_KEY, table, label, with_solver=False)
    return Sections(key=key, text=text, headers=headers, values=values)


__all__ = ["table_sections", "write_table"]
