"""The checks before a UR driver's controller accepts a goal: ROS 1's coded rejections with the controller's texts,
ROS 2's reasons."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ErrorCode
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal, TrajectoryPoint, check_goal
from ur3hanoi.interface.urdriver.profile import ROS1_SCALED, ROS2_SCALED

Z = (0.0,) * 6


def goal(*times: float, names: tuple[str, ...] = CONTROLLER_JOINTS, **point: tuple[float, ...]) -> TrajectoryGoal:
    fields = {"positions": Z, "velocities": Z, "accelerations": Z, **point}
    return TrajectoryGoal(names, tuple(TrajectoryPoint(**fields, time_from_start_s=t) for t in times))


def test_a_good_goal_in_any_joint_order_passes():
    assert check_goal(goal(0.0, 1.0, names=tuple(reversed(CONTROLLER_JOINTS))), ROS1_SCALED) is None
    assert check_goal(goal(0.0, 1.0), ROS2_SCALED) is None


@pytest.mark.parametrize("names", [CONTROLLER_JOINTS[:5], (*CONTROLLER_JOINTS[:5], "gripper_joint"),
                                   (*CONTROLLER_JOINTS, "extra_joint"), ()])
def test_ros1_wrong_joints_are_invalid_joints_without_an_error_string(names):
    r = check_goal(goal(1.0, names=names), ROS1_SCALED)
    assert r is not None and r.code == ErrorCode.INVALID_JOINTS and r.error_string == ""
    assert "don't match the controller joints" in r.reason


def test_ros1_times_not_increasing_is_invalid_goal_with_the_controllers_text():
    r = check_goal(goal(6.0, 3.0), ROS1_SCALED)  # the UR driver's own integration test's "illegal goal"
    assert r is not None and r.code == ErrorCode.INVALID_GOAL
    assert r.error_string == "Trajectory message contains waypoints that are not strictly increasing in time."
    assert "point 0 at 6 s, point 1 at 3 s" in r.reason
    assert check_goal(goal(1.0, 1.0), ROS1_SCALED) is not None


@pytest.mark.parametrize("field", ["positions", "velocities", "accelerations"])
def test_ros1_mismatched_lengths_are_invalid_goal(field):
    r = check_goal(goal(1.0, 2.0, **{field: (0.0,) * 5}), ROS1_SCALED)
    assert r is not None and r.code == ErrorCode.INVALID_GOAL
    assert r.error_string == "Size mismatch in trajectory point position, velocity or acceleration data."


def test_ros1_absent_fields_are_fine_and_an_empty_trajectory_is_accepted():
    assert check_goal(goal(1.0, velocities=(), accelerations=()), ROS1_SCALED) is None
    assert check_goal(TrajectoryGoal(CONTROLLER_JOINTS, ()), ROS1_SCALED) is None


def test_non_finite_values_are_refused():
    bad = goal(1.0, positions=(math.nan, *Z[1:]))
    r = check_goal(bad, ROS1_SCALED)
    assert r is not None and r.code == ErrorCode.INVALID_GOAL and "non-finite" in r.error_string
    assert check_goal(bad, ROS2_SCALED) is not None


def test_ros2_reasons():
    cases = {
        "don't match the controller joints": goal(1.0, names=CONTROLLER_JOINTS[:5]),
        "Empty trajectory received.": TrajectoryGoal(CONTROLLER_JOINTS, ()),
        "doesn't match the controller's joints": goal(1.0, names=(*CONTROLLER_JOINTS[:5], "x")),
        "is not zero": goal(1.0, velocities=(0.1, *Z[1:])),
        "not strictly increasing": goal(2.0, 1.0),
        "Mismatch between joint_names size (6) and accelerations (5)": goal(1.0, accelerations=(0.0,) * 5),
        "ends in the past": replace(goal(1.0), start_in_s=-5.0),
    }
    for text, g in cases.items():
        r = check_goal(g, ROS2_SCALED)
        assert r is not None and text in r.reason, (text, r)
    # Humble's controller accepts a moving last point (a deprecation warning only).
    assert check_goal(goal(1.0, velocities=(0.1, *Z[1:])), replace(ROS2_SCALED,
                                                                     reject_nonzero_final_velocity=False)) is None
