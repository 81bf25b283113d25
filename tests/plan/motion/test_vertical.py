"""Vertical legs (plan.motion.vertical): the path follows the line, its derivatives, its limits, braking speed."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.plan import KinematicLimits, PlanConfig, build_waypoints, tcp_positions_world, to_rest
from ur3hanoi.plan.motion.vertical import PathLimits, braking_speed
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, contact_point_world

SLOTS = [(0, 0), (1, 2), (2, 1)]


@pytest.mark.parametrize("slot", SLOTS)
def test_path_follows_the_vertical_line(shipped_station: Station, slot: tuple[int, int]) -> None:
    """Nodes and the spline between them put the suction point on the line, s below the above pose."""
    st_ = shipped_station
    wp = build_waypoints(st_)
    vp = wp.vertical[slot[0]][slot[1]]
    np.testing.assert_array_equal(vp.q[0], wp.table[slot[0], slot[1], ABOVE])
    np.testing.assert_array_equal(vp.q[-1], wp.table[slot[0], slot[1], ON])
    s = np.linspace(0.0, vp.length_m, 97)  # mostly between nodes
    p = tcp_positions_world(st_, vp.evaluate_many(s)[0])
    contact = contact_point_world(st_, *slot)
    np.testing.assert_allclose(p[:, :2], np.broadcast_to(contact[:2], p[:, :2].shape), rtol=0, atol=1e-8)
    np.testing.assert_allclose(p[:, 2], contact[2] + vp.length_m - s, rtol=0, atol=1e-8)


def test_path_derivatives_match_finite_differences(lab_sim: Station) -> None:
    vp = build_waypoints(lab_sim).vertical[1][1]
    h = 1e-5
    for s in np.linspace(0.002, vp.length_m - 0.002, 7):
        q_m, dq_m, _, _ = vp.evaluate(s - h)
        q_p, dq_p, _, _ = vp.evaluate(s + h)
        _, dq, ddq, _ = vp.evaluate(s)
        np.testing.assert_allclose((q_p - q_m) / (2 * h), dq, rtol=0, atol=1e-6)
        np.testing.assert_allclose((dq_p - dq_m) / (2 * h), ddq, rtol=0, atol=0.05 * np.max(np.abs(ddq)) + 1e-3)


def test_path_limits_keep_joint_velocities_within_limits(lab_real: Station) -> None:
    lim = PlanConfig().limits(lab_real)
    for row in build_waypoints(lab_real).vertical:
        for vp in row:
            pl = PathLimits.for_path(vp, lim)
            assert pl.v > 0 and pl.a > 0 and pl.j > 0
            assert np.all(np.max(np.abs(vp.dq), axis=0) * pl.v <= lim.v_max)


@settings(max_examples=30, deadline=None)
@given(dist=st.floats(0.005, 0.2), a=st.floats(0.1, 5.0), j=st.floats(0.5, 50.0))
def test_braking_speed_stops_just_within_the_distance(dist: float, a: float, j: float) -> None:
    """A jerk-limited stop from the braking speed ends within ``dist``; from 2 % faster it does not."""
    lim = KinematicLimits(v_max=np.array([1e3]), a_max=np.array([a]), j_max=np.array([j]))

    def stopping_distance(v: float) -> float:
        sol = to_rest([0.0], [v], [0.0], lim)
        assert sol.trajectory is not None, sol.reason
        return float(sol.trajectory.at_time(sol.trajectory.duration)[0][0])

    v = braking_speed(dist, a, j)
    assert stopping_distance(v) == pytest.approx(dist, rel=1e-9)
    assert stopping_distance(1.02 * v) > dist
