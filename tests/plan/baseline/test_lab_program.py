"""The lab program baseline (plan.baseline.lab_program): its movej sequence, its waits, and its motion time."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import build_waypoints
from ur3hanoi.plan.baseline.lab_program import lab_program_times
from ur3hanoi.station.calibration import Station


def _trapezoid_s(dq: np.ndarray, v: np.ndarray, a: np.ndarray) -> float:
    """Synchronised trapezoid duration [s], written out: the slowest joint at its own caps decides."""
    t = 0.0
    for d, vi, ai in zip(np.abs(dq), v, a, strict=True):
        if d == 0.0:
            continue
        t = max(t, 2.0 * np.sqrt(d / ai) if vi * vi / ai >= d else d / vi + vi / ai)
    return t


@pytest.mark.parametrize("n", [1, 3])
def test_movej_per_waypoint_and_the_waits(shipped_station: Station, n: int) -> None:
    st = shipped_station
    moves = solve_hanoi(n, 0, 2, st.n_towers, st.n_heights)
    t = lab_program_times(st, moves)
    assert t.n_movej == 6 * len(moves) + 1  # home, 6 waypoints per move, home
    # The motion: each waypoint-to-waypoint move is the synchronised trapezoid at v = a = 4 within the caps.
    table = build_waypoints(st).table
    qs = [st.q_home_array]
    for m in moves:
        src, dst = table[m.from_tower, m.from_height], table[m.to_tower, m.to_height]
        qs += [src[1], src[0], src[1], dst[1], dst[0], dst[1]]
    qs.append(st.q_home_array)
    v = np.minimum(4.0, st.limits.v_max)
    a = np.minimum(4.0, st.limits.a_max)
    durations = [_trapezoid_s(q1 - q0, v, a) for q0, q1 in itertools.pairwise(qs)]
    assert t.motion_s == pytest.approx(sum(durations), rel=1e-9)
    # The waits: move_arm publishes, sleeps one 50 ms period, checks, sleeps, ... and leaves after the sleep that
    # follows the first check at or after arrival; per move two gripper() calls of one period and the 1.0 s + 0.5 s
    # sleeps.
    move_arm = sum(0.05 * (max(1, math.ceil(d / 0.05 - 1e-9)) + 1) for d in durations)
    assert t.cycle_s == pytest.approx(move_arm + len(moves) * (2 * 0.05 + 1.0 + 0.5), rel=1e-12)
    assert t.cycle_s - t.motion_s > len(moves) * 1.5
