"""The stop-and-go references (plan.baseline.stop_and_go): the honest baseline is joint-space rest-to-rest between
the plan's waypoints; the exact-vertical one is slower; the plan beats both."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import OfflineRuckig, PlanConfig, build_waypoints, plan_solve, plan_table
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON


def test_honest_baseline_is_rest_to_rest_between_the_waypoints(shipped_station: Station) -> None:
    """Recomputed here from the waypoint sequence home, above, on, above, above, on, above, ..., home."""
    st = shipped_station
    plan = plan_solve(st, 0, 2, 3, PlanConfig(check_collisions=False))
    wp = build_waypoints(st)
    lim = plan.limits
    assert lim is not None
    rk = OfflineRuckig(lim.v_max, lim.a_max, lim.j_max)
    seq = [wp.q_home]
    for m in solve_hanoi(3, 0, 2, st.n_towers, st.n_heights):
        for t, h in ((m.from_tower, m.from_height), (m.to_tower, m.to_height)):
            seq += [wp.table[t, h, ABOVE], wp.table[t, h, ON], wp.table[t, h, ABOVE]]
    seq.append(wp.q_home)
    z = np.zeros(6)
    motion = 0.0
    for a, b in itertools.pairwise(seq):
        traj = rk.solve(a, z, z, b, z, z).trajectory
        assert traj is not None
        motion += traj.duration
    assert plan.stop_and_go_motion_s == pytest.approx(motion, rel=1e-12)
    assert plan.stop_and_go_duration_s == pytest.approx(motion + 2 * 7 * plan.config.dwell_s, rel=1e-12)


def test_exact_vertical_is_slower_and_the_plan_beats_both(shipped_station: Station) -> None:
    plan = plan_solve(shipped_station, 0, 2, 3, PlanConfig(check_collisions=False))
    assert plan.motion_s < plan.stop_and_go_motion_s < plan.exact_vertical_stop_and_go_motion_s


def test_honest_baseline_is_the_motion_of_the_lab_program_on_the_generated_table(shipped_station: Station) -> None:
    """The baseline's motion time equals that of a real trajectory: the lab program's rest-to-rest moves through
    the generated table (:func:`plan_table`, what ``solve --table`` executes)."""
    st = shipped_station
    plan = plan_solve(st, 0, 2, 3, PlanConfig(check_collisions=False))
    table_plan = plan_table(st, build_waypoints(st).table, 0, 2, 3)
    assert table_plan.motion_s == pytest.approx(plan.stop_and_go_motion_s, abs=1e-9)
    assert plan.motion_s < table_plan.motion_s
