"""Publish to a running station, then exit (a helper process of the ROS tests and of bench/bench_ros.py).

Usage:

- ``python tests/support/ros_publisher.py JSON`` with JSON a list of ``[topic, type, fields]``, type one of ``command``
  (ur3_driver/command), ``Int32`` (std_msgs/Int32), ``Bool`` (std_msgs/Bool) or ``String`` (std_msgs/String, a
  wrong type for
  /ur3/command). Waits for a subscriber on every topic first (rospy drops messages published before that), sends
  the messages in order 50 ms apart and lets them drain before exiting.
- ``python tests/support/ros_publisher.py --flood HZ SECONDS JSON_FIELDS``: publish the ``command`` JSON_FIELDS (a list
  of
  field dicts, sent in turn) at HZ for SECONDS on an absolute schedule while subscribing ``/ur3/position``; prints
  one JSON line: commands sent, positions received, and the largest gap between received positions [s] during the
  flood.
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from typing import Any

from ur3hanoi.interface.ros1.env import import_rospy, import_std_msgs
from ur3hanoi.interface.ros1.msgs import load_messages


def _wait_for(pubs: dict[Any, Any], skip: set[Any], timeout_s: float = 15.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while any(p.get_num_connections() == 0 for key, p in pubs.items() if key not in skip):
        if time.monotonic() > deadline:
            print(f"no subscriber connected within {timeout_s:g} s", file=sys.stderr)
            return False
        time.sleep(0.02)
    return True


def flood(rate_hz: float, seconds: float, fields: list[dict[str, Any]]) -> int:
    rospy, msgs = import_rospy(), load_messages()
    rospy.init_node("ur3hanoi_test_flood", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    stamps: list[float] = []
    rospy.Subscriber("/ur3/position", msgs.position, lambda _m: stamps.append(time.perf_counter()), queue_size=1000)
    pub = rospy.Publisher("/ur3/command", msgs.command, queue_size=1000)
    if not _wait_for({"c": pub}, set()):
        return 1
    deadline = time.monotonic() + 15.0
    while not stamps and time.monotonic() < deadline:
        time.sleep(0.01)
    period = 1.0 / rate_hz
    t0 = next_t = time.perf_counter()
    sent = 0
    while next_t - t0 < seconds:
        pub.publish(msgs.command(**fields[sent % len(fields)]))
        sent += 1
        next_t += period
        delay = next_t - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    t1 = time.perf_counter()
    time.sleep(0.5)
    during = [t for t in stamps if t0 <= t <= t1]
    gaps = [b - a for a, b in itertools.pairwise([t0, *during, t1])]  # a station that stops publishing shows
    print(json.dumps({"sent": sent, "seconds": round(t1 - t0, 3), "positions": len(during),
                      "max_gap_s": round(max(gaps), 6) if gaps else None}), flush=True)
    rospy.signal_shutdown("done")
    return 0


def main() -> int:
    if sys.argv[1] == "--flood":
        return flood(float(sys.argv[2]), float(sys.argv[3]), json.loads(sys.argv[4]))
    items = json.loads(sys.argv[1])
    rospy, std_msgs, msgs = import_rospy(), import_std_msgs(), load_messages()
    types = {"command": msgs.command, "Int32": std_msgs.Int32, "String": std_msgs.String, "Bool": std_msgs.Bool}
    rospy.init_node("ur3hanoi_test_publisher", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
    pubs = {}
    for topic, kind, _fields in items:
        if (topic, kind) not in pubs:
            pubs[topic, kind] = rospy.Publisher(topic, types[kind], queue_size=100)
    wrong_type = {key for key in pubs if key[1] == "String"}  # the station refuses these: no connection to wait for
    if not _wait_for(pubs, wrong_type):
        return 1
    time.sleep(0.3 if wrong_type else 0.0)
    for topic, kind, fields in items:
        pubs[topic, kind].publish(types[kind](**fields))
        time.sleep(0.05)
    time.sleep(0.5)
    rospy.signal_shutdown("done")
    return 0


if __name__ == "__main__":
    sys.exit(main())
