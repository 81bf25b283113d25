"""Helpers of the UR driver interface's CPU-clock tests: a station without a transport, goals, a loopback client."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ur3hanoi.interface.urdriver.client import GoalResult
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal, TrajectoryPoint
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport
from ur3hanoi.interface.urdriver.station import DriverStation, DriverStationOptions

Z = (0.0,) * 6


def station(**options: Any) -> DriverStation:
    """A driver station (lab_sim by default) whose report goes nowhere."""
    return DriverStation(DriverStationOptions(**options), lambda _s: None, lambda _s: None)


def goal(q_end: np.ndarray, duration: float, q_start: np.ndarray | None = None, fields: int = 3,
         names: tuple[str, ...] = CONTROLLER_JOINTS, **kw: Any) -> TrajectoryGoal:
    """Rest to rest from ``q_start`` (None: ``q_end``'s start is not given: one point) to ``q_end``."""
    def pt(q: np.ndarray, t: float) -> TrajectoryPoint:
        order = [CONTROLLER_JOINTS.index(n) for n in names]
        return TrajectoryPoint(tuple(float(q[i]) for i in order), Z if fields > 1 else (), Z if fields > 2 else (),
                               time_from_start_s=t)

    points = (pt(q_end, duration),) if q_start is None else (pt(q_start, 0.0), pt(q_end, duration))
    return TrajectoryGoal(names, points, **kw)


def run_until(transport: LoopbackTransport, done: Callable[[], bool], max_cycles: int,
              each: Callable[[int], None] | None = None) -> int:
    """Cycles until ``done()`` (its count); fails after ``max_cycles``."""
    for k in range(max_cycles):
        if done():
            return k
        if each is not None:
            each(k)
        transport.wait(0.0)
    raise AssertionError(f"not done within {max_cycles} cycles")


def send(transport: LoopbackTransport, g: TrajectoryGoal, max_cycles: int = 2000,
         each: Callable[[int], None] | None = None) -> tuple[GoalResult, int]:
    """Send ``g`` and run until its result: (result, cycles)."""
    h = transport.send_goal(g)
    n = run_until(transport, h.done, max_cycles, each)
    return h.result(), n
