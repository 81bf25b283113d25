"""Is the arm still? A pose is recorded only when no joint moved more than :data:`STILL_TOL_DEG` over the last
:data:`STILL_WINDOW_S` seconds of the positions the driver published.

A taught pose is only as good as the moment it is taken: a pose recorded while the arm still coasts (freedrive let
go a moment ago, a jog step not settled) is off by however far it moved. 0.05 deg of the base joint is 0.3 mm at
the UR3's reach, well under the 1-3 mm a hand-taught pose scatters; a real UR3 at rest publishes angles steady to
about 0.001 deg.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray

STILL_WINDOW_S = 0.5
"""[s] the arm must have been still this long before a pose is recorded."""
STILL_TOL_DEG = 0.05
"""[deg] no joint may move more than this within :data:`STILL_WINDOW_S`."""
COVER_SLACK_S = 0.1
"""[s] the positions at hand must reach back to within this of the window's start (a 125 Hz driver publishes
every 8 ms; a DDS reader polled every few tens of ms delivers them in bunches)."""
STALE_S = 0.25
"""[s] the newest position must be at most this old: older, the driver has stopped publishing."""


@dataclass(frozen=True)
class Stillness:
    """The verdict on the last :data:`STILL_WINDOW_S` of positions.

    Attributes:
        still: True when a pose may be recorded.
        moved_deg: the largest range of any joint over the window [deg] (NaN without positions).
        why: "" when still; else what is wrong, for people ("the arm is moving: joint 1 moved 0.8 deg ...").
    """

    still: bool
    moved_deg: float
    why: str


def stillness(samples: Sequence[tuple[float, FloatArray]], now: float) -> Stillness:
    """Judge ``samples`` ((arrival time [s, time.monotonic], q [rad]) oldest first) at time ``now`` [s]."""
    recent = [(t, q) for t, q in samples if t >= now - STILL_WINDOW_S - COVER_SLACK_S]
    if not recent or now - recent[-1][0] > STALE_S:
        return Stillness(False, math.nan, "no position from the driver for the last "
                                          f"{STALE_S:g} s: is it still publishing?")
    if recent[0][0] > now - STILL_WINDOW_S + COVER_SLACK_S:
        return Stillness(False, math.nan, f"positions of the last {STILL_WINDOW_S:g} s are not in yet: wait a moment")
    qs = np.array([q for _, q in recent], dtype=float)
    ranges = np.degrees(qs.max(axis=0) - qs.min(axis=0))
    worst = int(np.argmax(ranges))
    moved = float(ranges[worst])
    if moved > STILL_TOL_DEG:
        return Stillness(False, moved, f"the arm is moving: joint {worst + 1} moved {moved:.2f} deg in the last "
                                       f"{STILL_WINDOW_S:g} s (a pose is recorded when no joint moves more than "
                                       f"{STILL_TOL_DEG:g} deg)")
    return Stillness(True, moved, "")


__all__ = ["COVER_SLACK_S", "STALE_S", "STILL_TOL_DEG", "STILL_WINDOW_S", "Stillness", "stillness"]
