"""Errors of a remote station and its clients, whatever the middleware. All derive from
:class:`ur3hanoi.errors.Ur3HanoiError` (one line, exit code 2).

A suction fault seen through the gripper feedback is the project's :class:`ur3hanoi.errors.SuctionFaultError`
(exit code 3), as in ``ur3hanoi solve``.
"""

from __future__ import annotations

from ur3hanoi.errors import Ur3HanoiError


class RosError(Ur3HanoiError):
    """The middleware is missing, no master/peer answers, a node did not answer in time, or a message does not
    match."""


class CommandError(RosError):
    """A command message the station refuses (wrong length, not finite, outside the joint limits, too long)."""
