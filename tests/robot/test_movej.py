"""The UR movej profile: synchronised trapezoid, within the capped speed/acceleration, as fast as the caps allow."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.robot.model import JointLimits
from ur3hanoi.robot.movej import MoveJReference, plan_movej

LIM = JointLimits.ur3()
V_MAX, A_MAX = np.array(LIM.v_max), np.array(LIM.a_max)
angles = st.lists(st.floats(-3.0, 3.0), min_size=6, max_size=6)
rates = st.floats(0.05, 10.0)


def sampled(mv, n: int = 400) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.linspace(0.0, mv.duration, n)
    qs, vs, _accs = zip(*(mv.sample(x) for x in t), strict=True)
    return t, np.array(qs), np.array(vs)


@settings(max_examples=150, deadline=None)
@given(angles, angles, rates, rates)
def test_synchronised_within_caps_and_time_optimal(q0, q1, v, a):
    mv = plan_movej(q0, q1, v, a, V_MAX, A_MAX)
    dq = np.subtract(q1, q0)
    v_cap, a_cap = np.minimum(v, V_MAX), np.minimum(a, A_MAX)
    assert np.all(mv.peak_velocity <= v_cap * (1 + 1e-9) + 1e-12)
    assert np.all(mv.peak_acceleration <= a_cap * (1 + 1e-9) + 1e-12)
    # Time-optimal for a shared trapezoid: some joint uses its full acceleration, and its full speed unless the
    # profile is a triangle (no cruise phase).
    moving = np.abs(dq) > 1e-12
    if moving.any():
        acc_use = np.max(mv.peak_acceleration[moving] / a_cap[moving])
        assert acc_use == pytest.approx(1.0, rel=1e-9)
        cruise = mv.duration > 2 * mv.t_acc * (1 + 1e-9)
        if cruise:
            assert np.max(mv.peak_velocity[moving] / v_cap[moving]) == pytest.approx(1.0, rel=1e-9)
    t, qs, _vs = sampled(mv)
    # Synchronised: every joint is at the same fraction of its way at every instant.
    s = np.array([mv.path(x)[0] for x in t])
    np.testing.assert_allclose(qs, np.asarray(q0) + np.outer(s, dq), atol=1e-12)
    if moving.any():
        assert s[0] == 0.0 and np.all(np.diff(s) >= -1e-15)
    np.testing.assert_array_equal(mv.sample(mv.duration)[0], np.asarray(q1, dtype=float))
    np.testing.assert_array_equal(mv.sample(mv.duration + 1.0)[1], np.zeros(6))


def test_acceleration_of_samples_within_caps():
    q0, q1 = np.zeros(6), np.array([1.0, -0.5, 0.2, 2.0, 0.1, -1.5])
    mv = plan_movej(q0, q1, 4.0, 4.0, V_MAX, A_MAX)
    t, _qs, vs = sampled(mv, n=20000)
    acc = np.abs(np.diff(vs, axis=0)) / np.diff(t)[:, None]
    assert np.all(acc <= np.minimum(4.0, A_MAX) + 1e-6)
    assert np.all(np.abs(vs) <= np.minimum(4.0, V_MAX) + 1e-9)


@settings(max_examples=50, deadline=None)
@given(angles, angles, rates, rates)
def test_sampled_acceleration_is_the_rate_of_the_sampled_velocity(q0, q1, v, a):
    """The reference acceleration the servo's feed-forward uses: over any interval, its mean (the trapezoid is
    piecewise constant in acceleration: integrated exactly on a fine grid) is the change of velocity."""
    mv = plan_movej(q0, q1, v, a, V_MAX, A_MAX)
    if not 0.0 < mv.duration < 100.0:
        return
    t = np.linspace(-0.01, mv.duration + 0.01, 4001)
    _qs, vs, accs = (np.array(x) for x in zip(*(mv.sample(x) for x in t), strict=True))
    integral = np.cumsum(0.5 * (accs[1:] + accs[:-1]) * np.diff(t)[:, None], axis=0)
    # Each of the (at most 4) acceleration steps costs at most one grid interval times the step's height.
    tol = 4 * np.diff(t)[0] * mv.peak_acceleration + 1e-9
    assert np.all(np.abs(vs[1:] - vs[0] - integral) <= tol)
    assert np.all(np.abs(accs) <= mv.peak_acceleration * (1 + 1e-9) + 1e-12)
    np.testing.assert_array_equal(mv.sample(mv.duration)[2], np.zeros(6))


def test_long_move_lasts_distance_over_speed_plus_ramp():
    # The course's simulator: a move lasts about max|dq| / v; a trapezoid adds v / a for the ramps.
    q0 = np.zeros(6)
    q1 = np.array([3.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    mv = plan_movej(q0, q1, 1.0, 4.0, V_MAX, A_MAX)
    assert mv.duration == pytest.approx(3.0 / 1.0 + 1.0 / 4.0, rel=1e-12)


def test_lab_speed_is_capped_at_the_ur3_joint_limits():
    # v = a = 4.0 (the lab's) on the base: capped at 180 deg/s = pi rad/s, 4 rad/s^2.
    q1 = np.array([3.0, 0, 0, 0, 0, 0])
    mv = plan_movej(np.zeros(6), q1, 4.0, 4.0, V_MAX, A_MAX)
    assert mv.peak_velocity[0] == pytest.approx(math.pi, rel=1e-12)
    # The same distance on a wrist (360 deg/s) runs at the commanded 4 rad/s.
    wrist = plan_movej(np.zeros(6), np.array([0, 0, 0, 6.0, 0, 0]), 4.0, 4.0, V_MAX, A_MAX)
    assert wrist.peak_velocity[3] == pytest.approx(4.0, rel=1e-12)
    assert wrist.duration == pytest.approx(6.0 / 4.0 + 4.0 / 4.0, rel=1e-12)


def test_leading_joint_moves_at_v_and_a_others_scaled():
    q1 = np.array([1.0, 0.5, -0.25, 0.0, 0.0, 0.0])
    mv = plan_movej(np.zeros(6), q1, 0.5, 1.0, V_MAX, A_MAX)
    assert mv.peak_velocity[0] == pytest.approx(0.5, rel=1e-12)
    assert mv.peak_acceleration[0] == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_allclose(mv.peak_velocity[:3], [0.5, 0.25, 0.125], rtol=1e-12)


def test_zero_length_move_is_instant():
    q = np.array([0.1, -0.2, 0.3, -0.4, 0.5, -0.6])
    mv = plan_movej(q, q, 4.0, 4.0, V_MAX, A_MAX)
    assert mv.duration == 0.0
    np.testing.assert_array_equal(mv.sample(0.0)[0], q)


def test_the_reference_runs_one_move_after_another_from_where_it_rests():
    ref = MoveJReference(np.zeros(6), V_MAX, A_MAX)
    q1 = np.array([0.5, -0.3, 0.2, 0.0, 0.1, -0.4])
    first = ref.begin(q1, 4.0, 4.0)
    assert ref.motion is first and first.duration > 0.0
    samples = []
    while (s := ref.advance(0.008)) is not None:
        samples.append(s)
    assert len(samples) == math.ceil(first.duration / 0.008)
    np.testing.assert_array_equal(samples[-1][0], q1)  # the last sample is the destination, at rest
    np.testing.assert_array_equal(samples[-1][1], np.zeros(6))
    np.testing.assert_array_equal(ref.q, q1)
    second = ref.begin(np.zeros(6), 4.0, 4.0)
    np.testing.assert_array_equal(second.q0, q1)  # the next move starts where the last one ended
    np.testing.assert_array_equal(ref.target, np.zeros(6))
    assert ref.advance(0.008)[1].any()  # moving
    still = MoveJReference(q1, V_MAX, A_MAX)
    assert still.begin(q1, 4.0, 4.0).duration == 0.0 and still.motion is None and still.advance(0.008) is None
