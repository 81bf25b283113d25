"""The ROS 2 distributions a UR robot may run, and what each means for ur3hanoi (the command line reads this module
while it builds its parser: it imports nothing else)."""

from __future__ import annotations

import os

ROS_DISTROS: dict[str, str] = {"humble": "jazzy", "jazzy": "jazzy", "kilted": "kilted", "lyrical": "kilted"}
"""A robot's ROS 2 distribution -> its FollowJointTrajectory layout and the PyPI wheels that talk to it: Humble
(control_msgs 4.x) and Jazzy (5.x) share a layout; Kilted and later (>= 6.3.0) add the feedback's ``index``."""

DEFAULT_DISTRO = "jazzy"
"""Without ``$ROS_DISTRO``: the current long-term ROS 2 release."""


def default_distro() -> str:
    """``$ROS_DISTRO`` when it names one of :data:`ROS_DISTROS` (a sourced installation sets it), else jazzy."""
    distro = os.environ.get("ROS_DISTRO", "")
    return distro if distro in ROS_DISTROS else DEFAULT_DISTRO
