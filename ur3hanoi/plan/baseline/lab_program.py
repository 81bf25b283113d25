"""The lab's own program on the same moves: the baseline a plan's speed is judged against.

The course's starter program (``tests/support/lab2_exec_starter.py``; its waits are described in the course's ROS
interface notes) sends one ``movej`` per waypoint at ``v = a = 4``: home, then per move above(src), on(src),
above(src), above(dst), on(dst), above(dst), and home again. The controller runs each as its synchronised
trapezoid (:func:`ur3hanoi.robot.movej.plan_movej`, capped at the datasheet speeds and the 4 / 8 rad/s^2 caps of the
station's limits). Around the motion the program waits: ``move_arm`` publishes, sleeps one 20 Hz loop period, then
polls every period until the arm is at the goal and sleeps once more; ``gripper()`` re-sends the current pose with
the suction changed (at the goal at once: one period); it sleeps 1.0 s after suction on and 0.5 s after suction off.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from ur3hanoi.hanoi import Move
from ur3hanoi.plan.motion.waypoints import build_waypoints
from ur3hanoi.robot.movej import plan_movej
from ur3hanoi.station.calibration import Station

LAB_V = LAB_A = 4.0  # the starter's movej speed [rad/s] and acceleration [rad/s^2]
LAB_LOOP_S = 0.05  # its loop period [s] (20 Hz)
LAB_GRASP_SLEEP_S = 1.0  # [s] after suction on
LAB_RELEASE_SLEEP_S = 0.5  # [s] after suction off


@dataclass(frozen=True)
class LabProgramTimes:
    """The lab program's motion time [s] (the movej durations), its whole cycle [s] (waits included), and the
    number of movej commands."""

    motion_s: float
    cycle_s: float
    n_movej: int


def lab_program_times(station: Station, moves: Sequence[Move]) -> LabProgramTimes:
    """The lab program's times for ``moves`` on ``station`` (home to home; see the module docstring)."""
    table = build_waypoints(station).table
    lim = station.limits
    home = station.q_home_array
    qs = [home]
    for m in moves:
        src, dst = table[m.from_tower, m.from_height], table[m.to_tower, m.to_height]
        qs += [src[1], src[0], src[1], dst[1], dst[0], dst[1]]
    qs.append(home)
    motion = cycle = 0.0
    for a, b in itertools.pairwise(qs):
        t = plan_movej(a, b, LAB_V, LAB_A, lim.v_max, lim.a_max).duration
        motion += t
        polls = max(1, math.ceil(t / LAB_LOOP_S - 1e-9))  # poll k at k periods: the first at or after arrival
        cycle += (polls + 1) * LAB_LOOP_S
    per_move = 2 * LAB_LOOP_S + LAB_GRASP_SLEEP_S + LAB_RELEASE_SLEEP_S  # two gripper() calls and the sleeps
    return LabProgramTimes(motion, cycle + per_move * len(moves), len(qs) - 1)
