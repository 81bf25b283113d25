"""Clearance of a plan's segments (ur3hanoi.plan.checks.clearance): agrees with the sample-based check, sees a block
crossed between two coarse samples, reports a clearance it cannot meet."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import (
    OfflineRuckig,
    Phase,
    PlanConfig,
    Segment,
    build_waypoints,
    check_collisions,
    plan_solve,
)
from ur3hanoi.plan.checks.clearance import check_segments
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON


def test_clean_plans_agree_with_the_sample_based_check(shipped_station: Station) -> None:
    plan = plan_solve(shipped_station, 0, 2, 3, PlanConfig(check_collisions=False))
    assert plan.limits is not None
    args = (plan.moves, plan.station, plan.n_blocks, plan.start, plan.config, plan.limits)
    assert check_segments(plan.segments, *args) == []
    assert check_collisions(plan.trajectory, *args) == []


def test_a_block_crossed_between_coarse_samples_is_found(lab_sim: Station) -> None:
    """A transit at contact height from tower 1 to tower 3 sweeps through the block resting on tower 2 (flat
    layout, the middle of the row). Coarse samples only at its two ends (0.5 Hz): the refinement must find it."""
    st = lab_sim
    wp = build_waypoints(st)
    cfg = PlanConfig(collision_rate_hz=0.5)
    lim = cfg.limits(st)
    z = np.zeros(6)
    q0, q1 = wp.table[0, 0, ON], wp.table[2, 0, ON]
    traj = OfflineRuckig(lim.v_max, lim.a_max, lim.j_max).solve(q0, z, z, q1, z, z).trajectory
    assert traj is not None and traj.duration < 2.0
    moves = solve_hanoi(1, 1, 0, st.n_towers, st.n_heights)  # one block, resting on tower 2 before the move
    seg = Segment(Phase.TRANSIT, 0, 0.0, traj.duration, q0, q1, z, z, "above(t1,h1)", traj)
    viol = check_segments([seg], moves, st, 1, 1, cfg, lim)
    assert viol and all("from block_0" in v and "(TRANSIT, move 1)" in v for v in viol)
    t = float(viol[0].split("t = ")[1].split(" s")[0])
    assert 0.2 * traj.duration < t < 0.8 * traj.duration


def test_an_impossible_clearance_is_reported(lab_real: Station) -> None:
    plan = plan_solve(lab_real, 0, 2, 2, PlanConfig(check_collisions=False))
    assert plan.limits is not None
    cfg = dataclasses.replace(plan.config, clearance_m=0.2)
    viol = check_segments(plan.segments, plan.moves, plan.station, plan.n_blocks, plan.start, cfg, plan.limits)
    assert viol and all(v.startswith("carried_block is") and "required 200.0 mm" in v for v in viol)
    assert len(viol) == 5  # the first five


@pytest.mark.parametrize("rate", [5.0, 25.0])
def test_result_does_not_depend_on_the_coarse_rate(lab_sim: Station, rate: float) -> None:
    """Proven clear either way: the coarse rate only changes how much refinement it takes."""
    plan = plan_solve(lab_sim, 2, 1, 2, PlanConfig(check_collisions=False))
    assert plan.limits is not None
    cfg = dataclasses.replace(plan.config, collision_rate_hz=rate)
    assert check_segments(plan.segments, plan.moves, plan.station, plan.n_blocks, plan.start, cfg, plan.limits) == []
