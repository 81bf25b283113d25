#!/usr/bin/env python
"""A stand-in for the official UR ROS 2 driver that refuses work the way its controller does, written with rclpy's own
action server (run with ``ur3hanoi ros2-env``'s environment): ``/joint_states`` (the arm at HOME, joints in
alphabetical order), ``io_states`` (digital input 0 follows digital output 1, as a vacuum switch would), speed
scaling in percent, ``set_io`` (answers once the output is set), and the trajectory controller's action:

- ``reject``: every goal is refused at send_goal (``accepted = false``, no result, no code), as
  ros2_controllers' ``validate_trajectory_msg`` does;
- ``abort``: goals are accepted and aborted 0.3 s later with PATH_TOLERANCE_VIOLATED (-4) and the controller's text;
- ``stopped``: the External Control program is not running (``robot_program_running`` false, transient local as the
  driver's GPIO controller publishes it) and every goal is refused, as the inactive controller refuses it;
- ``stop-mid``: the program runs; 0.3 s into the first goal it stops: ``robot_program_running`` turns false and the
  goal is aborted with INVALID_GOAL and "Current goal cancelled during deactivate transition." (``on_deactivate``).

At SIGINT it prints one JSON line: the goals received and the ``set_io`` calls. Usage:
ur_driver_standin.py MODE HOME_JSON ACTION_NAME
"""

import json
import signal
import sys
import threading
import time

import rclpy
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool, Float64
from ur_msgs.msg import Analog, Digital, IOStates
from ur_msgs.srv import SetIO

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]


class StandIn(Node):
    def __init__(self, mode, home, action_name):
        super().__init__("ur_driver_standin")
        self.mode, self.home = mode, dict(zip(JOINTS, home, strict=True))
        self.outputs = [False] * 18
        self.goals, self.io_calls = 0, []
        group = ReentrantCallbackGroup()
        self.pub_js = self.create_publisher(JointState, "/joint_states", 10)
        self.pub_io = self.create_publisher(IOStates, "/io_and_status_controller/io_states", 10)
        self.pub_scaling = self.create_publisher(Float64, "/speed_scaling_state_broadcaster/speed_scaling", 10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.pub_program = self.create_publisher(Bool, "/io_and_status_controller/robot_program_running", latched)
        self.pub_program.publish(Bool(data=mode != "stopped"))
        self.create_service(SetIO, "/io_and_status_controller/set_io", self.set_io, callback_group=group)
        ActionServer(self, FollowJointTrajectory, action_name, self.execute, goal_callback=self.on_goal,
                     cancel_callback=lambda _: CancelResponse.ACCEPT, callback_group=group)
        self.create_timer(0.008, self.publish, callback_group=group)

    def publish(self):
        names = sorted(JOINTS)
        self.pub_js.publish(JointState(name=names, position=[self.home[j] for j in names], velocity=[0.0] * 6,
                                       effort=[0.0] * 6))
        inputs = [False] * 18
        inputs[0] = self.outputs[1]
        self.pub_io.publish(IOStates(
            digital_in_states=[Digital(pin=i, state=s) for i, s in enumerate(inputs)],
            digital_out_states=[Digital(pin=i, state=s) for i, s in enumerate(self.outputs)],
            analog_in_states=[Analog(pin=i, domain=1, state=0.0) for i in range(2)],
            analog_out_states=[Analog(pin=i, domain=1, state=0.0) for i in range(2)]))
        self.pub_scaling.publish(Float64(data=100.0))

    def set_io(self, request, response):
        self.io_calls.append([request.fun, request.pin, request.state])
        if request.fun == 1 and 0 <= request.pin < 18:
            self.outputs[request.pin] = request.state != 0.0
            time.sleep(0.05)
            response.success = True
        else:
            response.success = False
        return response

    def on_goal(self, _goal):
        self.goals += 1
        return GoalResponse.REJECT if self.mode in ("reject", "stopped") else GoalResponse.ACCEPT

    def execute(self, handle):
        time.sleep(0.3)
        handle.abort()
        if self.mode == "stop-mid":
            self.pub_program.publish(Bool(data=False))
            return FollowJointTrajectory.Result(error_code=FollowJointTrajectory.Result.INVALID_GOAL,
                                                error_string="Current goal cancelled during deactivate transition.")
        return FollowJointTrajectory.Result(error_code=FollowJointTrajectory.Result.PATH_TOLERANCE_VIOLATED,
                                            error_string="Aborted due to path tolerance violation")


def main():
    from rclpy.signals import SignalHandlerOptions

    rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
    signal.signal(signal.SIGINT, signal.default_int_handler)  # a script's background job starts with it ignored
    node = StandIn(sys.argv[1], json.loads(sys.argv[2]), sys.argv[3])
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    print("ur3hanoi ros2-station: ready (stand-in)", file=sys.stderr, flush=True)  # as the station: stdout = report
    try:
        while True:
            time.sleep(0.1)
    except KeyboardInterrupt:
        pass
    print(json.dumps({"goals": node.goals, "io_calls": node.io_calls}), flush=True)
    executor.shutdown()
    node.destroy_node()
    rclpy.try_shutdown()


if __name__ == "__main__":
    main()
