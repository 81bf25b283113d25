"""How the client words a goal's end: the driver's code and error string, or where to look when there is none."""

from __future__ import annotations

from ur3hanoi.interface.urdriver.client import GoalResult


def test_results_carry_the_drivers_code_and_string():
    assert GoalResult("aborted", -4, "shoulder_pan_joint path error 0.250000").describe() == \
        'aborted: PATH_TOLERANCE_VIOLATED (-4) "shoulder_pan_joint path error 0.250000"'
    assert GoalResult("rejected", -2, "").describe() == "rejected: INVALID_JOINTS (-2) (no error string)"
    assert GoalResult("aborted", 7, "x").describe() == 'aborted: error code 7 "x"'
    assert GoalResult("succeeded", 0, "").describe() == "succeeded: SUCCESSFUL (0)"
    assert GoalResult("canceled").describe() == "canceled"
    assert GoalResult("rejected").describe() == "rejected at send_goal (the ROS 2 driver gives no code: its log " \
                                                "says why)"


def test_a_preempted_goal_names_the_likely_causes():
    assert "does the robot program run on the pendant?" in GoalResult("preempted").describe()
