"""Publish a list of messages to a running station, then exit (a helper process of the ROS tests).

Usage: ``python tests/ros_publisher.py JSON`` with JSON a list of ``[topic, type, fields]``, type one of
``command`` (ur3_driver/command), ``Int32`` (std_msgs/Int32) or ``String`` (std_msgs/String, a wrong type for
/ur3/command). Waits for a subscriber on every topic first (rospy drops messages published before that), sends the
messages in order 50 ms apart and lets them drain before exiting.
"""

from __future__ import annotations

import json
import sys
import time

from ur3hanoi.ros.env import import_rospy, import_std_msgs
from ur3hanoi.ros.msgs import load_messages


def main() -> int:
    items = json.loads(sys.argv[1])
    rospy, std_msgs, msgs = import_rospy(), import_std_msgs(), load_messages()
    types = {"command": msgs.command, "Int32": std_msgs.Int32, "String": std_msgs.String}
    rospy.init_node("ur3hanoi_test_publisher", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    pubs = {}
    for topic, kind, _fields in items:
        if (topic, kind) not in pubs:
            pubs[topic, kind] = rospy.Publisher(topic, types[kind], queue_size=100)
    deadline = time.monotonic() + 15.0
    wrong_type = {key for key in pubs if key[1] == "String"}  # the station refuses these: no connection to wait for
    while any(p.get_num_connections() == 0 for key, p in pubs.items() if key not in wrong_type):
        if time.monotonic() > deadline:
            print("no subscriber connected within 15 s", file=sys.stderr)
            return 1
        time.sleep(0.02)
    time.sleep(0.3 if wrong_type else 0.0)
    for topic, kind, fields in items:
        pubs[topic, kind].publish(types[kind](**fields))
        time.sleep(0.05)
    time.sleep(0.5)
    rospy.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
