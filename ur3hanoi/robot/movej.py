"""The UR controller's ``movej`` profile: a synchronised trapezoidal velocity profile in joint space.

``movej(q, a, v)`` on a UR moves every joint along a straight line in joint space, ``q(t) = q0 + (q1 - q0) s(t)``,
with one normalised path parameter ``s`` in [0, 1] shared by all joints, so they start, reach cruise speed, brake
and stop together. ``s`` is a trapezoid in velocity (constant acceleration, cruise, constant deceleration; a
triangle when the move is too short to reach cruise speed). The *leading* joint, the one with the largest motion
relative to its limits, moves at the commanded speed ``v`` [rad/s] and acceleration ``a`` [rad/s^2]; the others
are scaled down.

ur3hanoi caps ``v`` and ``a`` per joint at the station's limits (UR3 datasheet speeds: 180 deg/s for joints 1-3,
360 deg/s for the wrists; accelerations 4 / 8 rad/s^2, see :class:`ur3hanoi.robot.model.JointLimits`): joint i may use
at most ``min(v, v_max_i)`` and ``min(a, a_max_i)``, and the shared profile is the fastest trapezoid satisfying
every joint's caps. With the lab's ``v = a = 4.0`` the base, shoulder and elbow are capped at pi rad/s and
4 rad/s^2, the wrists at 4 rad/s and 4 rad/s^2.

Why a trapezoid computed here and not Ruckig: this is what the UR controller does for ``movej`` (infinite jerk,
acceleration steps), and the station must reproduce the controller's timing (the course's simulator: duration
about ``max_i |dq_i| / v`` for long moves). Ruckig's jerk-limited profiles are the planner's business
(:mod:`ur3hanoi.plan`); the servo in MuJoCo tracks these acceleration steps with about 2 mrad of lag.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray

_EPS_RAD = 1e-12  # joints moving less than this [rad] do not constrain the profile


@dataclass(frozen=True)
class MoveJ:
    """One synchronised trapezoidal joint move (see the module docstring).

    Attributes:
        q0, q1: start and destination [rad].
        s_vel: cruise (or triangle peak) speed of the path parameter [1/s].
        s_acc: acceleration of the path parameter [1/s^2].
        t_acc: duration of the acceleration (and of the deceleration) phase [s].
        duration: total duration [s]; 0 for a move of zero length.
    """

    q0: FloatArray
    q1: FloatArray
    s_vel: float
    s_acc: float
    t_acc: float
    duration: float

    @property
    def peak_velocity(self) -> FloatArray:
        """Peak speed of each joint [rad/s]."""
        return np.abs(self.q1 - self.q0) * self.s_vel

    @property
    def peak_acceleration(self) -> FloatArray:
        """Acceleration of each joint during the ramps [rad/s^2] (absolute value)."""
        return np.abs(self.q1 - self.q0) * self.s_acc

    def path(self, t: float) -> tuple[float, float, float]:
        """The path parameter ``s``, its rate ``ds/dt`` [1/s] and its acceleration ``d2s/dt2`` [1/s^2] at time
        ``t`` [s] (clamped to [0, duration]; the acceleration steps at the ramps' ends, and is zero at rest)."""
        T, ta, A, V = self.duration, self.t_acc, self.s_acc, self.s_vel
        if t <= 0.0 or T <= 0.0:
            return (1.0, 0.0, 0.0) if T <= 0.0 else (0.0, 0.0, 0.0)
        if t >= T:
            return 1.0, 0.0, 0.0
        if t < ta:
            return 0.5 * A * t * t, A * t, A
        if t <= T - ta:
            return 0.5 * A * ta * ta + V * (t - ta), V, 0.0
        r = T - t
        return 1.0 - 0.5 * A * r * r, A * r, -A

    def sample(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Joint positions [rad], velocities [rad/s] and accelerations [rad/s^2] at time ``t`` [s]; exactly ``q1``
        at rest from ``duration`` on."""
        if t >= self.duration:
            return self.q1.copy(), np.zeros_like(self.q1), np.zeros_like(self.q1)
        s, ds, dds = self.path(t)
        dq = self.q1 - self.q0
        return self.q0 + s * dq, ds * dq, dds * dq


def plan_movej(q0: Sequence[float] | FloatArray, q1: Sequence[float] | FloatArray, v: float, a: float,
               v_max: Sequence[float], a_max: Sequence[float]) -> MoveJ:
    """The fastest synchronised trapezoid from ``q0`` to ``q1`` [rad] with joint i within ``min(v, v_max[i])``
    [rad/s] and ``min(a, a_max[i])`` [rad/s^2]. ``v`` and ``a`` must be positive (checked by the caller)."""
    start = np.array(q0, dtype=float)
    end = np.array(q1, dtype=float)
    dist = np.abs(end - start)
    moving = dist > _EPS_RAD
    if not np.any(moving):
        return MoveJ(start, end, 0.0, 0.0, 0.0, 0.0)
    v_cap = np.minimum(v, np.asarray(v_max, dtype=float))[moving]
    a_cap = np.minimum(a, np.asarray(a_max, dtype=float))[moving]
    s_vel = float(np.min(v_cap / dist[moving]))
    s_acc = float(np.min(a_cap / dist[moving]))
    if s_vel <= 0.0 or s_acc <= 0.0:  # v or a so small that the rate underflows: a move that never ends
        return MoveJ(start, end, s_vel, s_acc, math.inf, math.inf)
    if s_vel * s_vel / s_acc >= 1.0:  # cruise speed not reached within the unit path: a triangle
        t_acc = math.sqrt(1.0 / s_acc)
        return MoveJ(start, end, s_acc * t_acc, s_acc, t_acc, 2.0 * t_acc)
    t_acc = s_vel / s_acc
    return MoveJ(start, end, s_vel, s_acc, t_acc, 1.0 / s_vel + t_acc)


class MoveJReference:
    """The controller's joint reference under ``movej`` commands: each move starts where the reference rests (the
    end of the last one), and the reference is sampled once per control period.

    Args:
        q: the reference to start from, at rest [rad].
        v_max, a_max: the joints' speed [rad/s] and acceleration [rad/s^2] caps (:func:`plan_movej`).
    """

    def __init__(self, q: Sequence[float] | FloatArray, v_max: Sequence[float], a_max: Sequence[float]) -> None:
        self.q: FloatArray = np.array(q, dtype=float)  # the reference at the end of the last period [rad]
        self.target: FloatArray = self.q.copy()  # destination of the current (or last) move [rad]
        self.v_max, self.a_max = v_max, a_max
        self.motion: MoveJ | None = None  # the move running, if any
        self.t = 0.0  # time into it [s]

    def begin(self, destination: Sequence[float] | FloatArray, v: float, a: float) -> MoveJ:
        """Start ``movej(destination, a, v)`` from the reference; returns its profile (a move of zero length ends
        at once)."""
        motion = plan_movej(self.q, destination, v, a, self.v_max, self.a_max)
        self.target = motion.q1.copy()
        self.t = 0.0
        self.motion = motion if motion.duration > 0.0 else None
        if self.motion is None:
            self.q = motion.q1.copy()
        return motion

    def advance(self, dt: float) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """The reference ``dt`` [s] further into the running move: positions [rad], velocities [rad/s] and
        accelerations [rad/s^2]; None at rest (the reference stays :attr:`q`)."""
        if self.motion is None:
            return None
        self.t += dt
        sample = self.motion.sample(self.t)
        if self.t >= self.motion.duration:
            self.motion = None
        self.q = sample[0]
        return sample
