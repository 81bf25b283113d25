"""Safety checks (ur3hanoi.plan.checks): clean plans pass, crafted limit and vertical-line violations are flagged."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.plan import Phase, Plan, PlanConfig, check_limits, check_vertical, plan_solve, tcp_positions_world
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station


@pytest.fixture(scope="module")
def plan(lab_sim: Station) -> Plan:
    return plan_solve(lab_sim, 0, 2, 2, PlanConfig(check_collisions=False))


def _limit_violations(plan: Plan, **arrays: np.ndarray) -> list[str]:
    assert plan.limits is not None
    lim = plan.station.limits
    tr = dataclasses.replace(plan.trajectory, **arrays)
    return check_limits(tr, plan.segments, plan.limits, lim.q_min, lim.q_max)


def test_clean_plan_passes(plan: Plan) -> None:
    assert _limit_violations(plan) == []
    viol, worst = check_vertical(plan.trajectory, plan.moves, plan.station, 0.002)
    assert viol == [] and 0.0 <= worst < 0.002


@pytest.mark.parametrize(("field", "limit"), [("qd", "v_max"), ("qdd", "a_max"), ("qddd", "j_max")])
@pytest.mark.parametrize("joint", [0, 4])
def test_limit_check_flags_one_percent_over(plan: Plan, field: str, limit: str, joint: int) -> None:
    """One sample of one joint set to 1.01 x its limit is reported, naming the joint, the quantity and the time."""
    assert plan.limits is not None
    arr = getattr(plan.trajectory, field).copy()
    k = len(arr) // 3
    arr[k, joint] = -1.01 * getattr(plan.limits, limit)[joint]
    viol = _limit_violations(plan, **{field: arr})
    name = {"qd": "velocity", "qdd": "acceleration", "qddd": "jerk"}[field]
    assert len(viol) == 1
    assert f"joint {joint + 1} {name}" in viol[0] and f"t = {plan.trajectory.t[k]:.3f} s" in viol[0]


def test_limit_check_tolerance_is_relative_1e6(plan: Plan) -> None:
    assert plan.limits is not None
    qd = plan.trajectory.qd.copy()
    qd[10, 2] = plan.limits.v_max[2] * (1 + 0.5e-6)  # within LIMIT_RTOL
    assert _limit_violations(plan, qd=qd) == []
    qd[10, 2] = plan.limits.v_max[2] * (1 + 2e-6)
    assert len(_limit_violations(plan, qd=qd)) == 1


def test_limit_check_flags_a_position_outside_the_joint_range(plan: Plan) -> None:
    q = plan.trajectory.q.copy()
    q[5, 1] = plan.station.limits.q_max[1] + 1e-3
    viol = _limit_violations(plan, q=q)
    assert len(viol) == 1 and viol[0].startswith("joint 2 position")


@pytest.mark.parametrize("flagged", [True, False])
def test_vertical_check_flags_a_line_moved_away(plan: Plan, flagged: bool) -> None:
    """Checked against lines moved sideways by d: every vertical sample is d off, +- the plan's own deviation
    ``own`` (< 2 mm); d = 2 mm + own + 0.5 mm breaks the 2 mm tolerance, d = (2 mm - own) / 2 does not."""
    st = plan.station
    _, own = check_vertical(plan.trajectory, plan.moves, st, 0.002)
    d = 0.002 + own + 0.0005 if flagged else (0.002 - own) / 2
    assert d > 0
    moved = st.with_grid([(x + d * 0.6, y + d * 0.8, z) for x, y, z in st.tower_origins], st.height_step,
                         st.tool_yaw)
    viol, worst = check_vertical(plan.trajectory, plan.moves, moved, 0.002)
    assert d - own <= worst <= d + own
    assert bool(viol) == flagged
    if flagged:
        assert len(viol) == 5  # the first five are reported
        assert "mm off the vertical line of tower" in viol[0] and "allowed 2.0 mm" in viol[0]


def test_vertical_check_flags_a_single_bent_sample(plan: Plan) -> None:
    """One sample of a descend moved 3 mm sideways (by the inverse Jacobian) is the one reported."""
    tr, st = plan.trajectory, plan.station
    robot = load_ur3(st.tool, st.limits)
    k = int(np.flatnonzero(tr.phase == int(Phase.DESCEND_PICK))[5])
    q = tr.q.copy()
    # World x offset of the suction point, expressed in the local tcp frame (Jacobian frame), no rotation.
    R_world_tcp = st.T_world_base.rotation @ robot.fk(q[k], "tcp").rotation
    twist = np.concatenate([R_world_tcp.T @ np.array([0.003, 0.0, 0.0]), np.zeros(3)])
    q[k] = q[k] + np.linalg.solve(robot.frame_jacobian_local(q[k], "tcp"), twist)
    viol, worst = check_vertical(dataclasses.replace(tr, q=q), plan.moves, st, 0.002)
    assert worst == pytest.approx(0.003, abs=2e-4)
    assert len(viol) == 1 and f"t = {tr.t[k]:.3f} s" in viol[0] and "DESCEND_PICK" in viol[0]


def test_batched_fk_matches_pinocchio(lab_real: Station) -> None:
    robot = load_ur3(lab_real.tool, lab_real.limits)
    q = np.random.default_rng(1).uniform(-3.0, 3.0, (50, 6))
    expected = np.array([(lab_real.T_world_base * robot.fk(qi, "tcp")).translation for qi in q])
    np.testing.assert_allclose(tcp_positions_world(lab_real, q), expected, rtol=0, atol=1e-10)
