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


def test_ros1_load_switch_and_the_hardware_interface_refusing_while_the_program_is_stopped():
    from ur3hanoi.interface.urdriver.controllers import Ros1ControllerManager

    cm = Ros1ControllerManager()
    assert cm.trajectory_controller() == "scaled_pos_joint_traj_controller"
    assert cm.load("vel_joint_traj_controller") and cm.states["vel_joint_traj_controller"] == "initialized"
    assert not cm.load("vel_joint_traj_controller") and "already loaded" in cm.last_error
    assert not cm.switch(["pos_joint_traj_controller"], [], STRICT, True)  # both on the joints
    assert cm.last_error == "Could not switch controllers, due to resource conflict"
    # test_move's switch: BEST_EFFORT, stop a list of which most are not loaded or not running.
    assert cm.switch(["pos_joint_traj_controller"], ["scaled_pos_joint_traj_controller", "twist_controller"],
                     BEST_EFFORT, True)
    assert cm.trajectory_controller() is None  # the stand-in serves the scaled controller's action only
    cm.program(False)
    assert cm.states["pos_joint_traj_controller"] == "stopped" and cm.states["joint_state_controller"] == "running"
    assert not cm.switch(["scaled_pos_joint_traj_controller"], [], BEST_EFFORT, False)
    assert cm.last_error.startswith("Robot control is currently inactive.")
    cm.program(True)
    assert cm.states["pos_joint_traj_controller"] == "running"
