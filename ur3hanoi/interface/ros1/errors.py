"""Errors of the ROS 1 binding: ROS 1 itself failed (no master answers, roscore does not start, rospy is missing)."""

from __future__ import annotations

from ur3hanoi.errors import DriverError


class RosError(DriverError):
    """No ROS master answers (or something else holds its port), roscore did not start, a node did not answer in
    time, or a message does not match the course's."""


class RosUnavailableError(RosError):
    """Debian's ROS 1 packages (roscore, rospy, genpy, std_msgs) are not installed."""
