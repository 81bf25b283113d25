"""Connections and the per-station cache (ur3hanoi.plan.route.connections): keyed by content, pure, chained."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.plan import PlanConfig
from ur3hanoi.plan.route.connections import StationPlanner, station_planner
from ur3hanoi.plan.types import DEFAULT_VIA_ACCELS, DEFAULT_VIA_SPEEDS
from ur3hanoi.station.calibration import Station, load_station

HOPS = [(None, (0, 2)), ((0, 2), (2, 0)), ((2, 0), (1, 0)), ((1, 0), None)]


def _planner(station: Station) -> StationPlanner:
    return StationPlanner(station, PlanConfig().limits(station), 0.002, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS)


def test_cache_is_keyed_by_the_calibration_content(lab_real: Station) -> None:
    lim = PlanConfig().limits(lab_real)
    a = station_planner(lab_real, lim, 0.002, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS)
    again = load_station("lab_real")  # a new object with the same content
    assert station_planner(again, lim, 0.002, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS) is a
    moved = dataclasses.replace(lab_real, approach=lab_real.approach + 0.001)
    b = station_planner(moved, lim, 0.002, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS)
    assert b is not a and b.station.approach == moved.approach
    slower = PlanConfig(speed=0.5).limits(lab_real)
    assert station_planner(lab_real, slower, 0.002, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS) is not a


def test_connections_do_not_depend_on_what_was_planned_before(lab_sim: Station) -> None:
    first, second = _planner(lab_sim), _planner(lab_sim)
    a = {h: first.connect(*h) for h in HOPS}
    b = {h: second.connect(*h) for h in reversed(HOPS)}
    for h in HOPS:
        assert a[h].cells == b[h].cells and a[h].duration == b[h].duration


def test_a_connection_is_chained_from_dwell_to_dwell(lab_sim: Station) -> None:
    p = _planner(lab_sim)
    c = p.connect((0, 2), (2, 0))
    assert c.exit is not None and c.entry is not None
    np.testing.assert_array_equal(c.exit.states[-1][1], c.across_states[0][1])
    np.testing.assert_array_equal(c.entry.states[0][2], c.across_states[-1][2])
    for traj, s0, s1 in zip(c.across, c.across_states, c.across_states[1:], strict=False):
        for got, want in zip(traj.at_time(traj.duration), s1, strict=True):
            np.testing.assert_allclose(got, want, atol=1e-9)
        for got, want in zip(traj.at_time(0.0), s0, strict=True):
            np.testing.assert_allclose(got, want, atol=1e-9)
    # Pass-through: moving at both above poses.
    assert np.linalg.norm(c.across_states[0][1]) > 0.1 and np.linalg.norm(c.across_states[-1][1]) > 0.1
    assert c.duration == pytest.approx(c.exit.duration + sum(t.duration for t in c.across) + c.entry.duration,
                                       rel=1e-12)
