"""ur3hanoi.plan.table_plan: the lab program's joint moves through a given table's entries, under the UR3 limits."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support.table_helpers import shifted_table
from ur3hanoi.errors import PlanError, TableError
from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import (
    SUCTION_PHASES,
    Phase,
    PlanConfig,
    entries_visited,
    entry_label,
    missing_entries,
    plan_table,
    to_pose,
)
from ur3hanoi.robot.model import JointLimits
from ur3hanoi.station.calibration import Station

LAB_ORDER = [Phase.TRANSIT, Phase.DESCEND_PICK, Phase.GRASP_DWELL, Phase.LIFT, Phase.CARRY, Phase.DESCEND_PLACE,
             Phase.RELEASE_DWELL, Phase.RETREAT]
RTOL = 1e-6  # relative slack of the limit checks, as the planner's own


def test_the_plan_visits_the_table_entries_in_the_lab_programs_order(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)
    plan = plan_table(lab_sim, q, 0, 2, 3)
    tr = plan.trajectory
    moves = solve_hanoi(3, 0, 2)
    assert list(plan.moves) == moves and not plan.violations
    for mi, m in enumerate(moves):
        phases = [Phase(p) for p in dict.fromkeys(tr.phase[tr.move_index == mi].tolist())]
        assert phases == LAB_ORDER
        # At rest on the table's own contact poses while the suction switches.
        grasp = (tr.move_index == mi) & (tr.phase == Phase.GRASP_DWELL)
        release = (tr.move_index == mi) & (tr.phase == Phase.RELEASE_DWELL)
        np.testing.assert_array_equal(tr.q[grasp], np.tile(q[m.from_tower, m.from_height, 0], (grasp.sum(), 1)))
        np.testing.assert_array_equal(tr.q[release], np.tile(q[m.to_tower, m.to_height, 0], (release.sum(), 1)))
    np.testing.assert_allclose(tr.q[0], lab_sim.q_home_array, atol=1e-12)
    np.testing.assert_allclose(tr.q[-1], lab_sim.q_home_array, atol=1e-12)
    np.testing.assert_array_equal(tr.suction, np.isin(tr.phase, [int(p) for p in SUCTION_PHASES]))
    assert plan.duration_s == plan.stop_and_go_duration_s  # every waypoint is a stop


def test_every_move_is_rest_to_rest_between_two_entries(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)
    plan = plan_table(lab_sim, q, 0, 2, 3)
    rows = {q[t, h, k].tobytes() for t in range(3) for h in range(3) for k in (0, 1)}
    rows.add(lab_sim.q_home_array.tobytes())
    for seg in plan.segments:
        assert seg.q_start.tobytes() in rows and seg.q_end.tobytes() in rows, seg.target
        if seg.trajectory is None:
            continue
        for t, q_expected in ((0.0, seg.q_start), (seg.duration, seg.q_end)):
            pos, vel, acc = seg.trajectory.at_time(t)
            np.testing.assert_allclose(pos, q_expected, atol=1e-9)
            np.testing.assert_allclose(vel, 0.0, atol=1e-9)
            np.testing.assert_allclose(acc, 0.0, atol=1e-9)


def test_segment_targets_name_the_entries_1_based_with_the_file_index(lab_sim: Station) -> None:
    plan = plan_table(lab_sim, shifted_table(lab_sim), 0, 2, 1)
    targets = [s.target for s in plan.segments if s.move_index == 0]
    above, on = "table entry tower 1 height 1 above (Q[0][0][1])", "table entry tower 1 height 1 on (Q[0][0][0])"
    assert targets[:3] == [above, on, on]  # transit, descend, grasp dwell
    assert "table entry tower 3 height 1 on (Q[2][0][0])" in targets
    assert entry_label(2, 0, 1) == "tower 3 height 1 above (Q[2][0][1])"


@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), speed=st.sampled_from([0.2, 0.5, 1.0]),
       pair=st.sampled_from([(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]))
def test_hand_recorded_tables_stay_within_the_limits_and_take_the_time_optimal_moves(
        lab_sim: Station, seed: int, speed: float, pair: tuple[int, int]) -> None:
    # A hand table: every entry scattered by up to 0.05 rad per joint (several mm at the cup).
    rng = np.random.default_rng(seed)
    q = shifted_table(lab_sim) + rng.uniform(-0.05, 0.05, size=(3, 3, 2, 6))
    cfg = PlanConfig(speed=speed)
    plan = plan_table(lab_sim, q, pair[0], pair[1], 3, cfg)
    tr, lim = plan.trajectory, cfg.limits(lab_sim)
    assert not plan.violations
    for arr, bound in ((tr.qd, lim.v_max), (tr.qdd, lim.a_max), (tr.qddd, lim.j_max)):
        assert np.all(np.abs(arr) <= bound * (1 + RTOL))
    # Each move takes exactly the time-optimal rest-to-rest motion between its two poses (plus the dwells).
    expected = 0.0
    for seg in plan.segments:
        if seg.trajectory is None:
            expected += cfg.dwell_s
        else:
            sol = to_pose(seg.q_start, np.zeros(6), np.zeros(6), seg.q_end, lim)
            assert sol.trajectory is not None
            expected += sol.trajectory.duration
    assert plan.duration_s == pytest.approx(expected, rel=1e-12)
    assert tr.t[-1] >= plan.duration_s > tr.t[-1] - 1.0 / cfg.rate_hz


def test_half_speed_stretches_every_move(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)
    fast = plan_table(lab_sim, q, 0, 2, 2, PlanConfig(speed=1.0))
    slow = plan_table(lab_sim, q, 0, 2, 2, PlanConfig(speed=0.5))
    # Halving velocity, acceleration and jerk stretches a time-optimal move by 2^(1/3) (jerk-bound) to 2
    # (velocity-bound).
    pairs = [(f, s) for f, s in zip(fast.segments, slow.segments, strict=True) if f.trajectory is not None]
    assert pairs
    for f, s in pairs:
        assert 2 ** (1 / 3) - 1e-9 <= s.duration / f.duration <= 2 + 1e-9, f.target


def test_entries_visited_by_one_block() -> None:
    moves = solve_hanoi(1, 0, 2)
    assert entries_visited(moves) == [(0, 0, 1), (0, 0, 0), (2, 0, 1), (2, 0, 0)]


def test_a_missing_entry_the_solve_needs_is_named(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)
    q[0, 2, 1] = np.nan
    q[1, 0, 0, 3] = np.nan
    assert missing_entries(q, solve_hanoi(3, 0, 2)) == [(0, 2, 1), (1, 0, 0)]
    with pytest.raises(TableError) as info:
        plan_table(lab_sim, q, 0, 2, 3, where="lab2_data.yaml:sim_pos")
    msg = str(info.value)
    assert msg.startswith("lab2_data.yaml:sim_pos: 2 table entries the solve needs are missing: ")
    assert "tower 1 height 3 above (Q[0][2][1])" in msg and "tower 2 height 1 on (Q[1][0][0])" in msg
    assert "\n" not in msg


def test_missing_entries_the_solve_does_not_visit_are_fine(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)
    q[1] = np.nan  # tower 2 is never visited by one block from tower 1 to tower 3
    q[0, 1:] = np.nan
    plan = plan_table(lab_sim, q, 0, 2, 1)
    assert len(plan.moves) == 1 and np.all(np.isfinite(plan.trajectory.q))


def test_a_table_of_another_grid_is_refused(lab_sim: Station) -> None:
    q = shifted_table(lab_sim)[:, :2]
    with pytest.raises(TableError, match=r"shape \(3, 2, 2, 6\).*needs \(3, 3, 2, 6\)"):
        plan_table(lab_sim, q, 0, 2, 2)


def test_the_joint_limits_still_apply(lab_sim: Station) -> None:
    # The lab_sim table bends the elbow to ~2.2 rad at height 3: an elbow limited to 2 rad must refuse it.
    station = replace(lab_sim, limits=JointLimits.ur3(elbow_limit=2.0))
    q = shifted_table(lab_sim)
    with pytest.raises(PlanError, match=r"violates a limit: joint 3 position .* leaves \[-2\.0000, 2\.0000\]"):
        plan_table(station, q, 0, 2, 3)
    plan = plan_table(station, q, 0, 2, 3, PlanConfig(raise_on_violation=False))
    assert plan.violations and all("joint 3" in v for v in plan.violations)
    visited = [q[e][2] for e in entries_visited(plan.moves)]
    assert math.isclose(max(visited), float(np.max(plan.trajectory.q[:, 2])), abs_tol=1e-9)
