"""The vertical line of a grid slot as a joint-space path ``q(s)``, and limits for following it exactly.

A straight joint-space line between a slot's above and on poses bends the suction point up to ~10 mm off the
vertical on the lab stations. :class:`VerticalPath` is the line itself: closed-form IK points on it (on home's
branch) every few millimetres, interpolated by a cubic Hermite spline of (q, dq/ds). The approach legs
(:mod:`ur3hanoi.plan.motion.legs`) take their interior points and tangents from it. Following it exactly with a 1-DoF
Ruckig trajectory of the path coordinate ``s`` [m] under :class:`PathLimits` (constant limits that keep every joint
within its own) is the always-feasible fallback of a rest-to-rest leg and the "exact vertical" stop-and-go
reference (:mod:`ur3hanoi.plan.baseline.stop_and_go`); :func:`braking_speed` bounds the speed such a leg can stop
from within a distance.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.plan.types import KinematicLimits, VerticalPath
from ur3hanoi.robot.ik import analytic_ik, branch_of, nearest_equivalent
from ur3hanoi.robot.model import Ur3Model
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, T_base_tcp

FD_STEP_M = 1e-3  # [m] finite-difference step of the higher path derivatives

# Placing onto a stack: the last PLACE_BAND_M [m] above the contact pose within PLACE_TOL_M [m] of the vertical line
# (descend legs, 1 kHz, less legs.DENSE_MARGIN_M), for every slot at 0-based height >= PLACE_MIN_HEIGHT (a block
# below). Why: the simulated arm tracks the plan within ~0.25 mm and dips that far below the contact pose as it
# stops, so the carried block touches the stack while the suction point still closes in on the line; pressed down
# (0.6-0.75 N, three times its weight) and dragged sideways by friction, it tilts the stack below by ~0.4 deg, and
# on release the stack springs back and throws the block ~0.6 mm off. Measured on a tall grid (8 levels, 7 blocks,
# bench/bench_executes.py's): legs within 0.45-0.57 mm of the line in their last 0.5 mm shifted the released block
# by 0.01-0.12 mm per placement, legs at 0.75 and 0.87 mm by 0.58 and 0.35 mm, and tower 1 height 3, placed on 15
# times, drove the top block 8.1 mm off (final check 5 mm). The lab stations' descend legs come within 0.16-0.48 mm
# (lab_real tower 1 height 3 the most), so their plans are unchanged (bit-identical samples). On the table
# (height 0) nothing below can tilt: no band.
PLACE_BAND_M = 5e-4
PLACE_TOL_M = 6e-4
PLACE_MIN_HEIGHT = 1


def place_band(height: int) -> tuple[float, float] | None:
    """(band above the contact pose [m], allowed distance from the vertical line within it [m]) of a slot at 0-based
    ``height``, or None where no stack is below (:data:`PLACE_BAND_M`, :data:`PLACE_TOL_M`)."""
    return (PLACE_BAND_M, PLACE_TOL_M) if height >= PLACE_MIN_HEIGHT else None


def tangent_down(robot: Ur3Model, R_world_base: FloatArray, q: FloatArray) -> FloatArray:
    """Joint velocity [rad/s] moving the TCP at 1 m/s along world -z without rotating (J^-1 of the twist)."""
    J = robot.frame_jacobian_local(q, "tcp")
    R_world_tcp = R_world_base @ robot.fk(q, "tcp").rotation
    twist = np.concatenate([R_world_tcp.T @ np.array([0.0, 0.0, -1.0]), np.zeros(3)])
    return np.linalg.solve(J, twist)


def line_ik(robot: Ur3Model, station: Station, tower: int, height: int) -> Callable[[float, FloatArray], FloatArray]:
    """``ik(s, q_ref)``: closed-form IK [rad] of the suction point ``s`` [m] below the above pose of (tower, height),
    on home's branch, nearest ``q_ref``."""
    import pinocchio as pin

    T_above = T_base_tcp(station, tower, height, ABOVE)
    R_base_world = station.T_world_base.rotation.T
    branch = branch_of(station.q_home_array, robot.dh)

    def ik(s: float, q_ref: FloatArray) -> FloatArray:
        T = pin.SE3(T_above.rotation, T_above.translation - R_base_world @ np.array([0.0, 0.0, s]))
        sols = analytic_ik(T * robot.T_tcp_tool0, only=branch, dh=robot.dh)
        q = nearest_equivalent(sols[branch], q_ref, station.limits) if branch in sols else None
        if q is None:
            raise PlanError(f"tower {tower + 1} height {height + 1}: the vertical line {s * 1e3:.1f} mm below the "
                            "above pose has no IK solution on home's branch within the joint limits")
        return q

    return ik


def vertical_path(robot: Ur3Model, station: Station, table_q: FloatArray, tower: int, height: int,
                  s_nodes: FloatArray) -> VerticalPath:
    """The :class:`VerticalPath` of slot (tower, height) with nodes at ``s_nodes`` [m] (0 .. approach length).

    ``table_q`` is the table ``q[tower, height, k]`` [rad]; its above/on entries become the end nodes exactly
    (they agree with closed-form IK to ~1e-11 rad).
    """
    R_world_base = station.T_world_base.rotation
    ik = line_ik(robot, station, tower, height)
    n = len(s_nodes)
    q_nodes = np.empty((n, N_JOINTS))
    q_ref = table_q[tower, height, ABOVE]
    for k, s in enumerate(s_nodes):
        q_nodes[k] = q_ref = ik(float(s), q_ref)
    q_nodes[0], q_nodes[-1] = table_q[tower, height, ABOVE], table_q[tower, height, ON]
    dq = np.array([tangent_down(robot, R_world_base, q) for q in q_nodes])
    ddq = np.empty_like(dq)
    dddq = np.empty_like(dq)
    for k, (s, q) in enumerate(zip(s_nodes, q_nodes, strict=True)):
        dm = tangent_down(robot, R_world_base, ik(float(s) - FD_STEP_M, q))
        dp = tangent_down(robot, R_world_base, ik(float(s) + FD_STEP_M, q))
        ddq[k] = (dp - dm) / (2 * FD_STEP_M)
        dddq[k] = (dp - 2 * dq[k] + dm) / (FD_STEP_M * FD_STEP_M)
    return VerticalPath(s=s_nodes, q=q_nodes, dq=dq, ddq=ddq, dddq=dddq, length_m=station.approach)


def braking_speed(dist: float, a: float, j: float) -> float:
    """Largest speed a jerk-limited (a, j) profile starting at zero acceleration stops from within ``dist``."""
    # Stopping distance d(v): v*sqrt(v/j) if the profile never reaches a (v <= a^2/j), else v^2/(2a) + v*a/(2j).
    v_knee = a * a / j
    if v_knee * math.sqrt(v_knee / j) >= dist:
        return (dist * dist * j) ** (1.0 / 3.0)
    b = a / (2 * j)
    return (-b + math.sqrt(b * b + 2 * dist / a)) * a


@dataclass(frozen=True)
class PathLimits:
    """Limits of the path coordinate s of a vertical leg [m/s, m/s^2, m/s^3].

    They keep every joint within its limits through the chain rule ``qd = q1 sd``, ``qdd = q2 sd^2 + q1 sdd``,
    ``qddd = q3 sd^3 + 3 q2 sd sdd + q1 sddd`` (``qk`` = k-th derivative of q(s)). Budget split, per joint, with
    ``Dk = 1.05 max |qk|`` over the path: ``D1 v <= v_max``; ``D2 v^2 <= 0.4 a_max`` and ``D1 a`` takes the rest;
    ``D3 v^3 <= 0.3 j_max``, ``3 D2 v a <= 0.4 j_max`` and ``D1 j`` takes the rest.
    """

    v: float
    a: float
    j: float

    @classmethod
    def for_path(cls, path: VerticalPath, lim: KinematicLimits) -> PathLimits:
        D1, D2, D3 = (1.05 * x + 1e-12 for x in path.derivative_bounds)
        v = float(np.min(np.minimum.reduce([lim.v_max / D1, np.sqrt(0.4 * lim.a_max / D2),
                                            np.cbrt(0.3 * lim.j_max / D3)])))
        a = float(np.min(np.minimum((lim.a_max - D2 * v * v) / D1, 0.4 * lim.j_max / (3 * D2 * v))))
        j = float(np.min((lim.j_max - D3 * v**3 - 3 * D2 * v * a) / D1))
        return cls(v, a, j)
