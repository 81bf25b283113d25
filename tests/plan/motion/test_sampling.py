"""Sampling (ur3hanoi.plan.motion.sampling): the vectorised sampler equals Ruckig's own ``Trajectory.at_time``."""

from __future__ import annotations

import numpy as np
import pytest

from ur3hanoi.plan import OfflineRuckig, Phase, Plan, PlanConfig, Segment, plan_solve, sample
from ur3hanoi.station.calibration import Station


@pytest.fixture(scope="module")
def plan(lab_real: Station) -> Plan:
    return plan_solve(lab_real, 0, 2, 3, PlanConfig(check_collisions=False))


def test_samples_equal_ruckig_at_time(plan: Plan) -> None:
    """Joint segments: at_time itself; vertical legs: at_time of s mapped through the path (same arithmetic)."""
    tr = plan.trajectory
    rng = np.random.default_rng(0)
    for k in rng.choice(len(tr.t) - 1, 300, replace=False):
        seg = next(s for s in reversed(plan.segments) if s.t_start <= tr.t[k])
        if seg.trajectory is None:
            np.testing.assert_array_equal(tr.q[k], seg.q_start)
            continue
        x, xd, xdd = (np.array(v) for v in seg.trajectory.at_time(min(tr.t[k] - seg.t_start, seg.duration)))
        if seg.path is not None:
            q, d1, d2, _ = seg.path.evaluate(x[0])
            x, xd, xdd = q, d1 * xd[0], d2 * xd[0] ** 2 + d1 * xdd[0]
        np.testing.assert_allclose(tr.q[k], x, rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.qd[k], xd, rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.qdd[k], xdd, rtol=0, atol=1e-11)


def test_sample_grid_and_labels(plan: Plan) -> None:
    tr = plan.trajectory
    n = len(tr.t)
    np.testing.assert_array_equal(tr.t, np.arange(n) / tr.rate_hz)
    assert tr.t[-2] < plan.duration_s <= tr.t[-1]
    np.testing.assert_array_equal(tr.qd[-1], 0.0)
    for seg in plan.segments:
        inside = (tr.t >= seg.t_start) & (tr.t < seg.t_end)
        assert np.all(tr.phase[inside] == int(seg.phase)) and np.all(tr.move_index[inside] == seg.move_index)
        carrying_suction = seg.phase in (Phase.GRASP_DWELL, Phase.LIFT, Phase.CARRY, Phase.DESCEND_PLACE)
        assert np.all(tr.suction[inside] == carrying_suction)


def test_brake_profile_fallback_equals_at_time() -> None:
    """A start above the velocity limit gives Ruckig a brake pre-profile; sampling still equals at_time."""
    q1 = np.array([0.5, -0.3, 0.2, 0.1, 0.0, -0.4])
    v0 = np.array([1.5, 0.0, 0.0, 0.0, 0.0, 0.0])  # above max_velocity: brake first
    sol = OfflineRuckig([1.0] * 6, [2.0] * 6, [10.0] * 6).solve(np.zeros(6), v0, np.zeros(6), q1, np.zeros(6),
                                                               np.zeros(6))
    traj = sol.trajectory
    assert traj is not None and traj.profiles[0][0].brake.duration > 0
    z = np.zeros(6)
    tr = sample([Segment(Phase.TRANSIT, 0, 0.0, traj.duration, z, q1, v0, z, "x", traj)], 125.0)
    for k in range(len(tr.t) - 1):
        x, xd, xdd = (np.array(v) for v in traj.at_time(tr.t[k]))
        np.testing.assert_array_equal(tr.q[k], x)
        np.testing.assert_array_equal(tr.qd[k], xd)
        np.testing.assert_array_equal(tr.qdd[k], xdd)
