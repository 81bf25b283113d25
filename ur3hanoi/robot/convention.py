"""Joint conventions: the UR controller's (ur3hanoi's own) and the ROS 2 course bridge's, and the one conversion.

Everything in ur3hanoi (tables, calibrations, IK, plans, the simulator) is in the **controller** convention: the
joint values the teach pendant shows, whose zeros are the DH zeros. The UMD ENME480 UR3e bridge
(``../shared/lab/ros2-interface.md``) lets student programs work in its own **course** convention: it sends a
``destination`` to the controller with ``[0] += pi/2`` and ``[3] -= pi/2``, and publishes positions back with the
inverse offsets. So

    q_controller = q_course + COURSE_OFFSET,   COURSE_OFFSET = (pi/2, 0, 0, -pi/2, 0, 0) [rad].

:func:`to_controller` and :func:`from_controller` are that conversion and nothing else; the ROS 2 station and
client convert at the topic, and ``ur3hanoi tables --convention course`` writes a table students can send as is
(its header line says so).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from ur3hanoi.arrays import FloatArray

Convention = Literal["controller", "course"]
CONVENTIONS: tuple[str, ...] = ("controller", "course")
COURSE_OFFSET: tuple[float, ...] = (math.pi / 2, 0.0, 0.0, -math.pi / 2, 0.0, 0.0)
"""q_controller - q_course [rad] (the course bridge's offsets on joints 1 and 4)."""

DESCRIPTION: dict[str, str] = {
    "controller": "controller/DH convention",
    "course": "ROS 2 course bridge convention (controller = course + [pi/2, 0, 0, -pi/2, 0, 0])",
}


def _offset(convention: str) -> FloatArray:
    if convention == "controller":
        return np.zeros(6)
    if convention == "course":
        return np.array(COURSE_OFFSET)
    raise ValueError(f"joint convention {convention!r} is unknown: expected one of {', '.join(CONVENTIONS)}")


def to_controller(q: FloatArray, convention: str) -> FloatArray:
    """Joint values [rad] (..., 6) given in ``convention`` -> the controller convention."""
    return np.asarray(q, dtype=float) + _offset(convention)


def from_controller(q: FloatArray, convention: str) -> FloatArray:
    """Controller-convention joint values [rad] (..., 6) -> ``convention``."""
    return np.asarray(q, dtype=float) - _offset(convention)


__all__ = ["CONVENTIONS", "COURSE_OFFSET", "DESCRIPTION", "Convention", "from_controller", "to_controller"]
