"""Blending at the above points (ur3hanoi.plan.motion.blend): sideways start inside the corridor, shorter motion."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.plan import Phase, PlanConfig, build_waypoints, check_vertical, plan_solve, tcp_positions_world
from ur3hanoi.plan.motion.blend import lateral_direction
from ur3hanoi.plan.motion.corridor import DENSE_MARGIN_M
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import contact_point_world


def test_lateral_direction_moves_the_suction_point_sideways(lab_real: Station) -> None:
    st = lab_real
    robot = load_ur3(st.tool, st.limits)
    q = build_waypoints(st).table[1, 2, 1]
    d = np.array([0.6, -0.8, 0.0])
    R_world_tcp = st.T_world_base.rotation @ robot.fk(q, "tcp").rotation
    h = lateral_direction(robot.frame_jacobian_local(q, "tcp"), R_world_tcp, d)
    eps = 1e-6
    dp = (tcp_positions_world(st, (q + eps * h)[None]) - tcp_positions_world(st, (q - eps * h)[None]))[0] / (2 * eps)
    np.testing.assert_allclose(dp, d, atol=1e-6)
    R_plus = robot.fk(q + eps * h, "tcp").rotation
    np.testing.assert_allclose(R_plus, robot.fk(q, "tcp").rotation, atol=1e-9)  # no rotation


def test_blending_shortens_the_motion_and_keeps_the_corridor(shipped_station: Station) -> None:
    plain = plan_solve(shipped_station, 0, 2, 3, PlanConfig(blend=False, check_collisions=False))
    blended = plan_solve(shipped_station, 0, 2, 3, PlanConfig(check_collisions=False, rate_hz=1000.0))
    assert blended.motion_s < plain.motion_s - 0.2  # at least 0.2 s over 7 moves
    viol, worst = check_vertical(blended.trajectory, blended.moves, blended.station, 0.002)
    assert viol == [] and worst <= blended.vertical_deviation_m + DENSE_MARGIN_M


def test_blended_via_has_sideways_velocity_at_the_above_pose(lab_real: Station) -> None:
    """At a blended above pose the suction point moves toward the other slot, still up (lift) or down (descend)."""
    plan = plan_solve(lab_real, 0, 2, 2, PlanConfig(check_collisions=False))
    robot = load_ur3(lab_real.tool, lab_real.limits)
    sideways = 0
    for seg in plan.segments:
        if seg.phase != Phase.CARRY or not seg.target.startswith("above"):
            continue
        m = plan.moves[seg.move_index]
        d = contact_point_world(lab_real, m.to_tower, m.to_height) - contact_point_world(lab_real, m.from_tower,
                                                                                          m.from_height)
        J = robot.frame_jacobian_local(seg.q_start, "tcp")
        R = lab_real.T_world_base.rotation @ robot.fk(seg.q_start, "tcp").rotation
        v = R @ (J @ seg.v_start)[:3]  # world velocity of the suction point leaving the source above pose
        assert v[2] > 0.05
        sideways += float(v[:2] @ d[:2]) / float(np.linalg.norm(d[:2])) > 1e-3
    assert sideways >= 1


@pytest.mark.parametrize("blend", [True, False])
def test_plans_with_and_without_blending_are_clean(lab_sim: Station, blend: bool) -> None:
    plan = plan_solve(lab_sim, 1, 0, 2, dataclasses.replace(PlanConfig(), blend=blend))
    assert plan.violations == ()
