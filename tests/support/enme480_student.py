#!/usr/bin/env python
"""A Tower of Hanoi program written the way an ENME480 (UMD, ROS 2, UR3e) student writes one: an rclpy node with
globals set by subscriber callbacks, ``CommandUR3e`` published on ``ur3e/command``, a wait until every joint of
``ur3e/position`` is within 0.0008 rad, ``GripperInput.dig_in`` read after each grasp. On a missing block it halts:
suction off, home, error, exit 1. Joint values are in the course bridge's convention (the table comes from
``ur3hanoi tables ur3e_sim --convention course``). Runs in the throwaway rclpy environment of
``tests/support/rclpy_support.py`` against ``ur3hanoi ros2-station``.
"""

import sys
import time

import rclpy
import yaml
from rclpy.node import Node
from ur3e_mrc_msgs.msg import CommandUR3e, GripperInput, PositionUR3e

TOL = 0.0008
thetas = None
dig_in = 0
a_in0 = 0.0


def position_callback(msg):
    global thetas
    thetas = list(msg.position)


def gripper_callback(msg):
    global dig_in, a_in0
    dig_in = msg.dig_in
    a_in0 = msg.a_in0


class Student(Node):
    def __init__(self):
        super().__init__("enme480_student")
        self.pub = self.create_publisher(CommandUR3e, "ur3e/command", 10)
        self.create_subscription(PositionUR3e, "ur3e/position", position_callback, 10)
        self.create_subscription(GripperInput, "ur3e/gripper_input", gripper_callback, 10)
        self.suction = False
        self.dest = None

    def spin_for(self, seconds):
        end = time.time() + seconds
        while time.time() < end:
            rclpy.spin_once(self, timeout_sec=0.01)

    def move(self, dest):
        msg = CommandUR3e()
        msg.destination = [float(x) for x in dest]
        msg.v = 1.0
        msg.a = 1.0
        msg.io_0 = self.suction
        self.pub.publish(msg)
        self.dest = list(dest)
        start = time.time()
        while True:
            rclpy.spin_once(self, timeout_sec=0.01)
            if thetas is not None and all(abs(t - d) < TOL for t, d in zip(thetas, dest, strict=True)):
                return
            if time.time() - start > 30:
                raise RuntimeError("move timed out")

    def gripper(self, on):
        self.suction = on
        self.move(self.dest if self.dest is not None else thetas)


def main():
    table, start, end = sys.argv[1], int(sys.argv[2]) - 1, int(sys.argv[3]) - 1
    with open(table) as f:
        Q = yaml.safe_load(f)["sim_pos"]
    home = [float(x) for x in sys.argv[4].split(",")]
    n_blocks = int(sys.argv[5]) if len(sys.argv) > 5 else 3  # the lab's 3; fewer to keep a test short
    rclpy.init()
    node = Student()
    while thetas is None:
        rclpy.spin_once(node, timeout_sec=0.1)
    node.move(home)
    heights = [0, 0, 0]
    heights[start] = n_blocks
    via = 3 - start - end

    def move_block(src, dst):
        h_src, h_dst = heights[src] - 1, heights[dst]
        node.move(Q[src][h_src][1])
        node.move(Q[src][h_src][0])
        node.gripper(True)
        node.spin_for(1.0)
        if (dig_in & 1) == 0:
            node.gripper(False)
            node.move(home)
            print(f"Block not found at tower {src + 1} height {h_src + 1} (a_in0 = {a_in0:.3f} V)", file=sys.stderr)
            return 1
        node.move(Q[src][h_src][1])
        node.move(Q[dst][h_dst][1])
        node.move(Q[dst][h_dst][0])
        node.gripper(False)
        node.spin_for(0.5)
        node.move(Q[dst][h_dst][1])
        heights[src] -= 1
        heights[dst] += 1
        return 0

    def solve(n, src, dst, via):
        if n == 0:
            return 0
        return solve(n - 1, src, via, dst) or move_block(src, dst) or solve(n - 1, via, dst, src)

    error = solve(n_blocks, start, end, via)
    node.move(home)
    node.destroy_node()
    rclpy.shutdown()
    sys.exit(1 if error else 0)


if __name__ == "__main__":
    main()
