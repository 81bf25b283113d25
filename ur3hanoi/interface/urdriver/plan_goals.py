"""A Ruckig plan as ``FollowJointTrajectory`` goals: what the UR driver's controller executes is the plan itself.

:func:`plan_stretches` cuts a :class:`ur3hanoi.plan.Plan` at its suction dwells (where the arm rests and the suction
switches): one **motion** goal per stretch between two dwells, and a **dwell** (grasp or release) between them. Each
motion goal carries the plan's own samples (positions, velocities and accelerations, every point the same fields, so
the controller interpolates quintics through them) at every :data:`POINT_STRIDE` th sample and the stretch's last;
its first point is the stretch's first sample (the arm at rest where the previous goal ended: the controller drops a
point at time 0 and bridges from its own desired state), its last point is at rest exactly
(velocity and acceleration 0, as ROS 2 Jazzy requires).

:func:`move_goal` is a slow rest-to-rest move (Ruckig at a fraction of the station's limits): bringing the arm to where
the plan starts, or home after a halt.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal, TrajectoryPoint
from ur3hanoi.plan import DWELL_PHASES, KinematicLimits, Phase, Plan, Trajectory, control_samples, to_pose
from ur3hanoi.station.calibration import Station

POINT_STRIDE = 1
"""Every this many plan samples a goal point. Every sample: at the plan's rate the controller's quintics through its
exact positions, velocities and accelerations give back the plan itself (1e-12 rad); every 5th (25 Hz) would leave
0.3 mrad at the joints (tests/interface/urdriver/test_plan_goals.py). A 27 s lab solve is 3,400 points in 15 goals."""
MOVE_POINT_DT_S = 0.04
"""[s] Point spacing of :func:`move_goal`."""


@dataclass(frozen=True)
class Stretch:
    """A piece of the plan: a ``motion`` (its goal) or a ``grasp``/``release`` dwell at rest.

    Attributes:
        kind: ``motion``, ``grasp`` or ``release``.
        k0, k1: first and last plan sample (inclusive).
        move: the plan's move index (0-based; -1 before the first move and on the way home).
        duration_s: its duration in the plan [s].
        carrying: a motion during which a block must stay held (lift, carry, place).
        goal: a motion's goal (None for a dwell).
    """

    kind: Literal["motion", "grasp", "release"]
    k0: int
    k1: int
    move: int
    duration_s: float
    carrying: bool = False
    goal: TrajectoryGoal | None = None


def _point(q: FloatArray, qd: FloatArray, qdd: FloatArray, t: float) -> TrajectoryPoint:
    return TrajectoryPoint(tuple(float(x) for x in q), tuple(float(x) for x in qd), tuple(float(x) for x in qdd),
                           time_from_start_s=float(t))


def samples_goal(t: FloatArray, q: FloatArray, qd: FloatArray, qdd: FloatArray,
                 joints: tuple[str, ...] = CONTROLLER_JOINTS) -> TrajectoryGoal:
    """A goal through samples ``t`` (n,) [s] and ``q``, ``qd``, ``qdd`` (n, 6) [rad, rad/s, rad/s^2], times from the
    first sample; the last point at rest exactly."""
    n = len(t)
    points = [_point(q[i], qd[i], qdd[i], t[i] - t[0]) for i in range(n - 1)]
    zero = np.zeros(q.shape[1])
    points.append(_point(q[-1], zero, zero, t[-1] - t[0]))
    return TrajectoryGoal(joints, tuple(points))


def motion_goal(tr: Trajectory, k0: int, k1: int, stride: int = POINT_STRIDE) -> TrajectoryGoal:
    """The goal of plan samples ``k0..k1``: every ``stride`` th and the last."""
    ks = list(range(k0, k1 + 1, stride))
    if ks[-1] != k1:
        ks.append(k1)
    idx = np.array(ks)
    return samples_goal(tr.t[idx], tr.q[idx], tr.qd[idx], tr.qdd[idx])


def plan_stretches(plan: Plan, stride: int = POINT_STRIDE) -> list[Stretch]:
    """The plan as motions and dwells, in order (see the module docstring)."""
    tr = plan.trajectory
    dwell = np.isin(tr.phase, [int(p) for p in DWELL_PHASES])
    out: list[Stretch] = []
    k, n = 0, len(tr.t)
    while k < n - 1:
        if dwell[k] and k + 1 < n and dwell[k + 1]:
            end = k
            while end + 1 < n and dwell[end + 1]:
                end += 1
            kind: Literal["grasp", "release"] = "grasp" if tr.phase[k] == Phase.GRASP_DWELL else "release"
            out.append(Stretch(kind, k, end, int(tr.move_index[k]), float(tr.t[end] - tr.t[k])))
            k = end
            continue
        end = k + 1
        while end < n - 1 and not dwell[end]:
            end += 1
        phases = {Phase(int(p)) for p in tr.phase[k + 1:end]}
        carrying = bool(phases) and all(p.carrying for p in phases)
        if any(p.carrying for p in phases) and not carrying:
            raise PlanError(f"plan samples {k}..{end} mix carrying and empty phases between two dwells")
        move = int(tr.move_index[min(k + 1, end)])
        out.append(Stretch("motion", k, end, move, float(tr.t[end] - tr.t[k]), carrying,
                           motion_goal(tr, k, end, stride)))
        k = end
    return out


def move_goal(q0: FloatArray, q1: FloatArray, station: Station, speed: float,
              dt: float = MOVE_POINT_DT_S) -> TrajectoryGoal:
    """A rest-to-rest goal from ``q0`` to ``q1`` [rad] at ``speed`` (0..1] of the station's speed, acceleration and
    jerk limits (Ruckig)."""
    lim = station.limits
    limits = KinematicLimits(v_max=speed * np.asarray(lim.v_max, dtype=float),
                             a_max=speed * np.asarray(lim.a_max, dtype=float),
                             j_max=speed * np.asarray(lim.j_max, dtype=float))
    z = np.zeros(len(q0))
    solution = to_pose(q0, z, z, q1, limits)
    if solution.trajectory is None:
        raise PlanError(f"the move to {np.round(q1, 4).tolist()} could not be planned: {solution.reason}")
    qs, vs, accs = control_samples(solution.trajectory, dt)
    t = np.concatenate([[0.0], np.minimum(dt * np.arange(1, len(qs) + 1), solution.trajectory.duration)])
    keep = np.concatenate([[True], np.diff(t) > 1e-9])  # the last sample may repeat the end time
    return samples_goal(t[keep], np.vstack([q0, qs])[keep], np.vstack([z, vs])[keep], np.vstack([z, accs])[keep])
