"""Safety checks (plan.checks.limits): clean plans pass, crafted limit and vertical-line violations are flagged."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.errors import PlanError
from ur3hanoi.plan import Phase, Plan, PlanConfig, check_limits, check_vertical, plan_solve, tcp_positions_world
from ur3hanoi.plan.checks.suction import check_suction_hold
from ur3hanoi.plan.kinematics import tcp_accelerations_world
from ur3hanoi.plan.types import SUCTION_HOLD_MPS2
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station


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
    ``own``; d = 2 mm + own + 0.5 mm breaks the 2 mm tolerance, d = (2 mm - own) / 2 does not."""
    st = plan.station
    _, own = check_vertical(plan.trajectory, plan.moves, st, 0.002)
    d = 0.002 + own + 0.0005 if flagged else 0.5 * (0.002 - own)
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


# ------------------------------------------------------------------------------------------ what the suction holds


def test_tcp_acceleration_is_centripetal_when_only_the_base_turns(lab_sim: Station) -> None:
    """Joint 1 turning at a constant rate w: the suction point circles the base's vertical axis, so its world
    acceleration is w^2 r towards that axis (r: distance from it), nothing vertical."""
    q = np.array([lab_sim.q_home_array, lab_sim.q_home_array + np.array([0.3, -0.2, 0.4, 0.1, 0.0, 0.5])])
    w = 2.0
    qd = np.zeros_like(q)
    qd[:, 0] = w
    acc = tcp_accelerations_world(lab_sim, q, qd, np.zeros_like(q))
    p = tcp_positions_world(lab_sim, q)
    axis_xy = lab_sim.T_world_base.translation[:2]
    radial = p[:, :2] - axis_xy
    np.testing.assert_allclose(acc[:, :2], -w * w * radial, atol=1e-6)
    np.testing.assert_allclose(acc[:, 2], 0.0, atol=1e-6)


def test_suction_hold_check_flags_only_above_the_limit(plan: Plan) -> None:
    """The lab plan needs the weight plus a little inertia; a limit just below its worst need flags it, naming a
    carrying phase and the move, a limit just above does not."""
    viol, worst = check_suction_hold(plan.trajectory, plan.station, SUCTION_HOLD_MPS2)
    assert viol == [] and 9.81 < worst < 20.0
    below, _ = check_suction_hold(plan.trajectory, plan.station, worst - 0.01)
    assert len(below) == 1 and "of suction" in below[0]
    assert any(p.name in below[0] for p in Phase if p.carrying) and "move " in below[0]
    assert check_suction_hold(plan.trajectory, plan.station, worst + 0.01)[0] == []


def test_a_plan_the_suction_cannot_hold_is_refused(lab_sim: Station) -> None:
    """100x the acceleration caps (the carried block then needs about 215 m/s^2, the lab plan 12.8) against a seal
    an eighth as strong as the simulated one: the planner refuses the plan (the joint limits it was given are all
    kept)."""
    cfg = PlanConfig(a_max=(400.0,) * 6, j_max=(5e4,) * 6, check_collisions=False,
                     suction_hold_mps2=SUCTION_HOLD_MPS2 / 8)
    with pytest.raises(PlanError, match=r"the carried block needs \d+\.\d m/s\^2 of suction"):
        plan_solve(lab_sim, 0, 2, 3, cfg)
    plan = plan_solve(lab_sim, 0, 2, 3, dataclasses.replace(cfg, raise_on_violation=False))
    assert plan.violations and all("of suction" in v for v in plan.violations)
