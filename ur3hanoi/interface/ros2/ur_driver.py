"""The official UR ROS 2 driver (``ur_robot_driver``) as its clients see it: names per ROS 2 distribution, the
controller's profile per distribution, and the conversions between its messages and the middleware-neutral types of
:mod:`ur3hanoi.interface.urdriver` (sources: ``../shared/lab/ur-driver-interface.md`` section 2).

- Humble, Jazzy, Kilted: the scaled trajectory controller ``/scaled_joint_trajectory_controller``; Lyrical (and the
  driver's ``main``) removed it, scaling is built into ``/joint_trajectory_controller``
  (``ur_robot_driver/doc/migration/lyrical.rst``). IO on ``/io_and_status_controller``, speed scaling on
  ``/speed_scaling_state_broadcaster/speed_scaling`` in **percent** on every distribution.
- The controller (ros2_controllers' ``joint_trajectory_controller.cpp``): Humble accepts a last point that still moves
  (``allow_nonzero_velocity_at_trajectory_end`` defaults to true there), Jazzy and later reject it; a new goal
  preempts the running one, which aborts with INVALID_GOAL and "Current goal preempted by new incoming action."
  (Humble's controller writes "Current goal cancelled due to new incoming action." and marks it canceled, a
  transition rclpy's server allows only after a client's cancel request: the station aborts it with Humble's text).

Conversions take and return the rclpy message objects (``control_msgs``, ``ur_msgs``, ``sensor_msgs``) but import
nothing: the binding imports them (:mod:`ur3hanoi.interface.ros2.rclpy_env`) and passes the classes in.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, DriverNames
from ur3hanoi.interface.urdriver.goal import JointTolerance, TrajectoryGoal, TrajectoryPoint
from ur3hanoi.interface.urdriver.io import IoStates
from ur3hanoi.interface.urdriver.profile import ROS2_SCALED, ControllerProfile


def names_for(distro: str) -> DriverNames:
    """The driver's names on ``distro`` (one of :data:`~ur3hanoi.interface.ros2.rclpy_env.ROS_DISTROS`)."""
    controller = "joint_trajectory_controller" if distro == "lyrical" else "scaled_joint_trajectory_controller"
    return DriverNames(joint_states="/joint_states", follow_joint_trajectory=f"/{controller}/follow_joint_trajectory",
                       set_io="/io_and_status_controller/set_io", io_states="/io_and_status_controller/io_states",
                       speed_scaling="/speed_scaling_state_broadcaster/speed_scaling",
                       program_running="/io_and_status_controller/robot_program_running")


FEEDBACK_HZ = 20.0
"""The trajectory controller's ``action_monitor_rate``: feedback of the running goal [Hz]."""
SPEED_SCALING_HZ = 100.0
"""The speed scaling broadcaster's ``state_publish_rate`` [Hz]."""

PREEMPTED_TEXT = {"humble": "Current goal cancelled due to new incoming action."}
"""The preempted goal's ``error_string`` where it differs from Jazzy's."""
PREEMPTED_DEFAULT = "Current goal preempted by new incoming action."


def profile_for(distro: str) -> ControllerProfile:
    """The trajectory controller of ``distro``: Jazzy's (:data:`ROS2_SCALED`), on Humble accepting a moving last
    point."""
    if distro == "humble":
        return dataclasses.replace(ROS2_SCALED, name="ros2_scaled_humble", reject_nonzero_final_velocity=False)
    return dataclasses.replace(ROS2_SCALED, name=f"ros2_{distro}")


def preempted_text(distro: str) -> str:
    """``error_string`` of a goal preempted by a new one on ``distro``."""
    return PREEMPTED_TEXT.get(distro, PREEMPTED_DEFAULT)


# ------------------------------------------------------------------------------------------------ messages in
def duration_s(d: Any) -> float:
    """``builtin_interfaces/Duration`` (or ``Time``) in seconds."""
    return float(d.sec) + 1e-9 * float(d.nanosec)


def _floats(values: Any) -> tuple[float, ...]:
    return tuple(float(x) for x in values)


def goal_from_msg(goal: Any, now_s: float) -> TrajectoryGoal:
    """A ``FollowJointTrajectory`` goal as the neutral :class:`TrajectoryGoal`; ``now_s`` is the station's ROS clock
    [s] (a non-zero ``header.stamp`` becomes ``start_in_s``)."""
    traj = goal.trajectory
    stamp = duration_s(traj.header.stamp)
    points = tuple(TrajectoryPoint(_floats(p.positions), _floats(p.velocities), _floats(p.accelerations),
                                   _floats(p.effort), duration_s(p.time_from_start)) for p in traj.points)

    def tolerances(items: Any) -> tuple[JointTolerance, ...]:
        return tuple(JointTolerance(str(t.name), float(t.position), float(t.velocity), float(t.acceleration))
                     for t in items)

    return TrajectoryGoal(tuple(str(n) for n in traj.joint_names), points, tolerances(goal.path_tolerance),
                          tolerances(goal.goal_tolerance), duration_s(goal.goal_time_tolerance),
                          None if stamp == 0.0 else stamp - now_s)


def joint_positions(names: Any, positions: Any) -> FloatArray | None:
    """A ``/joint_states`` message's positions in the controller's joint order, by name (the driver guarantees no
    order), or None when one of the six is missing or the lengths differ."""
    names, positions = list(names), list(positions)
    if len(names) != len(positions):
        return None
    index = {str(n): i for i, n in enumerate(names)}
    if not all(j in index for j in CONTROLLER_JOINTS):
        return None
    return np.array([float(positions[index[j]]) for j in CONTROLLER_JOINTS])


def io_from_msg(msg: Any) -> IoStates:
    """``ur_msgs/IOStates`` as :class:`IoStates` (digital states by ``pin``; absent pins read False / 0)."""
    def digital(items: Any, n: int = 18) -> tuple[bool, ...]:
        by_pin = {int(d.pin): bool(d.state) for d in items}
        return tuple(by_pin.get(i, False) for i in range(n))

    def analog(items: Any, n: int = 2) -> tuple[tuple[int, float], ...]:
        by_pin = {int(a.pin): (int(a.domain), float(a.state)) for a in items}
        return tuple(by_pin.get(i, (1, 0.0)) for i in range(n))

    return IoStates(digital(msg.digital_in_states), digital(msg.digital_out_states), analog(msg.analog_in_states),
                    analog(msg.analog_out_states))


# ----------------------------------------------------------------------------------------------- messages out
def set_duration(d: Any, seconds: float) -> Any:
    """Fill a ``builtin_interfaces`` Duration or Time with ``seconds`` (>= 0, whole nanoseconds)."""
    ns = round(seconds * 1e9)
    d.sec, d.nanosec = ns // 1_000_000_000, ns % 1_000_000_000
    return d


def goal_to_msg(goal: TrajectoryGoal, action: Any, trajectory_msgs: Any) -> Any:
    """The neutral goal as a ``FollowJointTrajectory.Goal`` (``action`` = the action class; zero ``header.stamp``:
    start now)."""
    msg = action.Goal()
    msg.trajectory.joint_names = list(goal.joint_names)
    points = []
    for p in goal.points:
        point = trajectory_msgs.JointTrajectoryPoint(positions=list(p.positions), velocities=list(p.velocities),
                                                     accelerations=list(p.accelerations), effort=list(p.effort))
        set_duration(point.time_from_start, p.time_from_start_s)
        points.append(point)
    msg.trajectory.points = points
    set_duration(msg.goal_time_tolerance, max(goal.goal_time_tolerance_s, 0.0))
    return msg
