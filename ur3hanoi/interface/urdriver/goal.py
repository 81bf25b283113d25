"""A ``FollowJointTrajectory`` goal without a middleware, and the checks a UR driver's controller makes before it
accepts one.

A binding converts its message into a :class:`TrajectoryGoal` (every field as the message has it: an absent
velocity list is an empty tuple) and asks :func:`check_goal` (or hands it to the follower, which asks it too). The
checks and texts are the controllers' own:

- ROS 1 (``joint_trajectory_controller`` noetic-devel ``goalCB``, ``init_joint_trajectory.h``): a goal naming other
  joints, or not all six, is rejected with INVALID_JOINTS and no ``error_string``; times not strictly increasing
  and point fields of the wrong length with INVALID_GOAL and the controller's text; a goal whose points all lie in
  the past is decided by the follower (it knows the time). An empty trajectory is accepted: the arm stops and holds.
- ROS 2 (``joint_trajectory_controller.cpp``, jazzy ``validate_trajectory_msg``): the same conditions plus an empty
  trajectory, a final point that still moves (Jazzy and newer) and a non-zero stamp ending in the past; the goal is
  rejected at ``send_goal`` without a result, the reason only logged.

One deviation from both: non-finite numbers are refused (INVALID_GOAL) rather than sent to the simulated arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ErrorCode
from ur3hanoi.interface.urdriver.profile import ControllerProfile

FLOAT_EPS = 1.1920928955078125e-07
"""``std::numeric_limits<float>::epsilon()``: ROS 2's threshold for a non-zero final velocity [rad/s]."""


@dataclass(frozen=True)
class TrajectoryPoint:
    """``trajectory_msgs/JointTrajectoryPoint``: values in the goal's joint order; an empty tuple = not given."""

    positions: tuple[float, ...]
    velocities: tuple[float, ...] = ()
    accelerations: tuple[float, ...] = ()
    effort: tuple[float, ...] = ()
    time_from_start_s: float = 0.0


@dataclass(frozen=True)
class JointTolerance:
    """``control_msgs/JointTolerance``: 0 = the controller's default, -1 (any negative) = not checked."""

    name: str
    position: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0


@dataclass(frozen=True)
class TrajectoryGoal:
    """``control_msgs/FollowJointTrajectoryGoal`` (the fields the UR drivers read).

    Attributes:
        joint_names: the joints the points' values belong to, in that order.
        points: the trajectory.
        path_tolerance, goal_tolerance: per-joint overrides of the controller's tolerances.
        goal_time_tolerance_s: > 0 replaces the controller's goal time [s]; 0 keeps it; < 0 means none.
        start_in_s: ``header.stamp`` minus the controller's clock now [s]; None for a zero stamp (start now).
    """

    joint_names: tuple[str, ...]
    points: tuple[TrajectoryPoint, ...]
    path_tolerance: tuple[JointTolerance, ...] = ()
    goal_tolerance: tuple[JointTolerance, ...] = ()
    goal_time_tolerance_s: float = 0.0
    start_in_s: float | None = None


@dataclass(frozen=True)
class Rejection:
    """Why a controller refuses a goal: ``code`` and ``error_string`` as the ROS 1 result carries them, ``reason``
    what the controller logs (ROS 2's only trace of it)."""

    code: ErrorCode
    error_string: str
    reason: str

    def describe(self) -> str:
        """One line: ``INVALID_GOAL (-1): <reason>``."""
        from ur3hanoi.interface.urdriver.facts import code_name

        return f"{code_name(self.code)}: {self.reason}"


_SIZE = "Size mismatch in trajectory point position, velocity or acceleration data."
_NOT_INCREASING = "Trajectory message contains waypoints that are not strictly increasing in time."
_JOINTS = "Joints on incoming goal don't match the controller joints."


def _sizes_ros1(goal: TrajectoryGoal, n: int) -> tuple[str, str] | None:
    for i, p in enumerate(goal.points):
        if len(p.positions) != n or any(f and len(f) != n for f in (p.velocities, p.accelerations)):
            return _SIZE, (f"point {i} has {len(p.positions)} positions, {len(p.velocities)} velocities and "
                           f"{len(p.accelerations)} accelerations for {n} joints")
    return None


def _finite(goal: TrajectoryGoal) -> tuple[str, str] | None:
    for i, p in enumerate(goal.points):
        for field in ("positions", "velocities", "accelerations"):
            if not all(math.isfinite(x) for x in getattr(p, field)):
                text = f"Point {i} has a non-finite value in its {field}."
                return text, text
        if not math.isfinite(p.time_from_start_s):
            text = f"Point {i} has a non-finite time_from_start."
            return text, text
    return None


def _increasing(goal: TrajectoryGoal) -> tuple[str, str] | None:
    t = [p.time_from_start_s for p in goal.points]
    for i in range(1, len(t)):
        if not t[i] > t[i - 1]:
            return _NOT_INCREASING, f"point {i - 1} at {t[i - 1]:g} s, point {i} at {t[i]:g} s"
    return None


def _ros2(goal: TrajectoryGoal, profile: ControllerProfile, joints: tuple[str, ...]) -> str | None:
    """ros2_controllers' ``validate_trajectory_msg`` (jazzy), in its order."""
    names = goal.joint_names
    if len(names) != len(joints):
        return "Joints on incoming trajectory don't match the controller joints."
    if not goal.points:
        return "Empty trajectory received."
    for name in names:
        if name not in joints:
            return f"Incoming joint {name} doesn't match the controller's joints."
    if profile.reject_nonzero_final_velocity:
        for name, v in zip(names, goal.points[-1].velocities, strict=False):
            if abs(v) > FLOAT_EPS:
                return f"Velocity of last trajectory point of joint {name} is not zero: {v:.15f}"
    if goal.start_in_s is not None and goal.start_in_s + goal.points[-1].time_from_start_s < 0.0:
        return "Received trajectory with non-zero start time that ends in the past"
    n = len(names)
    for i, p in enumerate(goal.points):
        if i > 0 and not p.time_from_start_s > goal.points[i - 1].time_from_start_s:
            return (f"Time between points {i - 1} and {i} is not strictly increasing, it is "
                    f"{goal.points[i - 1].time_from_start_s:f} and {p.time_from_start_s:f} respectively")
        for field, allow_empty in (("positions", False), ("velocities", True), ("accelerations", True)):
            values = getattr(p, field)
            if (values or not allow_empty) and len(values) != n:
                return f"Mismatch between joint_names size ({n}) and {field} ({len(values)}) at point #{i}."
        if p.effort:
            return "Trajectories with effort fields are only supported for controllers using the 'effort' " \
                   "command interface."
    return None


def check_goal(goal: TrajectoryGoal, profile: ControllerProfile,
               joints: tuple[str, ...] = CONTROLLER_JOINTS) -> Rejection | None:
    """Why the controller with ``profile`` and ``joints`` refuses ``goal`` before looking at the time, or None.

    ROS 2 rejections carry INVALID_GOAL only for reports: the ROS 2 binding rejects at ``send_goal`` without one.
    """
    if profile.validation == "ros2":
        why = _ros2(goal, profile, joints)
        if why is None:
            bad = _finite(goal)
            why = None if bad is None else bad[1]
        return None if why is None else Rejection(ErrorCode.INVALID_GOAL, "", why)
    names = goal.joint_names
    if len(names) != len(joints) or sorted(names) != sorted(joints):
        return Rejection(ErrorCode.INVALID_JOINTS, "",
                         f"{_JOINTS} (got {', '.join(names) or 'none'}; expected {', '.join(joints)})")
    found = _increasing(goal) or _sizes_ros1(goal, len(joints)) or _finite(goal)
    if found is not None:
        text, detail = found
        return Rejection(ErrorCode.INVALID_GOAL, text, text if detail == text else f"{text} ({detail})")
    return None
