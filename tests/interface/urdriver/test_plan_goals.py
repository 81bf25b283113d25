"""A Ruckig plan as FollowJointTrajectory goals: one goal per stretch between the suction dwells, the plan's own
samples, the controller's quintics giving the plan back."""

from __future__ import annotations

import itertools
from functools import cache

import numpy as np
import pytest

from ur3hanoi.interface.urdriver.follower import TrajectoryFollower
from ur3hanoi.interface.urdriver.plan_goals import move_goal, plan_stretches
from ur3hanoi.interface.urdriver.profile import ROS1_SCALED
from ur3hanoi.plan import Phase, Plan, PlanConfig, plan_solve
from ur3hanoi.station.calibration import load_station


@cache
def plan() -> Plan:
    return plan_solve(load_station("lab_sim"), 0, 2, 2, PlanConfig())


def test_stretches_alternate_motions_and_dwells():
    p = plan()
    stretches = plan_stretches(p)
    kinds = [s.kind for s in stretches]
    assert kinds == ["motion", "grasp", "motion", "release"] * 3 + ["motion"]
    assert [s.carrying for s in stretches if s.kind == "motion"] == [False, True, False, True, False, True, False]
    for a, b in itertools.pairwise(stretches):
        assert a.k1 == b.k0  # contiguous: each starts where the last ended
    assert stretches[0].k0 == 0 and stretches[-1].k1 == len(p.trajectory.t) - 1
    for s in stretches:
        if s.kind != "motion":
            assert set(p.trajectory.phase[s.k0:s.k1 + 1]) <= {Phase.GRASP_DWELL, Phase.RELEASE_DWELL}
            assert s.duration_s == pytest.approx(p.config.dwell_s, abs=2 / p.trajectory.rate_hz)


def test_every_point_has_every_field_and_the_last_is_at_rest():
    for s in plan_stretches(plan()):
        if s.goal is None:
            continue
        points = s.goal.points
        assert points[0].time_from_start_s == 0.0
        assert all(len(p.positions) == len(p.velocities) == len(p.accelerations) == 6 for p in points)
        assert points[-1].velocities == (0.0,) * 6 and points[-1].accelerations == (0.0,) * 6
        assert np.all(np.diff([p.time_from_start_s for p in points]) > 0)


@pytest.mark.parametrize(("stride", "tolerance"), [(1, 1e-9), (5, 1e-3)])
def test_the_controllers_quintics_give_the_plan_back(stride, tolerance):
    p = plan()
    tr, dt = p.trajectory, 1.0 / p.trajectory.rate_hz
    f = TrajectoryFollower(ROS1_SCALED, tr.q[0], p.station.limits.a_max)
    f.update(tr.q[0], np.zeros(6), dt, 1.0)
    worst = 0.0
    for s in plan_stretches(p, stride):
        if s.goal is None:
            continue
        assert f.submit(s.k0, s.goal) is None
        for j in range(1, s.k1 - s.k0 + 2):  # the controller starts a goal at the next cycle: sample j - 1
            d = f.update(f.desired.q, f.desired.qd, dt, 1.0)
            worst = max(worst, float(np.max(np.abs(d.q - tr.q[s.k0 + j - 1]))))
        assert [o.status for o in f.take_outcomes()] == ["succeeded"]
    assert worst < tolerance


def test_a_slow_move_stays_within_its_fraction_of_the_limits():
    st = load_station("lab_sim")
    q0 = st.q_home_array
    g = move_goal(q0, q0 + np.array([0.5, -0.2, 0.3, 0.0, 0.1, -0.4]), st, 0.25)
    v = np.array([p.velocities for p in g.points])
    a = np.array([p.accelerations for p in g.points])
    assert np.all(np.max(np.abs(v), axis=0) <= 0.25 * np.array(st.limits.v_max) + 1e-9)
    assert np.all(np.max(np.abs(a), axis=0) <= 0.25 * np.array(st.limits.a_max) + 1e-9)
    np.testing.assert_allclose(g.points[-1].positions, q0 + np.array([0.5, -0.2, 0.3, 0.0, 0.1, -0.4]), atol=1e-9)
