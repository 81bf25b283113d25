#!/usr/bin/env python
"""A client that sends what MoveIt's ``moveit_simple_controller_manager`` sends the UR driver: one
``FollowJointTrajectory`` goal per plan, its first point the current state at ``time_from_start`` 0, then a few
points per second (here 4) with positions, velocities and accelerations from a time-parameterized path (a quintic
blend, zero velocity and acceleration at both ends), joints in the controller's order. It follows the action's
feedback while the goal runs and prints one JSON line: the result, the wall time, the largest |desired - actual|
the feedback reported, and the end position error. Written for the tests of ``ros2-station --driver ur``.

Usage: moveit_style_client.py HOME_JSON ACTION_NAME DURATION_S
"""

import json
import sys
import time

import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]
STEP = [0.4, -0.2, 0.3, -0.3, 0.2, 0.5]  # [rad] from home


def quintic(s):
    """Position, velocity and acceleration factors of a rest-to-rest quintic at phase s in [0, 1]."""
    return (10 * s**3 - 15 * s**4 + 6 * s**5, 30 * s**2 - 60 * s**3 + 30 * s**4, 60 * s - 180 * s**2 + 120 * s**3)


def main():
    home, action_name, duration = json.loads(sys.argv[1]), sys.argv[2], float(sys.argv[3])
    rclpy.init()
    node = Node("moveit_style_client")
    state = {}
    node.create_subscription(JointState, "/joint_states",
                             lambda m: state.update(dict(zip(m.name, m.position, strict=False))), 10)
    client = ActionClient(node, FollowJointTrajectory, action_name)
    assert client.wait_for_server(10.0)
    end = time.time() + 5
    while len(state) < 6 and time.time() < end:
        rclpy.spin_once(node, timeout_sec=0.01)
    start = [state[j] for j in JOINTS]
    target = [h + d for h, d in zip(home, STEP, strict=False)]
    traj = JointTrajectory(joint_names=JOINTS)
    n = round(duration * 4)
    for k in range(n + 1):
        t = duration * k / n
        p, v, a = quintic(k / n)
        point = JointTrajectoryPoint(
            positions=[s0 + (g - s0) * p for s0, g in zip(start, target, strict=False)],
            velocities=[(g - s0) * v / duration for s0, g in zip(start, target, strict=False)],
            accelerations=[(g - s0) * a / duration**2 for s0, g in zip(start, target, strict=False)],
            time_from_start=Duration(sec=int(t), nanosec=round((t % 1) * 1e9)))
        traj.points.append(point)
    worst = [0.0]

    def feedback(msg):
        fb = msg.feedback
        worst[0] = max([worst[0], *(abs(e) for e in fb.error.positions)])

    t0 = time.time()
    sent = client.send_goal_async(FollowJointTrajectory.Goal(trajectory=traj), feedback_callback=feedback)
    rclpy.spin_until_future_complete(node, sent, timeout_sec=10.0)
    handle = sent.result()
    result = handle.get_result_async()
    rclpy.spin_until_future_complete(node, result, timeout_sec=duration + 20.0)
    wall = time.time() - t0
    for _ in range(20):
        rclpy.spin_once(node, timeout_sec=0.01)
    response = result.result()
    print(json.dumps({"accepted": handle.accepted, "points": len(traj.points), "status": response.status,
                      "error_code": response.result.error_code, "error_string": response.result.error_string,
                      "wall_s": wall, "max_feedback_error": worst[0],
                      "end_error": max(abs(state[j] - g) for j, g in zip(JOINTS, target, strict=False))}), flush=True)
    node.destroy_node()
    rclpy.shutdown()


if __name__ == "__main__":
    main()
