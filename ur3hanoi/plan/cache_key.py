"""What a planner result kept in the user's cache (:mod:`ur3hanoi.io.cache`) depends on: the inputs of its key.

:func:`station_inputs`: the station geometry (the :class:`~ur3hanoi.station.calibration.Station` value without its name
and file, every float by ``repr``, so the same value is the same key and any changed field a new one), the robot model
(its URDF text with the tool frame), the Ruckig and NumPy versions (their arithmetic makes the numbers), and the
planner's own source (the ``ur3hanoi.plan`` package and the layers it reads: the loose modules, ``robot``,
``station`` and ``tables``, by content): a changed input or a
changed planner is a new entry, never a stale result.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ur3hanoi.io import cache
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station

PLANNER_SOURCE: tuple[str, ...] = ("plan", "", "robot", "station", "tables")
"""The planner's source, by :func:`ur3hanoi.io.cache.source_digest`: ``plan`` and the layers under it that it reads."""


def source_digest() -> bytes:
    """sha256 of the planner's source: every module of :data:`PLANNER_SOURCE`."""
    return cache.source_digest(PLANNER_SOURCE)


@lru_cache(maxsize=16)
def station_inputs(station: Station) -> tuple[bytes, ...]:
    """The key inputs of everything cached for ``station`` (pass its geometry, see the module docstring)."""
    import ruckig

    return (f"ruckig {ruckig.__version__}, numpy {np.__version__}".encode(), source_digest(),
            repr(station).encode(), load_ur3(station.tool, station.limits, station.robot).urdf.encode())
