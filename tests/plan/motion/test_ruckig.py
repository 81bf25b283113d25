"""The Ruckig wrapper (plan.motion.ruckig): results kept, states reached, halt trajectories and their samples."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from ruckig import Result

from ur3hanoi.plan import KinematicLimits, OfflineRuckig, control_samples, to_pose, to_rest

V_MAX, A_MAX, J_MAX = [np.pi] * 3 + [2 * np.pi] * 3, [4.0] * 3 + [8.0] * 3, [20.0] * 3 + [40.0] * 3
LIMITS = KinematicLimits(v_max=np.array(V_MAX), a_max=np.array(A_MAX), j_max=np.array(J_MAX))
ZERO = [0.0] * 6


def test_invalid_input_keeps_ruckig_result_and_message() -> None:
    """A target velocity above the limit is rejected by Ruckig; the solution says so instead of raising."""
    rk = OfflineRuckig([1.0], [2.0], [10.0])
    sol = rk.solve([0.0], [0.0], [0.0], [1.0], [1.5], [0.0])
    assert not sol.ok and sol.trajectory is None
    assert sol.result == Result.ErrorInvalidInput
    assert sol.reason.startswith("Ruckig ErrorInvalidInput: ")
    assert "target velocity" in sol.message and "\n" not in sol.reason


def test_success_reaches_the_target_state_and_is_timed() -> None:
    rk = OfflineRuckig(V_MAX, A_MAX, J_MAX)
    q0, q1 = [0.1, -1.2, 0.8, -0.3, 1.0, 0.0], [1.0, -0.5, 1.5, -1.0, 0.2, 2.0]
    v1, a1 = [0.3, -0.2, 0.0, 0.5, 0.0, -0.4], [0.0, 0.5, 0.0, 0.0, -1.0, 0.0]
    sol = rk.solve(q0, ZERO, ZERO, q1, v1, a1)
    assert sol.ok and sol.result == Result.Working and sol.trajectory is not None
    assert sol.reason == "Ruckig Working"
    q, v, a = (np.array(x) for x in sol.trajectory.at_time(sol.trajectory.duration))
    np.testing.assert_allclose(q, q1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v, v1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(a, a1, rtol=0, atol=1e-9)
    assert rk.seconds > 0.0


def test_lists_and_arrays_give_the_same_trajectory() -> None:
    rk = OfflineRuckig(np.array(V_MAX), np.array(A_MAX), np.array(J_MAX))
    q1 = [0.5, -0.3, 0.2, 0.1, 0.0, -0.4]
    from_lists = rk.solve(ZERO, ZERO, ZERO, q1, ZERO, ZERO).trajectory
    from_arrays = rk.solve(np.zeros(6), np.zeros(6), np.zeros(6), np.array(q1), np.zeros(6), np.zeros(6)).trajectory
    assert from_lists is not None and from_arrays is not None
    assert from_lists.duration == from_arrays.duration
    assert from_lists.at_time(0.3) == from_arrays.at_time(0.3)


states = st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6).map(np.array)


@settings(max_examples=25, deadline=None)
@given(q0=states, v_frac=states, a_frac=states)
def test_to_rest_stops_within_the_limits(q0: np.ndarray, v_frac: np.ndarray, a_frac: np.ndarray) -> None:
    v0, a0 = 0.9 * v_frac * LIMITS.v_max, 0.5 * a_frac * LIMITS.a_max
    sol = to_rest(q0, v0, a0, LIMITS)
    assert sol.ok and sol.trajectory is not None, sol.reason
    _, qd, qdd = control_samples(sol.trajectory, 1 / 125)
    np.testing.assert_allclose(qd[-1], 0.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(qdd[-1], 0.0, rtol=0, atol=1e-9)
    assert np.all(np.abs(qd) <= LIMITS.v_max * (1 + 1e-9))
    assert np.all(np.abs(qdd) <= LIMITS.a_max * (1 + 1e-9))


def test_to_pose_ends_at_rest_on_the_pose() -> None:
    q1 = np.array([0.3, -1.0, 1.2, -1.5, -1.5, 0.2])
    sol = to_pose(np.zeros(6), [0.5, 0.0, -0.5, 0.0, 1.0, 0.0], ZERO, q1, LIMITS)
    assert sol.ok and sol.trajectory is not None
    q, qd, _ = control_samples(sol.trajectory, 1 / 500)
    np.testing.assert_allclose(q[-1], q1, rtol=0, atol=1e-9)
    np.testing.assert_allclose(qd[-1], 0.0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("dt", [1 / 125, 1 / 500, 0.37])
def test_control_samples_are_one_cycle_ahead_and_clipped(dt: float) -> None:
    sol = to_pose(np.zeros(6), ZERO, ZERO, [0.4, 0.0, -0.2, 0.0, 0.0, 0.1], LIMITS)
    assert sol.trajectory is not None
    traj = sol.trajectory
    q, qd, qdd = control_samples(traj, dt)
    n = math.ceil(traj.duration / dt)
    assert q.shape == qd.shape == qdd.shape == (n, 6)
    for i in (0, n // 2, n - 1):
        expected = traj.at_time(min((i + 1) * dt, traj.duration))
        np.testing.assert_array_equal(np.array([q[i], qd[i], qdd[i]]), np.array(expected))


def test_control_samples_of_a_zero_length_motion_hold_the_pose() -> None:
    q0 = [0.2, -0.4, 0.6, 0.0, 0.1, 0.0]
    sol = to_pose(q0, ZERO, ZERO, q0, LIMITS)
    assert sol.ok and sol.trajectory is not None and sol.trajectory.duration == 0.0
    q, qd, _ = control_samples(sol.trajectory, 1 / 125)
    assert q.shape == (1, 6)
    np.testing.assert_array_equal(q[0], q0)
    np.testing.assert_array_equal(qd[0], 0.0)
