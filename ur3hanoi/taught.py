"""Taught points: joint poses recorded on the teach pendant, read from a file or taken from a lab table.

Taught-points file (tower and height are 0-based, like ``Q[tower][height]`` of ``lab2_data.yaml``)::

    units: deg            # deg | rad (required: a pose in the wrong unit is caught, see below)
    points:               # contact ("on") poses unless `pose: above`
      - {tower: 0, height: 0, q: [..6 joint values..]}
      - {tower: 1, height: 0, q: [...]}
      - {tower: 2, height: 0, q: [...]}
      - {tower: 0, height: 2, q: [...]}                # optional extra points
      - {tower: 1, height: 0, pose: above, q: [...]}

The file is read by the strict loader (:mod:`ur3hanoi.io.yaml_loader`) and checked against :data:`TAUGHT_SCHEMA`:
an unknown key (``point:``, ``towre:``) is an error naming the nearest valid one, and so is a duplicate key, a
wrong joint count, a non-finite value, or a value outside +-360. Degrees written under ``units: rad`` (or radians
under ``units: deg``) are caught by their size. Alternatively every entry ``Q[t][h][k]`` of a lab table is a taught
point (:func:`taught_from_table`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.grid import ABOVE, ON, POSE_NAMES
from ur3hanoi.io.schema import Choice, Field, ListOf, Number, Record, Vector
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.io.yaml_loader import load_yaml_file
from ur3hanoi.labfile import read_lab_file, table_of
from ur3hanoi.robot import N_JOINTS
from ur3hanoi.station import MAX_HEIGHTS, MAX_TOWERS

UNITS: tuple[str, ...] = ("deg", "rad")
MAX_TAUGHT_POINTS = 1000
_TWO_PI = 2 * math.pi

TAUGHT_SCHEMA = Record({
    "units": Field(Choice(UNITS)),
    "points": Field(ListOf(Record({
        "tower": Field(Number(0, MAX_TOWERS - 1, integer=True, what="a 0-based tower index")),
        "height": Field(Number(0, MAX_HEIGHTS - 1, integer=True, what="a 0-based height index")),
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
        tower, height: grid slot, 0-based.
        k: 0 = contact ("on") pose, 1 = the pose above it.
        q: joint angles [rad], controller convention.
    """

    index: int
    tower: int
    height: int
    k: int
    q: tuple[float, ...]

    @property
    def label(self) -> str:
        return f"points[{self.index}] (tower {self.tower} height {self.height} {POSE_NAMES[self.k]})"


@dataclass(frozen=True)
class TaughtPoints:
    """The taught poses of one file, with provenance for the output's header."""

    points: tuple[TaughtPoint, ...]
    source: str
    sha256: str


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
    raw = [TaughtPoint(index=i, tower=int(item["tower"]), height=int(item["height"]),
                       k=POSE_NAMES.index(item.get("pose", "on")), q=tuple(float(v) for v in item["q"]))
           for i, item in enumerate(data["points"])]  # q still in `units`
    _check_units(source, [p.q for p in raw], units, [p.label for p in raw])
    scale = math.pi / 180.0 if units == "deg" else 1.0
    points = tuple(replace(p, q=tuple(v * scale for v in p.q)) for p in raw)
    return TaughtPoints(points=points, source=source, sha256=sha256)


def load_taught(path: str | Path) -> TaughtPoints:
    """Read a taught-points YAML file (see the module docstring).

    Raises:
        TaughtPointsError: the file is unreadable, not strict YAML, or invalid; the message names the file.
    """
    doc = load_yaml_file(path, what="taught-points file", error=TaughtPointsError)
    return parse_taught(doc.data, str(path), doc.sha256)


def taught_from_table(path: str | Path, key: str) -> TaughtPoints:
    """Every entry ``Q[t][h][k]`` [rad] of a lab-format table as a taught point (numbered in Q order).

    Raises:
        TableError: the table file is invalid or has no ``key``.
        TaughtPointsError: the entries look like degrees.
    """
    lab = read_lab_file(path)
    q = table_of(lab, path, key)
    source = f"{path}:{key}"
    slots = [(t, h, k) for t in range(q.shape[0]) for h in range(q.shape[1]) for k in (ON, ABOVE)]
    points = tuple(TaughtPoint(index=i, tower=t, height=h, k=k, q=tuple(float(v) for v in q[t, h, k]))
                   for i, (t, h, k) in enumerate(slots))
    _check_units(source, [p.q for p in points], "rad", [f"{source}[{t}][{h}][{k}]" for t, h, k in slots])
    return TaughtPoints(points=points, source=source, sha256=lab.sha256)


__all__ = [
    "MAX_TAUGHT_POINTS",
    "TAUGHT_SCHEMA",
    "UNITS",
    "TaughtPoint",
    "TaughtPoints",
    "load_taught",
    "parse_taught",
    "taught_from_table",
]
