"""Publish ``ur3e/command`` to a running ``ros2-station`` over DDS, then exit (a helper process of the ROS 2 tests;
run it only inside the tests' private network namespace, :func:`tests.support.ros2_support.in_netns`).

Usage:

- ``python tests/support/ros2_publisher.py JSON``: JSON is a list of CommandUR3e field dicts (``destination``, ``v``,
  ``a``, ``io_0``). Waits until the station subscribes and publishes its position, sends them in order 100 ms
  apart and waits 0.5 s for them to drain.
- ``python tests/support/ros2_publisher.py --flood HZ SECONDS JSON``: send the field dicts in turn at HZ for SECONDS on
  an
  absolute schedule while reading ``ur3e/position``; prints one JSON line: commands sent, positions received
  during the flood, and the largest gap between received positions [s].
- ``python tests/support/ros2_publisher.py --int TOPIC VALUE...``: publish each VALUE as ``std_msgs/Int32`` on TOPIC
  (``ur3hanoi/spawn``, ``ur3hanoi/remove_block``) once the station subscribes it, 100 ms apart, then wait 0.5 s.
"""

from __future__ import annotations

import itertools
import json
import sys
import time
from typing import Any

from ur3hanoi.interface.ros2.dds import Ros2Node
from ur3hanoi.interface.ros2.msgs import CommandUR3e, Int32, PositionUR3e


def _connect(topic: str = "ur3e/command", msg_type: type = CommandUR3e) -> tuple[Ros2Node, Any, Any]:
    node = Ros2Node("ur3hanoi_test_publisher")
    pub = node.publisher(topic, msg_type)
    positions = node.subscription("ur3e/position", PositionUR3e)
    node.announce()
    deadline = time.monotonic() + 15.0
    seen = False
    while time.monotonic() < deadline:
        seen = seen or bool(positions.take(N=100))
        if seen and pub.get_matched_subscriptions():
            return node, pub, positions
        time.sleep(0.02)
    raise SystemExit(f"no {topic} subscriber or ur3e/position within 15 s")


def _command(fields: dict[str, Any]) -> CommandUR3e:
    return CommandUR3e(destination=[float(x) for x in fields["destination"]], v=float(fields["v"]),
                       a=float(fields["a"]), io_0=bool(fields["io_0"]))


def send(items: list[dict[str, Any]]) -> int:
    node, pub, _ = _connect()
    for fields in items:
        pub.write(_command(fields))
        time.sleep(0.1)
    time.sleep(0.5)
    node.close()
    return 0


def send_int(topic: str, values: list[int]) -> int:
    node, pub, _ = _connect(topic, Int32)
    for value in values:
        pub.write(Int32(data=value))
        time.sleep(0.1)
    time.sleep(0.5)
    node.close()
    return 0


def flood(rate_hz: float, seconds: float, items: list[dict[str, Any]]) -> int:
    node, pub, positions = _connect()
    msgs = [_command(f) for f in items]
    stamps: list[float] = []
    period = 1.0 / rate_hz
    t0 = next_t = time.perf_counter()
    sent = 0
    for msg in itertools.cycle(msgs):
        if next_t - t0 >= seconds:
            break
        pub.write(msg)
        sent += 1
        now = time.perf_counter()
        stamps.extend(now for s in positions.take(N=100) if hasattr(s, "position"))
        next_t += period
        delay = next_t - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    t1 = time.perf_counter()
    during = [t for t in stamps if t0 <= t <= t1]
    gaps = [b - a for a, b in itertools.pairwise([t0, *during, t1])]
    print(json.dumps({"sent": sent, "positions": len(during), "max_gap_s": round(max(gaps), 4)}))
    time.sleep(0.5)
    node.close()
    return 0


if __name__ == "__main__":
    if sys.argv[1] == "--flood":
        sys.exit(flood(float(sys.argv[2]), float(sys.argv[3]), json.loads(sys.argv[4])))
    if sys.argv[1] == "--int":
        sys.exit(send_int(sys.argv[2], [int(v) for v in sys.argv[3:]]))
    sys.exit(send(json.loads(sys.argv[1])))
