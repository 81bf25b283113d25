"""Taught points: joint poses recorded on the teach pendant, read from a file or taken from a lab table.

Taught-points file. Towers and heights are numbered from 1, as people count them (``tower: 1, height: 1`` is the
bottom block of the first tower, ``Q[0][0]`` of ``lab2_data.yaml``); a 0 is an error that says so::

    units: deg            # deg | rad (required: a pose in the wrong unit is caught, see below)
    station: lab_real_example   # optional: the name of the base calibration the poses were taught for
    points:               # contact ("on") poses unless `pose: above`
      - {tower: 1, height: 1, q: [..6 joint values..]}
      - {tower: 2, height: 1, q: [...]}
      - {tower: 3, height: 1, q: [...]}
      - {tower: 1, height: 3, q: [...]}                # optional extra points
      - {tower: 2, height: 1, pose: above, q: [...]}

The file is read by the strict loader (:mod:`ur3hanoi.io.yaml_loader`) and checked against :data:`TAUGHT_SCHEMA`:
an unknown key (``point:``, ``towre:``) is an error naming the nearest valid one, and so is a duplicate key, a
wrong joint count, a non-finite value, or a value outside +-360. Degrees written under ``units: rad`` (or radians
under ``units: deg``) are caught by their size. Alternatively every entry ``Q[t][h][k]`` present in a lab table is
a taught point (:func:`taught_from_table`); the missing entries and the "above" poses shared by the heights of a
tower are recorded with them (see :mod:`ur3hanoi.tables`).

``ur3hanoi teach`` records the poses the driver publishes into such a file (:func:`taught_text` writes it, in
degrees, naming its ``station``); ``calibrate`` does not read ``station``.

In code, :class:`TaughtPoint` holds 0-based indices (``tower = 0`` is the first tower), like ``Q[tower][height]``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.io.schema import Choice, Field, ListOf, Number, Record, Text, Vector
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.io.yaml_loader import load_yaml_file
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.station.grid import ABOVE, ON, POSE_NAMES, pose_label
from ur3hanoi.tables import RecordedTable, Slot, read_recorded_table

UNITS: tuple[str, ...] = ("deg", "rad")
MAX_TAUGHT_POINTS = 1000
_TWO_PI = 2 * math.pi
DEG_DECIMALS = 4
"""Decimals of a joint angle written in degrees (0.0001 deg: under 1 um at the UR3's reach)."""

TAUGHT_SCHEMA = Record({
    "units": Field(Choice(UNITS)),
    "station": Field(Text(max_len=255), required=False),
    "points": Field(ListOf(Record({
        "tower": Field(Number(1, MAX_TOWERS, integer=True, what="a tower number (numbering starts at 1)")),
        "height": Field(Number(1, MAX_HEIGHTS, integer=True, what="a height (numbering starts at 1: 1 = bottom)")),
        "pose": Field(Choice(POSE_NAMES), required=False),
        "q": Field(Vector(N_JOINTS, Number(-360.0, 360.0, what="a joint value (in 'units')"))),
    }), 1, MAX_TAUGHT_POINTS, what="points {tower, height, q[, pose]}")),
})
"""The taught-points file's schema (see the module docstring)."""


@dataclass(frozen=True)
class TaughtPoint:
    """One taught pose.

    Attributes:
        index: position in the taught list (``points[index]``; table entries are numbered in Q order).
        tower, height: grid slot, 0-based indices (people read ``tower + 1``, ``height + 1``).
        k: 0 = contact ("on") pose, 1 = the pose above it.
        q: joint angles [rad], controller convention.
        field: where the point is in its file (``points[3]``, ``real_pos[1][2][0]``); default ``points[index]``.
        shared: for an "above" pose of a table shared by several heights of its tower, those heights (0-based,
            this one included); else ``()``.
    """

    index: int
    tower: int
    height: int
    k: int
    q: tuple[float, ...]
    field: str = ""
    shared: tuple[int, ...] = ()

    @property
    def where(self) -> str:
        """The point's field path in its file."""
        return self.field or f"points[{self.index}]"

    @property
    def label(self) -> str:
        """``points[3] (tower 1 height 2 above)``: the field path, and the slot numbered from 1."""
        return f"{self.where} ({pose_label(self.tower, self.height, self.k)})"


@dataclass(frozen=True)
class TaughtPoints:
    """The taught poses of one file, with provenance for the output's header.

    Attributes:
        points: the poses, in file order.
        source: the file (``"<file>:<key>"`` for a table).
        sha256: hex digest of the file's bytes.
        missing: for a table, its missing entries ``(tower, height, k)`` (0-based); else ``()``.
        shape: for a table, its ``(towers, heights)``; else None.
        units: the file's ``units`` (the points are in radians whatever it says).
        station: the file's ``station`` ("" when it names none).
    """

    points: tuple[TaughtPoint, ...]
    source: str
    sha256: str
    missing: tuple[Slot, ...] = ()
    shape: tuple[int, int] | None = None
    units: str = "rad"
    station: str = ""


def _fail(source: str, msg: str) -> TaughtPointsError:
    return TaughtPointsError(f"{printable(source)}: {msg}", source=source)


def _check_units(source: str, raw: Sequence[Sequence[float]], units: str, labels: Sequence[str]) -> None:
    """Catch the classic mix-up: degrees written under ``units: rad`` or radians under ``units: deg``."""
    if not raw:
        return
    if units == "rad":
        for vals, label in zip(raw, labels, strict=True):
            worst = max(abs(v) for v in vals)
            if worst > _TWO_PI + 1e-9:
                raise _fail(source, f"{label}: joint value {worst:g} is outside +-2pi with units rad: "
                                    "looks like degrees (set 'units: deg')")
    else:
        # A down-pointing pose always has some joint far beyond 2pi degrees (6.3 deg): all of them that small
        # means the numbers are radians.
        worst = max(abs(v) for vals in raw for v in vals)
        if worst <= _TWO_PI:
            raise _fail(source, f"every joint value is within +-2pi (largest {worst:g}) with units deg: "
                                "looks like radians (set 'units: rad')")


def parse_taught(data: Any, source: str = "<memory>", sha256: str = "") -> TaughtPoints:
    """Validate a parsed taught-points document (:data:`TAUGHT_SCHEMA`) and convert it to radians.

    Raises:
        TaughtPointsError: unknown, missing or duplicate keys, wrong types or counts, values out of range, or
            values in the other unit; the message names the file and the field.
    """
    validate_schema(data, TAUGHT_SCHEMA, source, TaughtPointsError)
    units = data["units"]
    raw = [TaughtPoint(index=i, tower=int(item["tower"]) - 1, height=int(item["height"]) - 1,
                       k=POSE_NAMES.index(item.get("pose", "on")), q=tuple(float(v) for v in item["q"]))
           for i, item in enumerate(data["points"])]  # q still in `units`
    _check_units(source, [p.q for p in raw], units, [p.label for p in raw])
    scale = math.pi / 180.0 if units == "deg" else 1.0
    points = tuple(replace(p, q=tuple(v * scale for v in p.q)) for p in raw)
    return TaughtPoints(points=points, source=source, sha256=sha256, units=units, station=data.get("station", ""))


def taught_text(points: Sequence[TaughtPoint], station: str, header: Sequence[str] = ()) -> str:
    """A taught-points file of ``points`` (joint angles [rad]) in degrees with :data:`DEG_DECIMALS` decimals, one
    point a line, naming ``station``; ``header`` lines are written first as comments. :func:`parse_taught` reads it
    back to the rounding."""
    lines = [f"# {line}" for line in header]
    lines += ["units: deg", f"station: {json.dumps(station)}", "points:"]
    for p in points:
        pose = ", pose: above" if p.k == ABOVE else ""
        q = ", ".join(f"{round(math.degrees(v), DEG_DECIMALS) + 0.0:.{DEG_DECIMALS}f}" for v in p.q)
        lines.append(f"  - {{tower: {p.tower + 1}, height: {p.height + 1}{pose}, q: [{q}]}}")
    return "\n".join(lines) + "\n"


def load_taught(path: str | Path) -> TaughtPoints:
    """Read a taught-points YAML file (see the module docstring).

    Raises:
        TaughtPointsError: the file is unreadable, not strict YAML, or invalid; the message names the file.
    """
    doc = load_yaml_file(path, what="taught-points file", error=TaughtPointsError)
    return parse_taught(doc.data, str(path), doc.sha256)


def taught_from_table(path: str | Path, key: str) -> TaughtPoints:
    """Every entry ``Q[t][h][k]`` [rad] present in a lab-format table as a taught point (numbered in Q order).

    Raises:
        TableError: the table file is invalid, has no ``key``, or the key holds no entry.
        TaughtPointsError: the entries look like degrees.
    """
    return taught_from_recorded(read_recorded_table(path, key))


def taught_from_recorded(table: RecordedTable) -> TaughtPoints:
    """The entries present in ``table`` as taught points (see :func:`taught_from_table`)."""
    slots = [(t, h, k) for t in range(table.n_towers) for h in range(table.n_heights) for k in (ON, ABOVE)
             if table.present[t, h, k]]
    points = tuple(
        TaughtPoint(index=i, tower=t, height=h, k=k, q=tuple(float(v) for v in table.q[t, h, k]),
                    field=f"{table.key}[{t}][{h}][{k}]", shared=table.shared_with(t, h) if k == ABOVE else ())
        for i, (t, h, k) in enumerate(slots))
    _check_units(table.source, [p.q for p in points], "rad", [p.label for p in points])
    return TaughtPoints(points=points, source=table.source, sha256=table.sha256, missing=table.missing,
                        shape=(table.n_towers, table.n_heights))


__all__ = [
    "DEG_DECIMALS",
    "MAX_TAUGHT_POINTS",
    "TAUGHT_SCHEMA",
    "UNITS",
    "TaughtPoint",
    "TaughtPoints",
    "load_taught",
    "parse_taught",
    "taught_from_recorded",
    "taught_from_table",
    "taught_text",
]
