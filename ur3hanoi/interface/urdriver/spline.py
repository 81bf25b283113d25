"""The joint trajectory controller's segments: linear, cubic or quintic by the fields both end points give.

A port of ros_controllers' ``trajectory_interface/quintic_spline_segment.h`` (noetic-devel), which ros2_controllers'
``trajectory.cpp`` interpolates the same way ("splines"), vectorised over the joints: a segment between two states
is

- **linear** when either end has no velocities,
- **cubic** (position and velocity at both ends) when either end has no accelerations,
- **quintic** (position, velocity and acceleration at both ends) when both have all three,

so a trajectory whose points give different fields is interpolated at the lower degree; the first segment starts at
the controller's current desired state, which always has all three. Sampled outside ``[start, end]`` a segment holds
its end position with zero velocity and acceleration (``sampleWithTimeBounds``); a segment of zero duration holds its
start (the coefficients of a zero ``time`` there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ur3hanoi.arrays import FloatArray

_D1 = np.array([1.0, 2.0, 3.0, 4.0, 5.0])  # d/dt of t^k: k t^(k-1), k = 1..5
_D2 = np.array([2.0, 6.0, 12.0, 20.0])  # d2/dt2 of t^k: k (k-1) t^(k-2), k = 2..5


class JointState(NamedTuple):
    """One state of every joint: positions [rad], velocities [rad/s], accelerations [rad/s^2], each (n,); a field
    a trajectory point does not give is None."""

    q: FloatArray
    qd: FloatArray | None = None
    qdd: FloatArray | None = None


@dataclass(frozen=True)
class Segment:
    """A polynomial per joint from ``start_s`` to ``end_s`` (controller time [s]).

    Attributes:
        start_s, end_s: controller time [s] of the segment's start and end.
        coefficients: (n, 6) ``c0 + c1 t + ... + c5 t^5`` per joint, ``t`` from the start [s].
        degree: 1, 3 or 5 (linear, cubic, quintic).
    """

    start_s: float
    end_s: float
    coefficients: FloatArray
    degree: int

    @property
    def duration_s(self) -> float:
        return self.end_s - self.start_s

    def sample(self, t_s: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions [rad], velocities [rad/s] and accelerations [rad/s^2] at controller time ``t_s`` [s]; before
        the start the start position, after the end the end position, both at rest."""
        T = self.duration_s
        t = t_s - self.start_s
        c = self.coefficients
        if t < 0.0 or t > T:
            x = 0.0 if t < 0.0 else T
            p = c @ np.array([1.0, x, x * x, x ** 3, x ** 4, x ** 5])
            z = np.zeros(len(c))
            return p, z, z.copy()
        powers = np.array([1.0, t, t * t, t ** 3, t ** 4, t ** 5])
        p = c @ powers
        v = c[:, 1:] @ (_D1 * powers[:5])
        a = c[:, 2:] @ (_D2 * powers[:4])
        return p, v, a


def degree_of(start: JointState, end: JointState) -> int:
    """The interpolation both states allow: 1 (a velocity missing), 3 (an acceleration missing) or 5."""
    if start.qd is None or end.qd is None:
        return 1
    if start.qdd is None or end.qdd is None:
        return 3
    return 5


def segment(start_s: float, start: JointState, end_s: float, end: JointState) -> Segment:
    """The segment from ``start`` at controller time ``start_s`` to ``end`` at ``end_s`` [s], of the degree both
    states allow (see the module docstring); ``end_s >= start_s``."""
    if end_s < start_s:
        raise ValueError(f"segment end {end_s} s is before its start {start_s} s")
    T = end_s - start_s
    p0, p1 = np.asarray(start.q, dtype=float), np.asarray(end.q, dtype=float)
    c = np.zeros((len(p0), 6))
    c[:, 0] = p0
    deg = degree_of(start, end)
    if deg == 1:
        c[:, 1] = 0.0 if T == 0.0 else (p1 - p0) / T
        return Segment(start_s, end_s, c, 1)
    assert start.qd is not None and end.qd is not None
    v0, v1 = np.asarray(start.qd, dtype=float), np.asarray(end.qd, dtype=float)
    c[:, 1] = v0
    if deg == 3:
        if T > 0.0:
            c[:, 2] = (-3.0 * p0 + 3.0 * p1 - 2.0 * v0 * T - v1 * T) / T ** 2
            c[:, 3] = (2.0 * p0 - 2.0 * p1 + v0 * T + v1 * T) / T ** 3
        return Segment(start_s, end_s, c, 3)
    assert start.qdd is not None and end.qdd is not None
    a0, a1 = np.asarray(start.qdd, dtype=float), np.asarray(end.qdd, dtype=float)
    c[:, 2] = 0.5 * a0
    if T > 0.0:
        T2, dp = T * T, p1 - p0
        c[:, 3] = (20.0 * dp - 3.0 * a0 * T2 + a1 * T2 - 12.0 * v0 * T - 8.0 * v1 * T) / (2.0 * T ** 3)
        c[:, 4] = (-30.0 * dp + 3.0 * a0 * T2 - 2.0 * a1 * T2 + 16.0 * v0 * T + 14.0 * v1 * T) / (2.0 * T ** 4)
        c[:, 5] = (12.0 * dp - a0 * T2 + a1 * T2 - 6.0 * v0 * T - 6.0 * v1 * T) / (2.0 * T ** 5)
    return Segment(start_s, end_s, c, 5)


def find_segment(segments: list[Segment], t_s: float) -> int:
    """Index of the segment in force at controller time ``t_s``: the last one starting at or before it, or the
    first when ``t_s`` precedes them all (``trajectory_interface::sample``). ``segments`` is sorted, non-empty."""
    lo, hi = 0, len(segments)
    while lo < hi:  # first segment starting after t_s
        mid = (lo + hi) // 2
        if t_s < segments[mid].start_s:
            hi = mid
        else:
            lo = mid + 1
    return max(lo - 1, 0)
