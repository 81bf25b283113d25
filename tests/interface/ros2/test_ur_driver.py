"""ur3hanoi.interface.ros2.ur_driver on the CPU clock, with message objects from an independent implementation
(rosbags' classes from the vendored texts, tests/support/rosidl_oracle.py): the names and controller rules per
distribution, a goal and ``io_states`` into the neutral types, joint states by name, the kept ``IOStates`` message."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from tests.support.rosidl_oracle import typestore
from ur3hanoi.interface.ros2.rclpy_build import WHEELS, driver_packages
from ur3hanoi.interface.ros2.ur_driver import (
    duration_s,
    goal_from_msg,
    io_from_msg,
    joint_positions,
    names_for,
    preempted_text,
    profile_for,
    set_duration,
)
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS
from ur3hanoi.interface.urdriver.goal import check_goal
from ur3hanoi.interface.urdriver.io import IoStates, IoStatesMessage


def _types() -> dict[str, Any]:
    texts = {}
    for package in driver_packages(WHEELS["jazzy"]):
        for rel, text in package.texts.items():
            kind, file = rel.split("/")
            texts[f"{package.name}/{kind}/{file.rsplit('.', 1)[0]}"] = text
    return typestore(texts).types  # type: ignore[no-any-return]


T = _types()


def _goal(names: list[str], points: list[tuple[list[float], list[float], float]], stamp_s: float = 0.0) -> Any:
    Duration, Time = T["builtin_interfaces/msg/Duration"], T["builtin_interfaces/msg/Time"]
    Header, Point = T["std_msgs/msg/Header"], T["trajectory_msgs/msg/JointTrajectoryPoint"]
    empty = np.zeros(0)
    pts = [Point(positions=np.array(p), velocities=np.array(v), accelerations=empty, effort=empty,
                 time_from_start=set_duration(Duration(sec=0, nanosec=0), t)) for p, v, t in points]
    traj = T["trajectory_msgs/msg/JointTrajectory"](
        header=Header(stamp=set_duration(Time(sec=0, nanosec=0), stamp_s), frame_id=""), joint_names=names,
        points=pts)
    multi = T["trajectory_msgs/msg/MultiDOFJointTrajectory"](header=Header(stamp=Time(sec=0, nanosec=0), frame_id=""),
                                                            joint_names=[], points=[])
    tol = T["control_msgs/msg/JointTolerance"]
    return T["control_msgs/action/FollowJointTrajectory_Goal"](
        trajectory=traj, multi_dof_trajectory=multi, path_tolerance=[tol(name="elbow_joint", position=0.3,
                                                                          velocity=0.0, acceleration=0.0)],
        component_path_tolerance=[], goal_tolerance=[], component_goal_tolerance=[],
        goal_time_tolerance=Duration(sec=1, nanosec=500_000_000))


def test_names_per_distribution() -> None:
    assert names_for("jazzy").follow_joint_trajectory == "/scaled_joint_trajectory_controller/follow_joint_trajectory"
    assert names_for("humble") == names_for("kilted") == names_for("jazzy")
    assert names_for("lyrical").follow_joint_trajectory == "/joint_trajectory_controller/follow_joint_trajectory"
    assert {n.speed_scaling for n in map(names_for, ("humble", "lyrical"))} == {
        "/speed_scaling_state_broadcaster/speed_scaling"}


def test_humble_accepts_a_moving_last_point_jazzy_does_not() -> None:
    goal = goal_from_msg(_goal(list(CONTROLLER_JOINTS), [([0.1] * 6, [0.2] * 6, 1.0)]), 0.0)
    assert check_goal(goal, profile_for("humble")) is None
    rejection = check_goal(goal, profile_for("jazzy"))
    assert rejection is not None and "Velocity of last trajectory point" in rejection.reason
    assert preempted_text("humble") != preempted_text("jazzy") == preempted_text("kilted")


def test_a_goal_keeps_its_fields_and_its_stamp_becomes_a_start_time() -> None:
    names = sorted(CONTROLLER_JOINTS)
    goal = goal_from_msg(_goal(names, [([0.1] * 6, [], 0.5), ([0.2] * 6, [0.0] * 6, 1.25)], stamp_s=100.0), 99.0)
    assert goal.joint_names == tuple(names)
    assert [p.time_from_start_s for p in goal.points] == [0.5, 1.25]
    assert goal.points[0].velocities == () and goal.points[1].velocities == (0.0,) * 6
    assert goal.start_in_s == pytest.approx(1.0, abs=1e-9) and goal.goal_time_tolerance_s == 1.5
    assert goal.path_tolerance[0].name == "elbow_joint" and goal.path_tolerance[0].position == 0.3
    assert goal_from_msg(_goal(names, [([0.1] * 6, [], 0.5)]), 99.0).start_in_s is None  # zero stamp: now


def test_durations_are_whole_nanoseconds() -> None:
    d = set_duration(T["builtin_interfaces/msg/Duration"](sec=0, nanosec=0), 2.0000000004)
    assert (d.sec, d.nanosec) == (2, 0) and duration_s(d) == 2.0
    d = set_duration(d, 0.123456789)
    assert (d.sec, d.nanosec) == (0, 123456789)


def test_joint_states_are_read_by_name() -> None:
    names = sorted(CONTROLLER_JOINTS)
    q = joint_positions(names, [float(i) for i in range(6)])
    assert q is not None
    assert q.tolist() == [float(names.index(j)) for j in CONTROLLER_JOINTS]
    assert joint_positions(names[:5], [0.0] * 5) is None and joint_positions(names, [0.0] * 5) is None


def test_io_states_both_ways() -> None:
    Digital, Analog = T["ur_msgs/msg/Digital"], T["ur_msgs/msg/Analog"]

    class Msgs:  # the module ``ur_msgs.msg`` as the binding passes it
        IOStates, Digital, Analog = T["ur_msgs/msg/IOStates"], T["ur_msgs/msg/Digital"], T["ur_msgs/msg/Analog"]

    io = IoStates(tuple(i == 0 for i in range(18)), tuple(i == 1 for i in range(18)), ((1, 1.05), (0, 0.004)),
                  ((1, 0.0), (1, 0.5)))
    kept = IoStatesMessage(Msgs)
    msg = kept.update(io)
    assert [d.pin for d in msg.digital_in_states] == list(range(18)) and msg.flag_states == []
    assert io_from_msg(msg) == io
    later = IoStates(io.digital_in, tuple(i in (1, 17) for i in range(18)), ((1, 0.2), (0, 0.0)), io.analog_out)
    assert kept.update(later) is msg and io_from_msg(msg) == later
    partial = Msgs.IOStates(digital_in_states=[Digital(pin=3, state=True)], digital_out_states=[], flag_states=[],
                            analog_in_states=[Analog(pin=1, domain=0, state=0.01)], analog_out_states=[])
    sparse = io_from_msg(partial)
    assert sparse.digital_in[3] and sum(sparse.digital_in) == 1 and sparse.analog_in[1] == (0, pytest.approx(0.01))
