"""Synthetic lab tables for the table-following tests, made the way the course made its own: IK of targets that are
a few millimetres off the block centres (the course's ``sim_pos`` is up to 4.3 mm off), plus single bad entries."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.station.calibration import Station
from ur3hanoi.tables.ik_table import generate_table

COURSE_LIKE_OFFSET_M = (0.0, 0.0043, 0.0)  # the course's table is ~4.3 mm off the block centres, sideways


def shifted_station(station: Station, offset_m: Sequence[float], yaw_deg: float = 0.0) -> Station:
    """``station`` with every IK target moved by ``offset_m`` [m, world] and the tool turned ``yaw_deg`` [deg]."""
    return station.with_grid([np.add(o, offset_m) for o in station.tower_origins], station.height_step,
                             station.tool_yaw + np.radians(yaw_deg))


@cache
def _table(station: Station, offset_m: tuple[float, ...], yaw_deg: float) -> FloatArray:
    q = generate_table(shifted_station(station, offset_m, yaw_deg)).q
    q.flags.writeable = False
    return q


def shifted_table(station: Station, offset_m: Sequence[float] = COURSE_LIKE_OFFSET_M,
                  yaw_deg: float = 0.0) -> FloatArray:
    """A table (T, H, 2, 6) [rad] by IK of the station's targets moved by ``offset_m`` / turned by ``yaw_deg``."""
    return _table(station, tuple(float(x) for x in offset_m), float(yaw_deg)).copy()


def with_bad_entry(table: FloatArray, station: Station, entry: tuple[int, int, int],
                   offset_m: Sequence[float]) -> FloatArray:
    """A copy of ``table`` whose ``entry`` (0-based tower, height, k) is the IK of its target moved by
    ``offset_m`` [m, world] (e.g. a pose recorded 15 mm off)."""
    out = table.copy()
    out[entry] = shifted_table(station, offset_m)[entry]
    return out


def table_yaml(q: FloatArray, key: str = "sim_pos", missing: Sequence[tuple[int, int, int]] = ()) -> str:
    """Lab-format YAML text of ``q`` under ``key``, with the ``missing`` entries written as ``null``."""
    lines = [f"{key}:"]
    for t in range(q.shape[0]):
        lines.append("  -")
        for h in range(q.shape[1]):
            lines.append("    -")
            for k in (0, 1):
                value = "null" if (t, h, k) in missing else "[" + ", ".join(repr(float(x)) for x in q[t, h, k]) + "]"
                lines.append(f"      - {value}")
    return "\n".join(lines) + "\n"
