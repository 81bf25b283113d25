"""Clearance results kept in the user's cache (:mod:`ur3hanoi.io.cache`): a plan the cache rebuilt is not re-checked.

The planner's clearance check (:func:`~ur3hanoi.plan.checks.clearance.check_segments`: the collision scene, then
every distinct segment against every slot) is a third of a cold plan whose connections come from the cache, and
its result is a function of the plan's content alone. :func:`check_segments` keeps that result, the list of
violation messages, on disk:

- **Key**: :func:`~ur3hanoi.plan.cache_key.station_inputs` (station geometry, robot model with its tool frame,
  Ruckig and NumPy versions, the planner's source, which includes the check's own code), the collision geometry's
  origin (the Pinocchio, coal and example-robot-data versions, and each collision mesh's path and size), the plan
  configuration, limits, moves, blocks and start tower, and the plan's motion itself: every segment's phase, move,
  times and boundary states and every sample of the trajectory (t, q, qd), by their bytes. A plan that differs in
  anything the check reads is a new entry, never an old result.
- **Entry**: the violation messages as JSON; an entry that does not decode to a list of strings is rebuilt
  (:func:`ur3hanoi.io.cache.cached`: atomic, safe when processes race, a corrupt entry ignored and rewritten).
- Pinocchio and coal are imported only when the check runs (a cache miss).
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Sequence
from functools import lru_cache
from pathlib import Path

import numpy as np

from ur3hanoi.hanoi import Move
from ur3hanoi.io.cache import cached, installed_versions
from ur3hanoi.plan.cache_key import station_inputs
from ur3hanoi.plan.motion.waypoints import geometry_key
from ur3hanoi.plan.types import KinematicLimits, PlanConfig, Segment, Trajectory
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station

CLEARANCE = "plan-clearance"
"""Kind of the cache entries of :func:`check_segments`."""

_MESH = re.compile(r'filename="([^"]+)"')
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.S)


def check_segments(segments: Sequence[Segment], moves: Sequence[Move], station: Station, n_blocks: int, start: int,
                   config: PlanConfig, limits: KinematicLimits, trajectory: Trajectory) -> list[str]:
    """:func:`ur3hanoi.plan.checks.clearance.check_segments` of a plan whose samples are ``trajectory``, through the
    user's cache: the same violations."""

    def build() -> list[str]:
        from ur3hanoi.plan.checks.clearance import check_segments as check

        return check(segments, moves, station, n_blocks, start, config, limits)

    plan = repr((tuple(moves), n_blocks, start, config, limits.v_max.tolist(), limits.a_max.tolist(),
                 limits.j_max.tolist())).encode()
    geometry = geometry_key(station)
    inputs = [*station_inputs(geometry), *_geometry_inputs(geometry), plan,
              motion_digest(segments, trajectory)]
    return cached(CLEARANCE, inputs, build, lambda v: json.dumps(v).encode(), _decode)


def motion_digest(segments: Sequence[Segment], trajectory: Trajectory) -> bytes:
    """sha256 of a plan's motion: each segment's phase, move, start, duration, boundary states and kind, and the
    samples' t, q and qd."""
    h = hashlib.sha256()
    for seg in segments:
        h.update(repr((int(seg.phase), seg.move_index, seg.t_start, seg.duration, seg.trajectory is None,
                       seg.path is not None)).encode())
        for x in (seg.q_start, seg.q_end, seg.v_start, seg.v_end):
            h.update(np.ascontiguousarray(x, dtype=np.float64).tobytes())
    for x in (trajectory.t, trajectory.q, trajectory.qd):
        h.update(np.ascontiguousarray(x, dtype=np.float64).tobytes())
    return h.digest()


@lru_cache(maxsize=8)
def _geometry_inputs(station: Station) -> tuple[bytes, ...]:
    """What the collision geometry is made of besides the URDF text: the libraries and the collision meshes."""
    versions = installed_versions(("pin", "coal", "example_robot_data"))
    meshes = []
    for block in _COLLISION.findall(load_ur3(station.tool, station.limits, station.robot).urdf):
        for mesh in _MESH.findall(block):
            try:
                size = os.stat(mesh).st_size
            except OSError:
                size = -1
            meshes.append((Path(mesh).as_posix(), size))
    return (repr(versions).encode(), repr(meshes).encode())


def _decode(payload: bytes) -> list[str] | None:
    value = json.loads(payload)
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        return None
    return value


__all__ = ["CLEARANCE", "check_segments", "motion_digest"]
