#!/usr/bin/env python
"""The official UR ROS 2 driver's own example and integration-test clients, ported to run against
``ur3hanoi ros2-station --driver ur`` (run with a real rclpy: ``ur3hanoi ros2-env``'s environment).

Ported from UniversalRobots/Universal_Robots_ROS2_Driver, branch jazzy:
``ur_robot_driver/examples/examples.py`` @ e9499954614229f089a672b64cd63c1e2a49c328 (waitForService, waitForAction,
Robot.send_trajectory, Robot.set_io) and ``ur_robot_driver/test/test_common.py`` @
587921676fa4790480aa07411ba80f1aef83e3ab with ``ur_robot_driver/test/integration_test_scaled_joint_controller.py``
and ``integration_test_io_controller.py`` (sjtc_trajectory_test, sjtc_illegal_trajectory_test,
test_trajectory_scaled_aborts_on_violation, test_set_io). Changes: positions are offsets from the station's home
(the originals drive every joint to 0, -0.5, -1 rad, into the table of a Tower of Hanoi cell) and times are shorter;
the checks the originals assert are collected into one JSON line instead of unittest; the controller-manager and
dashboard calls are left out (the station has neither). Added: a goal preempted by another, a cancel, the speed
scaling topic, a last point that still moves, the External Control program stopped mid-goal and started again
(``robot_program_running``, ur3hanoi's fault topic), a single point at t = 0.

Usage: ur_driver_examples.py HOME_JSON ACTION_NAME
"""

import json
import sys
import time

import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

TIMEOUT_WAIT = 10
ROBOT_JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
                "wrist_3_joint"]
STATUS = {4: "SUCCEEDED", 5: "CANCELED", 6: "ABORTED"}


def wait_for_service(node, name, srv_type):
    client = node.create_client(srv_type, name)
    if client.wait_for_service(TIMEOUT_WAIT) is False:
        raise Exception(f"Could not reach service '{name}' within timeout of {TIMEOUT_WAIT}")
    return client


def wait_for_action(node, name, action_type):
    client = ActionClient(node, action_type, name)
    if client.wait_for_server(TIMEOUT_WAIT) is False:
        raise Exception(f"Could not reach action server '{name}' within timeout of {TIMEOUT_WAIT}")
    return client


class Robot:
    def __init__(self, node, action_name):
        self.node = node
        self.set_io_client = wait_for_service(node, "/io_and_status_controller/set_io", SetIO)
        self.jtc = wait_for_action(node, action_name, FollowJointTrajectory)
        self.joint_state = None
        self.io = None
        self.scaling = None
        node.create_subscription(JointState, "/joint_states", self._js, 10)
        node.create_subscription(IOStates, "/io_and_status_controller/io_states", self._io,
                                 rclpy.qos.qos_profile_system_default)
        node.create_subscription(Float64, "/speed_scaling_state_broadcaster/speed_scaling", self._scaling, 10)

    def _js(self, msg):
        self.joint_state = msg

    def _io(self, msg):
        self.io = msg

    def _scaling(self, msg):
        self.scaling = msg.data

    def spin_until(self, done, timeout):
        end = time.time() + timeout
        while not done() and time.time() < end:
            rclpy.spin_once(self.node, timeout_sec=0.01)
        return done()

    def trajectory(self, waypts, times, velocities=None):
        traj = JointTrajectory(joint_names=ROBOT_JOINTS)
        for i, (pos, t) in enumerate(zip(waypts, times, strict=False)):
            point = JointTrajectoryPoint(positions=[float(x) for x in pos],
                                         time_from_start=Duration(sec=int(t), nanosec=round((t % 1) * 1e9)))
            if velocities is not None:
                point.velocities = [float(x) for x in velocities[i]]
            traj.points.append(point)
        return traj

    def send(self, trajectory):
        future = self.jtc.send_goal_async(FollowJointTrajectory.Goal(trajectory=trajectory))
        rclpy.spin_until_future_complete(self.node, future, timeout_sec=TIMEOUT_WAIT)
        return future.result()

    def result(self, goal_handle, timeout=30.0):
        future = goal_handle.get_result_async()
        rclpy.spin_until_future_complete(self.node, future, timeout_sec=timeout)
        response = future.result()
        return {"status": STATUS.get(response.status, response.status), "error_code": response.result.error_code,
                "error_string": response.result.error_string}

    def set_io(self, fun, pin, state):
        future = self.set_io_client.call_async(SetIO.Request(fun=fun, pin=pin, state=state))
        rclpy.spin_until_future_complete(self.node, future, timeout_sec=TIMEOUT_WAIT)
        return future.result().success

    def position(self):
        js = self.joint_state
        return {n: p for n, p in zip(js.name, js.position, strict=False)}

    def at_rest(self, timeout):
        """Spin until the arm has stopped (three positions 0.1 s apart within 1 mrad: two would also match either
        side of an overshoot's turning point), at most ``timeout`` [s]; the seconds waited. An abort or a cancel
        stops the arm within its deceleration limits: from full speed that takes longer than a fixed wait may
        allow."""
        t0, last, still = time.monotonic(), self.position(), 0
        while time.monotonic() - t0 < timeout:
            self.spin_until(lambda: False, 0.1)
            now = self.position()
            still = still + 1 if max(abs(now[j] - last[j]) for j in ROBOT_JOINTS) < 1e-3 else 0
            if still == 2:
                break
            last = now
        return time.monotonic() - t0


def program(robot, node, offset, out):
    """Added: the External Control program stops mid-goal (ur3hanoi's fault topic) and runs again; then a single
    point at t = 0 where the arm is (accepted by the ROS 2 controller)."""
    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    topic = "/io_and_status_controller/robot_program_running"
    state = {}
    node.create_subscription(Bool, topic, lambda m: state.__setitem__("running", m.data), latched)
    fault = node.create_publisher(Bool, "/ur3hanoi/program_running", 10)
    robot.spin_until(lambda: "running" in state and fault.get_subscription_count() > 0, 5.0)
    out["program_at_start"] = state.get("running")
    slow = robot.send(robot.trajectory([offset(-0.4)], [4.0]))
    robot.spin_until(lambda: False, 0.5)
    fault.publish(Bool(data=False))
    out["stopped_goal"] = robot.result(slow)
    robot.spin_until(lambda: state.get("running") is False, 2.0)
    out["program_after_stop"] = state.get("running")
    late = {}
    node.create_subscription(Bool, topic, lambda m: late.setdefault("running", m.data), latched)
    robot.spin_until(lambda: "running" in late, 2.0)
    out["late_subscriber"] = late.get("running")
    out["accepted_while_stopped"] = robot.send(robot.trajectory([offset(-0.3)], [1.0])).accepted
    robot.io = robot.joint_state = None
    robot.spin_until(lambda: robot.io is not None and robot.joint_state is not None, 1.0)
    out["states_while_stopped"] = robot.io is not None and robot.joint_state is not None
    fault.publish(Bool(data=True))
    robot.spin_until(lambda: state.get("running") is True, 2.0)
    out["program_after_resume"] = state.get("running")
    here = robot.position()
    gh = robot.send(robot.trajectory([[here[j] + 0.02 for j in ROBOT_JOINTS]], [0.0]))
    out["t0_point_accepted"] = gh.accepted
    out["t0_point"] = robot.result(gh, 5.0) if gh.accepted else None


def main():
    home = json.loads(sys.argv[1])
    rclpy.init()
    node = Node("robot_driver_test")
    robot = Robot(node, sys.argv[2])
    out = {}
    robot.spin_until(lambda: robot.joint_state is not None and robot.io is not None and robot.scaling is not None, 5)
    out["joint_names"] = list(robot.joint_state.name)
    out["speed_scaling"] = robot.scaling
    by_name = robot.position()
    out["start_error"] = max(abs(by_name[j] - h) for j, h in zip(ROBOT_JOINTS, home, strict=False))

    def offset(d):
        return [h + d for h in home]

    # sjtc_trajectory_test (shorter: 1, 2, 3 s; -0.1 rad steps from home)
    gh = robot.send(robot.trajectory([offset(0.0), offset(-0.1), offset(-0.2)], [1.0, 2.0, 3.0]))
    out["simple_accepted"] = gh.accepted
    t0 = time.time()
    out["simple"] = robot.result(gh)
    out["simple_s"] = time.time() - t0
    robot.spin_until(lambda: False, 0.2)
    by_name = robot.position()
    out["simple_end_error"] = max(abs(by_name[j] - x) for j, x in zip(ROBOT_JOINTS, offset(-0.2), strict=False))

    # sjtc_illegal_trajectory_test: the second point before the first
    gh = robot.send(robot.trajectory([offset(-0.2), offset(-0.1)], [2.0, 1.0]))
    out["illegal_accepted"] = gh.accepted
    # a last point that still moves (rejected from Jazzy on)
    gh = robot.send(robot.trajectory([offset(-0.1)], [1.0], velocities=[[0.1] * 6]))
    out["moving_end_accepted"] = gh.accepted
    # unknown joints
    bad = robot.trajectory([offset(-0.1)], [1.0])
    bad.joint_names = ["joint_a", *ROBOT_JOINTS[1:]]
    out["bad_joints_accepted"] = robot.send(bad).accepted

    # preemption: a slow goal replaced by a new one after 0.5 s
    slow = robot.send(robot.trajectory([offset(-0.5)], [6.0]))
    robot.spin_until(lambda: False, 0.5)
    fresh = robot.send(robot.trajectory([offset(-0.2)], [1.5]))
    out["preempted"] = robot.result(slow)
    out["preempting"] = robot.result(fresh)

    # cancel: the arm decelerates and holds
    slow = robot.send(robot.trajectory([offset(-0.6)], [4.0]))
    robot.spin_until(lambda: False, 1.0)
    cancel = slow.cancel_goal_async()
    rclpy.spin_until_future_complete(node, cancel, timeout_sec=TIMEOUT_WAIT)
    out["cancel_accepted"] = len(cancel.result().goals_canceling) == 1
    out["canceled"] = robot.result(slow)
    robot.spin_until(lambda: False, 0.5)
    held = robot.position()
    robot.spin_until(lambda: False, 1.0)
    later = robot.position()
    out["drift_after_cancel"] = max(abs(later[j] - held[j]) for j in ROBOT_JOINTS)

    # test_trajectory_scaled_aborts_on_violation: a jump the joints cannot follow
    gh = robot.send(robot.trajectory([offset(-0.2), offset(-1.0)], [1.0, 1.05]))
    out["violation"] = robot.result(gh)
    out["stop_after_abort_s"] = robot.at_rest(3.0)
    aborted_at = robot.position()
    robot.spin_until(lambda: False, 1.0)
    after = robot.position()
    out["drift_after_abort"] = max(abs(after[j] - aborted_at[j]) for j in ROBOT_JOINTS)

    # test_set_io (and examples.py's set_io(1, 1.0)): the output reads on io_states when the call returns
    t0 = time.time()
    out["set_io_on"] = robot.set_io(1, 1, 1.0)
    out["set_io_s"] = time.time() - t0
    robot.io = None
    robot.spin_until(lambda: robot.io is not None, 1.0)
    out["do1_after_on"] = robot.io.digital_out_states[1].state
    out["set_io_off"] = robot.set_io(1, 1, 0.0)
    robot.io = None
    robot.spin_until(lambda: robot.io is not None, 1.0)
    out["do1_after_off"] = robot.io.digital_out_states[1].state
    out["set_flag"] = robot.set_io(2, 1, 1.0)
    program(robot, node, offset, out)
    print(json.dumps(out), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
