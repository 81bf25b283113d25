"""Motion plan of a Hanoi solve: waypoints from the table, time-parameterized by Ruckig under UR3 limits.

CONTRACT (shared with ur3hanoi.sim; keep these names and meanings):

- :class:`Phase` labels every trajectory sample.
- :class:`Trajectory` holds the samples at ``rate_hz``: ``t`` (N,) [s], ``q``/``qd``/``qdd``/``qddd`` (N, 6)
  [rad, rad/s, rad/s^2, rad/s^3], ``suction`` (N,) bool (commanded suction), ``move_index`` (N,) int (0-based
  index into ``Plan.moves``, -1 before the first move / on the way home), ``phase`` (N,) int (Phase values).
- :class:`Plan`: ``station``, ``moves`` (tuple of hanoi.Move), ``trajectory``, ``stop_and_go_duration_s``,
  ``config``.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt

from ur3hanoi.hanoi import Move
from ur3hanoi.station import Station

FloatArray = npt.NDArray[np.float64]


class Phase(IntEnum):
    """What the robot is doing at a trajectory sample."""

    TRANSIT = 0  # home/previous place -> above(src), empty cup
    DESCEND_PICK = 1  # above(src) -> on(src), empty cup
    GRASP_DWELL = 2  # at on(src), suction on, waiting for the vacuum
    LIFT = 3  # on(src) -> above(src), carrying
    CARRY = 4  # above(src) -> above(dst), carrying
    DESCEND_PLACE = 5  # above(dst) -> on(dst), carrying
    RELEASE_DWELL = 6  # at on(dst), suction off, waiting for the release
    RETREAT = 7  # on(dst) -> above(dst), empty cup
    HOME = 8  # last above -> home, suction off

    @property
    def carrying(self) -> bool:
        """True when a block must be held during this phase (suction feedback is checked)."""
        return self in (Phase.LIFT, Phase.CARRY, Phase.DESCEND_PLACE)


@dataclass(frozen=True)
class Trajectory:
    """Sampled joint trajectory at ``rate_hz`` (see the module docstring for array shapes and units)."""

    rate_hz: float
    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    qddd: FloatArray
    suction: npt.NDArray[np.bool_]
    move_index: npt.NDArray[np.int_]
    phase: npt.NDArray[np.int_]

    @property
    def duration_s(self) -> float:
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True)
class PlanConfig:
    """Planner settings. ``speed`` scales velocity, acceleration and jerk limits (0 < speed <= 1)."""

    speed: float = 1.0
    rate_hz: float = 125.0
    dwell_s: float = 0.3


@dataclass(frozen=True)
class Plan:
    station: Station
    moves: tuple[Move, ...]
    trajectory: Trajectory
    stop_and_go_duration_s: float
    config: PlanConfig
