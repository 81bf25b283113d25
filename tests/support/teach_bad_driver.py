"""A driver no UR controller would be: publishes ``ur3/position`` with the JSON list of joint values given (5 of
them, or a NaN) at 50 Hz until killed (a helper process of tests/teach/test_ros.py). Prints ``publishing`` once
registered."""

from __future__ import annotations

import json
import sys
import time

from ur3hanoi.interface.ros1.env import import_rospy
from ur3hanoi.interface.ros1.msgs import load_messages


def main() -> int:
    values = [float(v) for v in json.loads(sys.argv[1])]
    rospy, msgs = import_rospy(), load_messages()
    rospy.init_node("ur3hanoi_test_bad_driver", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    pub = rospy.Publisher("/ur3/position", msgs.position, queue_size=10)
    print("publishing", flush=True)
    while True:
        pub.publish(msgs.position(position=values, isReady=True))
        time.sleep(0.02)


if __name__ == "__main__":
    sys.exit(main())
