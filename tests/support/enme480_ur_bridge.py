#!/usr/bin/env python
"""The ENME480 (UMD) UR3e course bridge, ported to Python: a client of the official UR ROS 2 driver's interface that
serves the course's topics to student programs. Its behaviour as ``../shared/lab/ros2-interface.md`` ("The course
bridge as its code behaves", read from the 2025 real-arm bridge's C++ source, MarylandRoboticsCenter/ENME480_mrc @
202d608) describes it:

- At start (``ioStartStop(1)``, lines 57-58 and 95-110 of ``ur3e_mrc_enme480_ctrl.cpp``, MarylandRoboticsCenter/
  ENME480_mrc): ``set_io`` the tool voltage to 12 V (``FUN_SET_TOOL_VOLTAGE``, for a laser pointer), then the
  **vacuum generator on**: digital output pin 12 (configurable output 4); both waited for. On exit (line 329,
  ``ioStartStop(0)``): the tool voltage 0 V and pin 12 off, not waited for.
- ``ur3e/command`` (``CommandUR3e``), queue depth 10, one command at a time: commands arriving during a move wait
  and run one after another. A ``destination`` whose length is not 6 is logged and ignored. The suction output
  (digital output 1, through ``set_io``) is switched first, only when ``io_0`` changes; then the destination (course
  convention: + pi/2 on joint 1, - pi/2 on joint 4 to the controller's) goes to the trajectory controller as one
  point exactly 2.0 s away, ``v`` and ``a`` ignored, and the bridge waits for the result. A failed trajectory leaves
  the bridge not ready for good (every later command is only logged).
- ``ur3e/position`` (``PositionUR3e``, course convention, ``is_ready`` always true) once per ``/joint_states``
  message, by joint name; ``ur3e/gripper_input`` (``dig_in`` = digital input 0, ``a_in0`` = analog input 0,
  ``a_in1`` = 0) and ``gripper/grasping`` (digital input 0) once per ``io_states`` message.

Usage: enme480_ur_bridge.py ACTION_NAME     (runs until SIGINT)
"""

import math
import sys
import threading

import rclpy
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup, ReentrantCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Bool
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from ur3e_mrc_msgs.msg import CommandUR3e, GripperInput, PositionUR3e
from ur_msgs.msg import IOStates
from ur_msgs.srv import SetIO

JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]
OFFSET = [math.pi / 2, 0.0, 0.0, -math.pi / 2, 0.0, 0.0]
SUCTION_PIN = 1
GENERATOR_PIN = 12
MOVE_S = 2.0


def wait(future, timeout=30.0):
    done = threading.Event()
    future.add_done_callback(lambda _: done.set())
    done.wait(timeout)
    return future.result() if future.done() else None


class Bridge(Node):
    def __init__(self, action_name):
        super().__init__("ur3e_mrc_bridge")
        others = ReentrantCallbackGroup()
        self.action = ActionClient(self, FollowJointTrajectory, action_name, callback_group=others)
        self.set_io = self.create_client(SetIO, "/io_and_status_controller/set_io", callback_group=others)
        # As the bridge's constructor: the generator on before the course's topics exist (a student's program waits
        # for ur3e/position)
        self.set_io.wait_for_service(timeout_sec=30.0)
        io_start_stop(self, True)  # "Turning ON the vacuum generator"
        self.pub_position = self.create_publisher(PositionUR3e, "ur3e/position", 10)
        self.pub_gripper = self.create_publisher(GripperInput, "ur3e/gripper_input", 10)
        self.pub_grasping = self.create_publisher(Bool, "gripper/grasping", 10)
        self.create_subscription(JointState, "/joint_states", self.on_joints, 10, callback_group=others)
        self.create_subscription(IOStates, "/io_and_status_controller/io_states", self.on_io, 10,
                                 callback_group=others)
        self.create_subscription(CommandUR3e, "ur3e/command", self.on_command, 10,
                                 callback_group=MutuallyExclusiveCallbackGroup())
        self.suction = False
        self.ready = True

    def on_joints(self, msg):
        by_name = dict(zip(msg.name, msg.position, strict=True))
        if all(j in by_name for j in JOINTS):
            self.pub_position.publish(PositionUR3e(
                position=[by_name[j] - o for j, o in zip(JOINTS, OFFSET, strict=True)], is_ready=True))

    def on_io(self, msg):
        dig = bool(msg.digital_in_states[0].state)
        self.pub_gripper.publish(GripperInput(dig_in=int(dig), a_in0=float(msg.analog_in_states[0].state),
                                              a_in1=0.0))
        self.pub_grasping.publish(Bool(data=dig))

    def on_command(self, msg):
        if not self.ready:
            self.get_logger().error("a previous trajectory failed: command ignored")
            return
        if len(msg.destination) != 6:
            self.get_logger().error(f"destination has {len(msg.destination)} values, expected 6: ignored")
            return
        if msg.io_0 != self.suction:
            response = wait(self.set_io.call_async(SetIO.Request(fun=1, pin=SUCTION_PIN,
                                                                 state=1.0 if msg.io_0 else 0.0)))
            self.suction = bool(msg.io_0)
            if response is None or not response.success:
                self.get_logger().error("set_io failed")
        point = JointTrajectoryPoint(positions=[d + o for d, o in zip(msg.destination, OFFSET, strict=True)],
                                     time_from_start=Duration(sec=int(MOVE_S)))
        goal = FollowJointTrajectory.Goal(trajectory=JointTrajectory(joint_names=JOINTS, points=[point]))
        handle = wait(self.action.send_goal_async(goal))
        if handle is None or not handle.accepted:
            self.get_logger().error("trajectory rejected")
            self.ready = False
            return
        response = wait(handle.get_result_async(), 60.0)
        if response is None or response.result.error_code != 0:
            self.get_logger().error(f"trajectory failed: {None if response is None else response.result}")
            self.ready = False


def io_start_stop(bridge, on):
    """The bridge's ``ioStartStop``: the tool voltage (12 V / 0 V), then the vacuum generator's output; waits for
    the answers only when switching on."""
    for fun, pin, state in ((4, 17, 12.0 if on else 0.0), (1, GENERATOR_PIN, 1.0 if on else 0.0)):
        future = bridge.set_io.call_async(SetIO.Request(fun=fun, pin=pin, state=state))
        rclpy.spin_until_future_complete(bridge, future, timeout_sec=5.0 if on else 1.0)
        if on and not (future.done() and future.result().success):
            bridge.get_logger().error("IO Start/Stop failed")


def main():
    rclpy.init()
    bridge = Bridge(sys.argv[1])
    executor = MultiThreadedExecutor(num_threads=4)
    executor.add_node(bridge)
    try:
        executor.spin()
    except KeyboardInterrupt:
        pass
    finally:
        executor.shutdown()
        if rclpy.ok():
            io_start_stop(bridge, False)
        bridge.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
