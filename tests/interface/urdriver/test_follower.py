"""The scaled joint trajectory controller on the CPU clock: interpolation from the current desired state, scaled
time, tolerances and results, preemption and cancel, ROS 1 against ROS 2 rules."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ErrorCode
from ur3hanoi.interface.urdriver.follower import TrajectoryFollower
from ur3hanoi.interface.urdriver.goal import JointTolerance, TrajectoryGoal, TrajectoryPoint
from ur3hanoi.interface.urdriver.profile import ROS1_SCALED, ROS2_SCALED

DT = 0.008
Q0 = np.radians([120.0, -90.0, 90.0, -90.0, -90.0, 0.0])
A_MAX = (4.0, 4.0, 4.0, 8.0, 8.0, 8.0)
Z = (0.0,) * 6


def goal(q_end: np.ndarray, duration: float, q_start: np.ndarray = Q0, fields: int = 3,
         **kw: object) -> TrajectoryGoal:
    def pt(q: np.ndarray, t: float) -> TrajectoryPoint:
        return TrajectoryPoint(tuple(q), Z if fields > 1 else (), Z if fields > 2 else (), time_from_start_s=t)

    return TrajectoryGoal(CONTROLLER_JOINTS, (pt(q_start, 0.0), pt(q_end, duration)), **kw)  # type: ignore[arg-type]


def run(f: TrajectoryFollower, cycles: int, scaling: float = 1.0, actual=None):
    """Run ``cycles`` cycles with a perfect tracker (or ``actual(k, desired) -> q``); the outcomes and desired q's."""
    outcomes, qs = [], []
    q, qd = f.desired.q.copy(), np.zeros(6)
    for k in range(cycles):
        d = f.update(q, qd, DT, scaling)
        qs.append(d.q.copy())
        q, qd = (d.q.copy(), d.qd * scaling) if actual is None else (actual(k, d), np.zeros(6))
        for o in f.take_outcomes():
            outcomes.append((k + 1, o))
    return outcomes, np.array(qs)


def follower(profile=ROS1_SCALED) -> TrajectoryFollower:
    return TrajectoryFollower(profile, Q0, A_MAX)


def test_a_goal_succeeds_when_its_trajectory_ends_and_follows_the_quintic():
    f = follower()
    assert f.submit("a", goal(Q0 + 0.5, 2.0)) is None
    outcomes, qs = run(f, 300)
    (k, o), = outcomes
    assert (o.key, o.status, o.code, o.error_string) == ("a", "succeeded", ErrorCode.SUCCESSFUL, "")
    assert k == 250  # 2.0 s at 8 ms: the cycle its trajectory ends
    # The quintic rest-to-rest: half way at half time, smooth.
    np.testing.assert_allclose(qs[124], Q0 + 0.25, atol=0.01)
    np.testing.assert_allclose(qs[-1], Q0 + 0.5, atol=1e-12)


def test_speed_scaling_stretches_the_trajectory():
    f = follower()
    f.submit("a", goal(Q0 + 0.5, 2.0))
    outcomes, _ = run(f, 600, scaling=0.5)
    assert outcomes[0][0] == pytest.approx(500, abs=1)
    f = follower()
    f.submit("a", goal(Q0 + 0.5, 2.0))
    assert run(f, 600, scaling=0.0)[0] == []  # paused: the trajectory waits


def test_the_first_segment_starts_at_the_current_desired_state_not_at_point_zero():
    f = follower()
    far = Q0 + 0.3  # a first point elsewhere: the controller bridges from where it is, no jump
    f.submit("a", goal(Q0 + 0.5, 2.0, q_start=far))
    _, qs = run(f, 2)
    assert np.max(np.abs(qs[0] - Q0)) < 1e-3


def test_positions_only_interpolate_linearly():
    f = follower()
    f.submit("a", goal(Q0 + 0.4, 1.0, fields=1))
    _, qs = run(f, 130)
    steps = np.diff(qs[5:100, 0])
    np.testing.assert_allclose(steps, 0.4 * DT, rtol=1e-9)


def test_path_tolerance_aborts_when_the_arm_is_held_ros1_keeps_going_ros2_holds():
    for profile, keeps_going in ((ROS1_SCALED, True), (ROS2_SCALED, False)):
        f = follower(profile)
        f.submit("a", goal(Q0 + 1.0, 2.0))
        outcomes, qs = run(f, 300, actual=lambda k, d: Q0.copy())  # the arm does not move
        (k, o), = outcomes
        assert o.status == "aborted" and o.code == ErrorCode.PATH_TOLERANCE_VIOLATED
        assert o.error_string == profile.path_error  # ROS 1's scaled controller: none; ROS 2: a fixed text
        # Aborted in the cycle the error first exceeds 0.2 rad.
        assert abs(qs[k - 1, 0] - Q0[0]) > 0.2 >= abs(qs[k - 2, 0] - Q0[0])
        assert (np.max(np.abs(qs[-1] - Q0 - 1.0)) < 1e-9) == keeps_going


def test_ros1_scaled_path_error_has_no_text_but_the_plain_jtc_format_names_the_joint():
    from ur3hanoi.interface.urdriver.profile import JTC_ERROR_TEXTS

    f = follower(replace(ROS1_SCALED, **JTC_ERROR_TEXTS))
    f.submit("a", goal(Q0 + 1.0, 2.0))
    (_, o), = run(f, 300, actual=lambda k, d: Q0.copy())[0]
    assert o.error_string.startswith("shoulder_pan_joint path error 0.2")


def lagging(offset: float):
    return lambda k, d: d.q - offset


def test_goal_tolerance_waits_the_goal_time_then_aborts():
    f = follower()
    f.submit("a", goal(Q0 + 0.5, 1.0))
    outcomes, _ = run(f, 400, actual=lagging(0.15))  # 0.15 rad behind: inside the path, outside the goal tolerance
    (k, o), = outcomes
    assert o.code == ErrorCode.GOAL_TOLERANCE_VIOLATED
    assert (k - 125) * DT == pytest.approx(0.6, abs=DT)  # the 0.6 s goal time after the 1.0 s trajectory


def test_a_goals_own_tolerances_and_goal_time():
    f = follower()
    f.submit("a", goal(Q0 + 0.5, 1.0, goal_time_tolerance_s=2.0))
    (k, o), = run(f, 500, actual=lagging(0.15))[0]
    assert o.code == ErrorCode.GOAL_TOLERANCE_VIOLATED and (k - 125) * DT == pytest.approx(2.0, abs=DT)
    f = follower()
    wide = tuple(JointTolerance(j, position=-1.0) for j in CONTROLLER_JOINTS)  # -1: not checked
    f.submit("a", goal(Q0 + 0.5, 1.0, goal_tolerance=wide))
    (k, o), = run(f, 300, actual=lagging(0.15))[0]
    assert o.code == ErrorCode.SUCCESSFUL and k == 125
    f = follower()
    tight = tuple(JointTolerance(j, position=0.01) for j in CONTROLLER_JOINTS)
    f.submit("a", goal(Q0 + 0.5, 1.0, path_tolerance=tight))
    (_, o), = run(f, 300, actual=lagging(0.015))[0]
    assert o.code == ErrorCode.PATH_TOLERANCE_VIOLATED


def test_ros2_goal_time_zero_waits_for_the_arm():
    f = follower(ROS2_SCALED)
    f.submit("a", goal(Q0 + 0.5, 1.0))
    arrive = 400  # the arm lags until cycle 400, then arrives
    outcomes, _ = run(f, 500, actual=lambda k, d: d.q - (0.15 if k < arrive else 0.0))
    (k, o), = outcomes
    assert o.status == "succeeded" and o.error_string == "Goal successfully reached!"
    assert k == arrive + 2  # the arm is read in the cycle after


def test_a_new_goal_preempts_and_continues_smoothly():
    f = follower()
    f.submit("a", goal(Q0 + 1.0, 2.0))
    run(f, 100)
    before = f.desired
    assert f.submit("b", goal(Q0 - 0.5, 2.0, q_start=before.q)) is None
    outcomes, qs = run(f, 400)
    assert [(o.key, o.status) for _, o in outcomes] == [("a", "preempted"), ("b", "succeeded")]
    assert outcomes[0][0] == 1  # reported in the next cycle
    # No jump: the bridge starts from the desired position and velocity.
    assert np.max(np.abs(qs[0] - before.q)) < 2 * DT * np.max(np.abs(before.qd)) + 1e-9
    np.testing.assert_allclose(qs[-1], Q0 - 0.5, atol=1e-12)


def test_cancel_ramps_to_rest_within_the_deceleration_limit_and_holds():
    f = follower()
    f.submit("a", goal(Q0 + 2.0, 1.5))
    run(f, 94)
    assert np.max(np.abs(f.desired.qd)) > 2.0
    assert f.cancel("a") and not f.cancel("a")
    outcomes, qs = run(f, 200)
    assert [(o.key, o.status) for _, o in outcomes] == [("a", "canceled")]
    acc = np.diff(qs, n=2, axis=0) / DT ** 2
    assert np.all(np.max(np.abs(acc), axis=0) <= np.array(A_MAX) * 1.01)
    assert np.max(np.abs(qs[-1] - qs[-50])) == 0.0  # at rest, holding


def test_points_all_in_the_past_are_invalid_goal():
    f = follower()
    r = f.submit("a", replace(goal(Q0 + 0.5, 1.0), start_in_s=-10.0))
    assert r is not None and r.code == ErrorCode.INVALID_GOAL
    assert r.error_string.startswith("Dropping all 2 trajectory point(s), as they occur before the current time.")


def test_a_start_stamp_in_the_future_waits():
    f = follower()
    f.submit("a", replace(goal(Q0 + 0.5, 1.0), start_in_s=0.5))
    outcomes, qs = run(f, 300)
    assert np.max(np.abs(qs[50] - Q0)) < 1e-12  # still holding 0.4 s in
    assert outcomes[0][0] == pytest.approx(188, abs=2)


def test_an_empty_trajectory_stops_and_succeeds():
    f = follower()
    assert f.submit("a", TrajectoryGoal(CONTROLLER_JOINTS, ())) is None
    outcomes, _ = run(f, 10)
    assert [o.status for _, o in outcomes] == ["succeeded"]


def test_a_stopped_program_ends_the_goal_as_each_driver_does_and_refuses_goals_without_a_text():
    for profile, status, text in ((ROS1_SCALED, "preempted", ""),
                                  (ROS2_SCALED, "aborted", "Current goal cancelled during deactivate transition.")):
        f = follower(profile)
        f.submit("a", goal(Q0 + 1.0, 2.0))
        _, qs = run(f, 100, actual=lagging(0.05))
        measured = qs[-2] - 0.05  # what the last cycle read
        f.set_running(False)
        (o,) = f.take_outcomes()
        assert (o.status, o.error_string) == (status, text)
        assert o.code == (ErrorCode.INVALID_GOAL if text else ErrorCode.SUCCESSFUL)
        r = f.submit("b", goal(Q0 + 0.5, 1.0))
        assert r is not None and (r.code, r.error_string) == (ErrorCode.INVALID_GOAL, "")  # ROS 1: no error string
        assert r.reason == "Can't accept new action goals. Controller is not running."
        _, qs = run(f, 20, actual=lambda k, d, m=measured: m)
        np.testing.assert_allclose(qs[-1], measured, atol=1e-12)  # the arm stopped where it was
        f.set_running(True)
        assert f.submit("c", goal(Q0, 1.0, q_start=measured)) is None


def test_ros2_holds_the_measured_position_after_an_abort_not_the_desired_one():
    f = follower(ROS2_SCALED)
    f.submit("a", goal(Q0 + 1.0, 2.0))
    stuck = Q0 + 0.1  # the arm stops 0.1 rad along: the desired position runs 0.2 rad past it
    (_, o), = run(f, 300, actual=lambda k, d: np.minimum(d.q, stuck))[0]
    assert o.code == ErrorCode.PATH_TOLERANCE_VIOLATED
    np.testing.assert_allclose(f.desired.q, stuck, atol=1e-12)
    g = follower(ROS1_SCALED)  # ROS 1 keeps following its trajectory: the contrast
    g.submit("a", goal(Q0 + 1.0, 2.0))
    run(g, 300, actual=lambda k, d: np.minimum(d.q, stuck))
    assert np.max(np.abs(g.desired.q - stuck)) > 0.5


def test_ros2_starts_a_new_goal_from_the_measured_state_ros1_from_the_desired_one():
    for profile, from_measured in ((ROS2_SCALED, True), (ROS1_SCALED, False)):
        f = follower(profile)
        f.submit("a", goal(Q0 + 1.0, 2.0))
        run(f, 100)
        desired = f.desired.q.copy()
        measured = desired - 0.05  # the arm lags 0.05 rad behind
        f.submit("b", TrajectoryGoal(CONTROLLER_JOINTS, (TrajectoryPoint(tuple(Q0), Z, Z, time_from_start_s=2.0),)))
        first = f.update(measured, np.zeros(6), DT, 1.0).q
        start = measured if from_measured else desired
        assert np.max(np.abs(first - start)) < 0.01  # one cycle along the bridge from there
        assert np.max(np.abs(first - (desired if from_measured else measured))) > 0.04


def test_a_single_point_at_zero_seconds_ros2_commands_it_ros1_drops_it():
    near = Q0 + 0.05
    one = TrajectoryGoal(CONTROLLER_JOINTS, (TrajectoryPoint(tuple(near), time_from_start_s=0.0),))
    f = follower(ROS2_SCALED)
    assert f.submit("a", one) is None
    outcomes, qs = run(f, 10)
    np.testing.assert_allclose(qs[0], near, atol=1e-12)  # commanded at once
    assert [o.status for _, o in outcomes] == ["succeeded"]
    f = follower(ROS2_SCALED)  # farther than the path tolerance: aborted on its first sample
    f.submit("a", TrajectoryGoal(CONTROLLER_JOINTS, (TrajectoryPoint(tuple(Q0 + 0.3), time_from_start_s=0.0),)))
    (_, o), = run(f, 3, actual=lambda k, d: Q0.copy())[0]
    assert o.code == ErrorCode.PATH_TOLERANCE_VIOLATED
    r = follower(ROS1_SCALED).submit("a", one)
    assert r is not None and r.error_string.startswith("Dropping all 1 trajectory point(s)")
