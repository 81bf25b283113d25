"""Clients of the official ROS 1 UR driver, written as others write them, run against ``ros-station --driver ur``.

``python tests/support/ur_driver_clients.py KIND`` runs one and prints one JSON line with what it saw; exit 0 when
every check of that client passed, 1 otherwise:

- ``integration``: a port of the driver's own test client, ``ur_robot_driver/test/integration_test.py``
  (UniversalRobots/Universal_Robots_ROS_Driver master @ 66510fd: ``test_joint_trajectory_position_interface`` and
  ``test_set_io``), with ``actionlib.SimpleActionClient`` and ``rospy.ServiceProxy`` as there. Ported, not copied:
  the robot power cycling, controller switching and the other controllers' tests are left out (the station has one
  controller, always running), the action name is the driver's absolute one, and the slow parts are shortened
  (the first goal's 6 / 9 / 12 s to 2 / 3 / 4 s; the too-fast goals' approach of 6 s to 2 s, their 1 rad in 0.5 s
  kept).
- ``moveit``: what MoveIt's ``FollowJointTrajectory`` controller handler sends: a few points per second, each with
  positions, velocities and accelerations, the first the current state.
- ``bridge``: a course bridge in the style of ECE470's (``movej`` per waypoint) mapped onto the action: one goal per
  waypoint, a single point whose time is the ``movej``'s duration, waiting for each result.
- ``program``: the External Control program stopped mid-goal and started again: the goal preempted, the latched
  ``robot_program_running``, a goal rejected meanwhile (INVALID_GOAL, no error string), one after it runs again.
- ``controllers``: ``controller_manager``'s list, load and switch and the dashboard's stop, play and
  program_running, with the classes :func:`ur3hanoi.interface.ros1.ur_packages.write_ur_packages` writes (the
  folder on ``PYTHONPATH``); leaves the scaled controller stopped for UR's ``test_move`` to switch back.
- ``set-io``: ``set_io`` called with the current Noetic ``ur_msgs/SetIO`` text, with ur_msgs 1.3.x's, and with
  ``md5sum *``; each must switch the output seen in ``io_states``.
"""

from __future__ import annotations

import json
import math
import sys
from typing import Any

import numpy as np

from ur3hanoi.interface.ros1.driver_msgs import load_driver_messages
from ur3hanoi.interface.ros1.env import import_rospy
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ROS1

INTEGRATION_JOINTS = ["elbow_joint", "shoulder_lift_joint", "shoulder_pan_joint", "wrist_1_joint", "wrist_2_joint",
                      "wrist_3_joint"]


def connect() -> tuple[Any, Any, Any]:
    rospy, m = import_rospy(), load_driver_messages()
    import actionlib

    rospy.init_node("ur_driver_test_client", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    client = actionlib.SimpleActionClient(ROS1.follow_joint_trajectory, m.FollowJointTrajectoryAction)
    if not client.wait_for_server(rospy.Duration(30)):
        raise SystemExit("Could not reach controller action. Make sure that the driver is actually running.")
    return rospy, m, client


def point(m: Any, rospy: Any, q: Any, t: float, qd: Any = None, qdd: Any = None) -> Any:
    p = m.JointTrajectoryPoint()
    p.positions = [float(x) for x in q]
    if qd is not None:
        p.velocities = [float(x) for x in qd]
    if qdd is not None:
        p.accelerations = [float(x) for x in qdd]
    p.time_from_start = rospy.Duration(t)
    return p


def send(client: Any, goal: Any) -> tuple[int, str]:
    client.send_goal(goal)
    client.wait_for_result()
    result = client.get_result()
    return int(result.error_code), str(result.error_string)


def integration() -> dict[str, Any]:
    rospy, m, client = connect()
    R = m.FollowJointTrajectoryResult
    seen: dict[str, Any] = {}

    def goal(positions: list[list[float]], durations: list[float], goal_time: float | None = None) -> Any:
        g = m.FollowJointTrajectoryGoal()
        g.trajectory.joint_names = INTEGRATION_JOINTS
        g.trajectory.points = [point(m, rospy, q, t) for q, t in zip(positions, durations, strict=True)]
        if goal_time is not None:
            g.goal_time_tolerance = rospy.Duration(goal_time)
        return g

    # "Test robot movement" (positions only, as the original).
    seen["simple"] = send(client, goal([[0.0] * 6, [-0.5] * 6, [-1.0] * 6], [2.0, 3.0, 4.0]))
    # "Create illegal goal by making the second point come earlier than the first".
    seen["illegal"] = send(client, goal([[0.0] * 6, [-0.5] * 6], [6.0, 3.0]))
    # "Sending scaled goal without time restrictions", then the same with a goal time constraint.
    seen["scaled"] = send(client, goal([[0.0] * 6, [-1.0] * 6], [2.0, 2.5]))
    seen["scaled_tight"] = send(client, goal([[0.0] * 6, [-1.0] * 6], [2.0, 2.5], goal_time=0.01))
    ok = (seen["simple"][0] == R.SUCCESSFUL and seen["illegal"][0] == R.INVALID_GOAL
          and seen["scaled"][0] == R.SUCCESSFUL and seen["scaled_tight"][0] == R.GOAL_TOLERANCE_VIOLATED)
    # test_set_io: pin 0 off then on, each seen in io_states within 5 messages.
    set_io = rospy.ServiceProxy(ROS1.set_io, m.SetIO)
    set_io.wait_for_service(30)
    for state in (0, 1):
        set_io(1, 0, state)
        for _ in range(5):
            io = rospy.wait_for_message(ROS1.io_states, m.IOStates)
            if io.digital_out_states[0].state == bool(state):
                break
        else:
            ok = False
        seen[f"set_io_{state}"] = bool(io.digital_out_states[0].state)
    return {"ok": ok, **seen}


def moveit() -> dict[str, Any]:
    """A joint-space move as MoveIt sends it: 5 points per second with velocities and accelerations."""
    rospy, m, client = connect()
    import sensor_msgs.msg

    js = rospy.wait_for_message(ROS1.joint_states, sensor_msgs.msg.JointState)
    q0 = np.array([js.position[js.name.index(j)] for j in CONTROLLER_JOINTS])
    dq = np.array([0.4, -0.3, 0.3, -0.2, 0.3, 0.5])
    T, n = 2.0, 11  # cosine profile, points every 0.2 s
    g = m.FollowJointTrajectoryGoal()
    g.trajectory.joint_names = list(CONTROLLER_JOINTS)
    for t in np.linspace(0.0, T, n):
        s, ds, dds = (1 - math.cos(math.pi * t / T)) / 2, math.pi / T * math.sin(math.pi * t / T) / 2, \
            (math.pi / T) ** 2 * math.cos(math.pi * t / T) / 2
        g.trajectory.points.append(point(m, rospy, q0 + s * dq, float(t), ds * dq, dds * dq))
    g.trajectory.points[-1].velocities = [0.0] * 6
    code, text = send(client, g)
    js = rospy.wait_for_message(ROS1.joint_states, sensor_msgs.msg.JointState)
    q1 = np.array([js.position[js.name.index(j)] for j in CONTROLLER_JOINTS])
    return {"ok": code == 0 and float(np.max(np.abs(q1 - q0 - dq))) < 0.01, "code": code, "error_string": text,
            "final_error_rad": float(np.max(np.abs(q1 - q0 - dq)))}


def bridge() -> dict[str, Any]:
    """movej per waypoint, as a course bridge does it on the driver: one single-point goal each, in turn."""
    rospy, m, client = connect()
    import sensor_msgs.msg

    js = rospy.wait_for_message(ROS1.joint_states, sensor_msgs.msg.JointState)
    q = np.array([js.position[js.name.index(j)] for j in CONTROLLER_JOINTS])
    home = q.copy()
    codes = []
    for dq in ([0.3, 0, 0, 0, 0, 0], [0, -0.2, 0.2, 0, 0, 0], [0, 0, 0, 0.3, -0.3, 0.5]):
        target = q + np.array(dq)
        duration = max(float(np.max(np.abs(target - q))) / 0.5, 0.5)  # movej's v = 0.5 rad/s
        g = m.FollowJointTrajectoryGoal()
        g.trajectory.joint_names = list(CONTROLLER_JOINTS)
        g.trajectory.points = [point(m, rospy, target, duration, [0.0] * 6)]
        codes.append(send(client, g)[0])
        q = target
    js = rospy.wait_for_message(ROS1.joint_states, sensor_msgs.msg.JointState)
    reached = np.array([js.position[js.name.index(j)] for j in CONTROLLER_JOINTS])
    return {"ok": codes == [0, 0, 0] and float(np.max(np.abs(reached - q))) < 0.01, "codes": codes,
            "moved_rad": float(np.max(np.abs(reached - home)))}


def set_io_versions() -> dict[str, Any]:
    rospy, m = import_rospy(), load_driver_messages()
    rospy.init_node("ur_driver_set_io_client", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    seen = {}
    for name, cls, headers, pin in (("noetic_1.4", m.SetIO, None, 4), ("ur_msgs_1.3", m.SetIO13, None, 5),
                                    ("md5_any", m.SetIO13, {"md5sum": "*"}, 6)):
        proxy = rospy.ServiceProxy(ROS1.set_io, cls, headers=headers)
        proxy.wait_for_service(30)
        success = bool(proxy(1, pin, 1.0).success)
        io = rospy.wait_for_message(ROS1.io_states, m.IOStates)
        io = rospy.wait_for_message(ROS1.io_states, m.IOStates)
        seen[name] = success and bool(io.digital_out_states[pin].state)
    seen["refused_pin_18"] = not bool(rospy.ServiceProxy(ROS1.set_io, m.SetIO)(1, 18, 1.0).success)
    return {"ok": all(seen.values()), **seen}


def program() -> dict[str, Any]:
    """The External Control program stopped mid-goal (ur3hanoi's fault topic, as the pendant's stop button) and
    started again, seen through actionlib and the driver's latched ``robot_program_running``."""
    rospy, m, client = connect()
    import sensor_msgs.msg
    import std_msgs.msg
    from actionlib_msgs.msg import GoalStatus

    def running() -> bool:  # a fresh subscription: the latched value
        return bool(rospy.wait_for_message(ROS1.program_running, std_msgs.msg.Bool, timeout=5.0).data)

    fault = rospy.Publisher("/ur3hanoi/program_running", std_msgs.msg.Bool, queue_size=1)
    end = rospy.get_time() + 5.0
    while fault.get_num_connections() == 0 and rospy.get_time() < end:
        rospy.sleep(0.05)
    js = rospy.wait_for_message(ROS1.joint_states, sensor_msgs.msg.JointState)
    q0 = [js.position[js.name.index(j)] for j in CONTROLLER_JOINTS]

    def goal(dq: float, t: float) -> Any:
        g = m.FollowJointTrajectoryGoal()
        g.trajectory.joint_names = list(CONTROLLER_JOINTS)
        g.trajectory.points = [point(m, rospy, [*q0[:5], q0[5] + dq], t, [0.0] * 6)]
        return g

    seen: dict[str, Any] = {"at_start": running()}
    client.send_goal(goal(0.4, 3.0))
    rospy.sleep(0.5)
    fault.publish(std_msgs.msg.Bool(False))
    client.wait_for_result(rospy.Duration(10))
    seen["stopped_goal"] = client.get_state()
    seen["after_stop"] = running()
    client.send_goal(goal(0.2, 1.0))
    client.wait_for_result(rospy.Duration(10))
    result = client.get_result()
    seen["while_stopped"] = [client.get_state(), int(result.error_code), str(result.error_string)]
    fault.publish(std_msgs.msg.Bool(True))
    rospy.sleep(0.2)
    seen["after_resume"] = running()
    seen["resumed"] = send(client, goal(0.0, 1.5))
    seen["ok"] = (seen["at_start"] and seen["stopped_goal"] == GoalStatus.PREEMPTED and not seen["after_stop"]
                  and seen["while_stopped"] == [GoalStatus.REJECTED, -1, ""] and seen["after_resume"]
                  and seen["resumed"][0] == 0)
    return seen


def controllers() -> dict[str, Any]:
    """The controller manager and the dashboard as UR's ``test_move`` and ``integration_test.py`` call them, with the
    classes ``write_ur_packages`` generates (on ``PYTHONPATH``): list, load, switch; stop and play the program.
    Leaves ``pos_joint_traj_controller`` running and the scaled one stopped, for ``test_move`` to switch back."""
    rospy = import_rospy()
    from controller_manager_msgs.srv import ListControllers, LoadController, SwitchController, SwitchControllerRequest
    from std_srvs.srv import Trigger
    from ur_dashboard_msgs.srv import IsProgramRunning

    rospy.init_node("ur_driver_controllers_client", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    cm, dash = "/controller_manager/", "/ur_hardware_interface/dashboard/"
    for name in ("list_controllers", "load_controller", "switch_controller"):
        rospy.wait_for_service(cm + name, 30)
    listing, load = rospy.ServiceProxy(cm + "list_controllers", ListControllers), \
        rospy.ServiceProxy(cm + "load_controller", LoadController)
    switch = rospy.ServiceProxy(cm + "switch_controller", SwitchController)
    play, stop = rospy.ServiceProxy(dash + "play", Trigger), rospy.ServiceProxy(dash + "stop", Trigger)
    running = rospy.ServiceProxy(dash + "program_running", IsProgramRunning)
    strict, best = SwitchControllerRequest.STRICT, SwitchControllerRequest.BEST_EFFORT

    def states() -> dict[str, str]:
        return {c.name: c.state for c in listing().controller}

    seen: dict[str, Any] = {"initial": states()}
    seen["load_known"] = load("vel_joint_traj_controller").ok
    seen["load_again"] = load("vel_joint_traj_controller").ok
    seen["load_unknown"] = load("no_such_controller").ok
    seen["start_running_strict"] = switch(["scaled_pos_joint_traj_controller"], [], strict, False, 0.0).ok
    seen["two_on_the_joints"] = switch(["pos_joint_traj_controller"], [], strict, False, 0.0).ok
    r = running()
    seen["program"] = [r.success, r.answer, r.program_running]
    s = stop()
    seen["stop"] = [s.success, s.message]
    seen["after_stop"] = states()
    seen["start_while_stopped"] = switch(["pos_joint_traj_controller"], ["scaled_pos_joint_traj_controller"], best,
                                         False, 0.0).ok
    p = play()
    seen["play"] = [p.success, p.message]
    seen["after_play"] = states()
    seen["to_pos"] = switch(["pos_joint_traj_controller"], ["scaled_pos_joint_traj_controller"], strict, False,
                            0.0).ok
    seen["final"] = states()
    seen["ok"] = seen["to_pos"] and seen["final"]["scaled_pos_joint_traj_controller"] == "stopped"
    return seen


if __name__ == "__main__":
    run = {"integration": integration, "moveit": moveit, "bridge": bridge, "set-io": set_io_versions,
           "program": program, "controllers": controllers}[sys.argv[1]]
    out = run()
    print(json.dumps(out))
    sys.exit(0 if out["ok"] else 1)
