"""Approach/retreat legs (plan.motion.legs): on the vertical line at 1 kHz, within the limits, chained, bounded."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.plan import PlanConfig, build_waypoints, tcp_positions_world
from ur3hanoi.plan.motion.corridor import CONTACT_OVERSHOOT_M, Leg
from ur3hanoi.plan.motion.legs import SlotLegs
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.route.connections import station_planner
from ur3hanoi.plan.types import DEFAULT_VIA_ACCELS, DEFAULT_VIA_SPEEDS, KinematicLimits
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import contact_point_world

TOL = 0.002
CELLS = [(0, 1), (1, 1), (1, 2)]  # rest, and two cells feasible on every tested slot (lab_real uses (1, 2))


def _slot_legs(station: Station, slot: tuple[int, int], speed: float = 1.0) -> tuple[SlotLegs, KinematicLimits]:
    lim = PlanConfig(speed=speed).limits(station)
    rk = OfflineRuckig(lim.v_max, lim.a_max, lim.j_max)
    return SlotLegs(station, build_waypoints(station), slot, rk, lim, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS,
                    TOL), lim


def _at_1khz(leg: Leg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, qd, qdd of the chained leg every millisecond, from Ruckig's own at_time (independent of the planner's
    vectorised evaluation)."""
    rows = []
    for traj in leg.trajectories:
        for t in np.append(np.arange(0.0, traj.duration, 1e-3), traj.duration):
            rows.append(traj.at_time(float(t)))
    arr = np.array(rows, dtype=float)
    return arr[:, 0], arr[:, 1], arr[:, 2]


@pytest.mark.parametrize("slot", [(0, 0), (1, 2), (2, 1)])
def test_legs_hold_the_line_and_the_limits_at_1khz(shipped_station: Station, slot: tuple[int, int]) -> None:
    st = shipped_station
    legs, lim = _slot_legs(st, slot)
    contact = contact_point_world(st, *slot)
    for cell in CELLS:
        pair = legs.legs(cell)
        assert pair is not None, cell
        for leg, down in zip(pair, (True, False), strict=True):
            assert leg.path is None  # the lab slots never need the exact path-following fallback
            q, qd, qdd = _at_1khz(leg)
            p = tcp_positions_world(st, q)
            dev = np.hypot(p[:, 0] - contact[0], p[:, 1] - contact[1])
            assert np.max(dev) <= TOL and np.max(dev) == pytest.approx(leg.deviation_m, abs=1e-9)
            assert np.min(p[:, 2]) >= contact[2] - CONTACT_OVERSHOOT_M
            assert np.all(np.abs(qd) <= lim.v_max * (1 + 1e-6)) and np.all(np.abs(qdd) <= lim.a_max * (1 + 1e-6))
            # Chained: each segment ends in the next one's start state; the leg joins the cell's above state and
            # rest on the contact pose.
            for traj, s0, s1 in zip(leg.trajectories, leg.states, leg.states[1:], strict=False):
                for got, want in zip(traj.at_time(0.0), s0, strict=True):
                    np.testing.assert_allclose(got, want, atol=1e-9)
                for got, want in zip(traj.at_time(traj.duration), s1, strict=True):
                    np.testing.assert_allclose(got, want, atol=1e-9)
            above = legs.above_state(cell, down)
            ends = (leg.states[0], leg.states[-1]) if down else (leg.states[-1], leg.states[0])
            np.testing.assert_array_equal(ends[0][1], above[1])
            np.testing.assert_array_equal(ends[1][1], 0.0)
            assert leg.duration >= legs.lower_bound(cell) - 1e-9


def test_a_single_joint_segment_leaves_the_line(lab_real: Station) -> None:
    """The check the legs pass is live: the straight joint-space descent of a lab_real slot is over 4 mm off."""
    legs, _ = _slot_legs(lab_real, (2, 1))
    single = legs.ruckig.solve(*legs.above_state(legs.rest_cell, True), *legs.on).trajectory
    assert single is not None
    dev, _, _ = legs.corridor.measure([single])
    assert dev > 0.004


def test_legs_are_independent_of_the_build_order(lab_sim: Station) -> None:
    a, _ = _slot_legs(lab_sim, (1, 1))
    b, _ = _slot_legs(lab_sim, (1, 1))
    order = [(8, 2), (4, 3), (0, 1), (6, 4)]
    got_a = {c: a.legs(c) for c in order}
    got_b = {c: b.legs(c) for c in reversed(order)}
    for c in order:
        la, lb = got_a[c], got_b[c]
        assert (la is None) == (lb is None)
        if la is not None and lb is not None:
            assert [leg.duration for leg in la] == [leg.duration for leg in lb]
            for x, y in zip(la[0].states, lb[0].states, strict=True):
                np.testing.assert_array_equal(x[1], y[1])


def test_near_singular_slot_gets_interior_point_legs(lab_real: Station) -> None:
    """Tower 3 of a grid pulled close to the base: the joint path curves so much near the contact pose that one or
    two interior points dip into the block; many points along the path timing keep the line, and beat the exact
    path-following leg."""
    close = dataclasses.replace(lab_real, tower_origins=tuple((0.22, y, z) for _, y, z in lab_real.tower_origins))
    legs, lim = _slot_legs(close, (2, 0))
    down, up = legs.legs(legs.rest_cell) or (None, None)
    assert down is not None and up is not None
    assert down.path is None and len(down.trajectories) > 3
    assert down.deviation_m <= TOL and up.deviation_m <= TOL
    planner = station_planner(close, lim, TOL, DEFAULT_VIA_SPEEDS, DEFAULT_VIA_ACCELS)
    assert down.duration < planner.exact_vertical_leg((2, 0))
