"""Errors of the ROS bridge. All derive from :class:`ur3hanoi.errors.Ur3HanoiError` (one line, exit code 2).

A suction fault seen through ``ur3/gripper_input`` is the project's :class:`ur3hanoi.errors.SuctionFaultError`
(exit code 3), as in ``ur3hanoi solve``.
"""

from __future__ import annotations

from ur3hanoi.errors import Ur3HanoiError


class RosError(Ur3HanoiError):
    """ROS is missing, no master answers, a node did not answer in time, or a message does not match."""


class RosUnavailableError(RosError):
    """Debian's ROS 1 packages (roscore, rospy, genpy, std_msgs) are not installed."""


class CommandError(RosError):
    """A ``ur3/command`` message the station refuses (wrong length, not finite, outside the joint limits)."""
