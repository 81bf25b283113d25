"""Errors of a server (:mod:`ur3hanoi.interface.common.station`), whatever the middleware.

A client's errors are :class:`ur3hanoi.errors.DriverError` (the driver cannot be reached, stopped, answers
wrongly) and its middleware's subclasses (:class:`ur3hanoi.interface.ros1.errors.RosError`,
:class:`ur3hanoi.interface.ros2.errors.DdsError`). A suction fault seen through the gripper feedback is the
project's :class:`ur3hanoi.errors.SuctionFaultError` (exit code 3), as in ``ur3hanoi solve``.
"""

from __future__ import annotations

from ur3hanoi.errors import Ur3HanoiError


class CommandError(Ur3HanoiError):
    """A command message the server refuses (wrong length, not finite, outside the joint limits, too long)."""
