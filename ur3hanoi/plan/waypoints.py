"""The joint waypoints a plan moves through: home, the IK table (on/above of every slot) and the vertical paths."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.motion.vertical import VerticalPath, vertical_path
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station
from ur3hanoi.waypoints import generate_table


@dataclass(frozen=True)
class Waypoints:
    """Joint waypoints of a station [rad]: home, the table ``q[tower, height, k]`` and the vertical paths."""

    q_home: FloatArray
    table: FloatArray
    vertical: tuple[tuple[VerticalPath, ...], ...]  # [tower][height]


def geometry_key(station: Station) -> Station:
    """``station`` without its name, source file and file digest: the key of every per-station cache (they do not
    change a motion; the rest of the calibration does, field by field)."""
    return replace(station, name="", source="", sha256="")


def build_waypoints(station: Station, node_step_m: float = 0.002) -> Waypoints:
    """Table by IK on the home branch, plus the vertical path of every slot (nodes every <= ``node_step_m`` [m]).

    Cached per station geometry (:func:`geometry_key`): every plan on a station reuses them.
    """
    return _build_waypoints(geometry_key(station), node_step_m)


@lru_cache(maxsize=32)
def _build_waypoints(station: Station, node_step_m: float) -> Waypoints:
    table = generate_table(station)
    robot = load_ur3(station.tool, station.limits, station.robot)
    n = max(2, math.ceil(station.approach / node_step_m)) + 1
    s_nodes = np.linspace(0.0, station.approach, n)
    vertical = tuple(tuple(vertical_path(robot, station, table.q, t, h, s_nodes) for h in range(station.n_heights))
                     for t in range(station.n_towers))
    return Waypoints(q_home=station.q_home_array, table=table.q, vertical=vertical)
