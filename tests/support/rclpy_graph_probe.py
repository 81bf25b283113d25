#!/usr/bin/env python
"""Run with a real rclpy: wait (10 s at most) until the node ``ur3hanoi_station`` is in the ROS 2 graph, then print
one JSON object with what the graph says about it (nodes, topics and types, endpoint types, hashes and QoS) and the
first ur3e/position and ur3e/gripper_input samples."""

import json
import time

import rclpy
from rclpy.node import Node
from ur3e_mrc_msgs.msg import GripperInput, PositionUR3e

rclpy.init()
node = Node("graph_probe")
got = {}
node.create_subscription(PositionUR3e, "ur3e/position", lambda m: got.setdefault("position", list(m.position)), 10)
node.create_subscription(GripperInput, "ur3e/gripper_input",
                         lambda m: got.setdefault("gripper", [m.dig_in, m.a_in0, m.a_in1]), 10)
deadline = time.time() + 10.0


def named():
    infos = node.get_publishers_info_by_topic("ur3e/position")
    return infos and all(i.node_name == "ur3hanoi_station" for i in infos)


while time.time() < deadline and not (named() and len(got) == 2):
    rclpy.spin_once(node, timeout_sec=0.05)


def endpoint(info):
    q = info.qos_profile
    return {"node": info.node_name, "type": info.topic_type, "hash": str(info.topic_type_hash),
            "reliability": q.reliability.name, "durability": q.durability.name}


out = {
    "nodes": [n for n, _ in node.get_node_names_and_namespaces()],
    "topics": {t: types for t, types in node.get_topic_names_and_types()},
    "publishers": {t: [endpoint(i) for i in node.get_publishers_info_by_topic(t)]
                   for t in ("ur3e/position", "ur3e/gripper_input", "gripper/grasping")},
    "subscriptions": {"ur3e/command": [endpoint(i) for i in node.get_subscriptions_info_by_topic("ur3e/command")]},
    "samples": got,
}
print(json.dumps(out))
node.destroy_node()
rclpy.shutdown()
