"""The joint waypoints a plan moves through: home, the IK table (on/above of every slot) and the vertical paths."""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.io.cache import cached
from ur3hanoi.plan.cache_key import station_inputs
from ur3hanoi.plan.motion.vertical import vertical_path
from ur3hanoi.plan.types import VerticalPath
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.tables.ik_table import generate_table


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

    Cached per station geometry (:func:`geometry_key`): every plan on a station reuses them, and so does the next
    process (kept in the user's cache, :data:`WAYPOINTS` entries keyed by
    :func:`~ur3hanoi.plan.cache_key.station_inputs` and ``node_step_m``; the arrays read back bit for bit).
    """
    return _cached_waypoints(geometry_key(station), node_step_m)


WAYPOINTS = "plan-waypoints"
"""Kind of the user's cache entries of :func:`build_waypoints`."""


@lru_cache(maxsize=32)
def _cached_waypoints(station: Station, node_step_m: float) -> Waypoints:
    return cached(WAYPOINTS, [*station_inputs(station), repr(node_step_m).encode()],
                  lambda: _build_waypoints(station, node_step_m), _encode,
                  lambda payload: _decode(payload, station))


def _encode(wp: Waypoints) -> bytes:
    """NumPy's ``.npz`` of q_home, the table, then (s, q, dq, ddq, dddq) of every path, tower by tower."""
    arrays = [wp.q_home, wp.table]
    for paths in wp.vertical:
        for p in paths:
            arrays += [p.s, p.q, p.dq, p.ddq, p.dddq]
    buf = io.BytesIO()
    np.savez(buf, *arrays)
    return buf.getvalue()


def _decode(payload: bytes, station: Station) -> Waypoints | None:
    n_t, n_h = station.n_towers, station.n_heights
    with np.load(io.BytesIO(payload), allow_pickle=False) as npz:
        if len(npz.files) != 2 + 5 * n_t * n_h:
            return None
        arrays = [np.asarray(npz[f"arr_{i}"], dtype=np.float64) for i in range(len(npz.files))]
    q_home, table = arrays[0], arrays[1]
    if table.shape != (n_t, n_h, 2, 6) or q_home.shape != (6,):
        return None

    def path(k: int) -> VerticalPath:
        s, q, dq, ddq, dddq = arrays[2 + 5 * k: 7 + 5 * k]
        if not (s.ndim == 1 and q.shape == dq.shape == ddq.shape == dddq.shape == (len(s), 6)):
            raise ValueError("malformed vertical path")
        return VerticalPath(s=s, q=q, dq=dq, ddq=ddq, dddq=dddq, length_m=station.approach)

    vertical = tuple(tuple(path(t * n_h + h) for h in range(n_h)) for t in range(n_t))
    return Waypoints(q_home=q_home, table=table, vertical=vertical)


def _build_waypoints(station: Station, node_step_m: float) -> Waypoints:
    table = generate_table(station)
    robot = load_ur3(station.tool, station.limits, station.robot)
    n = max(2, math.ceil(station.approach / node_step_m)) + 1
    s_nodes = np.linspace(0.0, station.approach, n)
    vertical = tuple(tuple(vertical_path(robot, station, table.q, t, h, s_nodes) for h in range(station.n_heights))
                     for t in range(station.n_towers))
    return Waypoints(q_home=station.q_home_array, table=table.q, vertical=vertical)
