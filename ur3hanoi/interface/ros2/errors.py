"""Errors of the ROS 2 binding: Cyclone DDS failed (the participant cannot start on the network asked for, the domain
is invalid)."""

from __future__ import annotations

from ur3hanoi.errors import DriverError


class DdsError(DriverError):
    """The DDS participant cannot start (network, domain), or the peers do not appear."""


class RclpyUnavailableError(DriverError):
    """``rclpy`` (or the UR driver's message packages) cannot be imported, or the ``ros2-env`` environment that would
    bring them cannot be built."""
