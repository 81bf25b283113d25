"""The controller manager and controller_stopper of the UR ROS 2 driver, without a middleware: ros2_control's switch
rules and texts, UR's one motion mode, the controllers the program stop deactivates and the start brings back."""

from __future__ import annotations

from ur3hanoi.interface.urdriver.controllers import BEST_EFFORT, STRICT, ControllerManager

SCALED, JTC, PASS = "scaled_joint_trajectory_controller", "joint_trajectory_controller", \
    "passthrough_trajectory_controller"


def states(cm: ControllerManager) -> dict[str, str]:
    return {c.name: state for c, state in cm.listing()}


def test_the_launch_files_states_and_the_trajectory_controller():
    cm = ControllerManager(SCALED)
    s = states(cm)
    assert s[SCALED] == "active" and s[JTC] == s[PASS] == "inactive"
    assert s["joint_state_broadcaster"] == s["io_and_status_controller"] == "active"
    assert cm.trajectory_controller() == SCALED
    lyrical = ControllerManager(JTC)  # scaling built into the plain controller: the scaled one is not loaded
    assert SCALED not in states(lyrical) and lyrical.trajectory_controller() == JTC


def test_switch_strict_and_best_effort_as_ros2_control():
    cm = ControllerManager(SCALED)
    assert cm.switch([PASS], [SCALED], BEST_EFFORT) == (True, "")
    assert cm.trajectory_controller() == PASS
    ok, text = cm.switch([JTC], [], STRICT)  # position and passthrough: one motion mode at a time
    assert not ok and text == "Could not switch controllers since prepare command mode switch was rejected."
    assert cm.switch([SCALED], [PASS], STRICT) == (True, "")
    ok, text = cm.switch([JTC], [], STRICT)  # the same joints' position interfaces
    assert not ok and text.startswith(f"Resource conflict for controller '{JTC}'. Command interface "
                                      "'shoulder_pan_joint/position' is already claimed.")
    assert cm.switch([SCALED], [], STRICT) == (False, f"Could not activate controller '{SCALED}' since it is already "
                                                      "active")
    assert cm.switch([SCALED], [], BEST_EFFORT) == (True, "")  # skipped, nothing to do
    assert cm.switch(["x"], [], STRICT) == (False, "Could not activate controller with name 'x' because no "
                                                   "controller with this name exists")
    assert cm.switch([], [PASS], STRICT)[0] is False and states(cm)[SCALED] == "active"  # nothing changed


def test_the_controller_stopper_keeps_the_consistent_controllers_and_restores_the_others():
    cm = ControllerManager(SCALED)
    cm.program(False)
    s = states(cm)
    assert s[SCALED] == "inactive" and s["io_and_status_controller"] == "active" and cm.trajectory_controller() is None
    cm.program(True)
    assert states(cm)[SCALED] == "active"
