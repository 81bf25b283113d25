"""Errors of the ROS 1 binding. :class:`~ur3hanoi.interface.errors.RosError` (and the station's
:class:`~ur3hanoi.interface.errors.CommandError`) are the transport-neutral ones of :mod:`ur3hanoi.interface.errors`.
"""

from __future__ import annotations

from ur3hanoi.interface.errors import RosError


class RosUnavailableError(RosError):
    """Debian's ROS 1 packages (roscore, rospy, genpy, std_msgs) are not installed."""
