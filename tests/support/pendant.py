"""The pendant's play and stop, as UR's ROS 2 driver offers them (``/dashboard_client/play``,
``/dashboard_client/stop``, ``std_srvs/srv/Trigger``): ``python -m tests.support.pendant play|stop`` with rclpy (run
it in the ``ros2-env`` environment); prints the dashboard's answer and exits 0 when it succeeded."""

from __future__ import annotations

import sys


def main() -> int:
    from ur3hanoi.interface.ros2.rclpy_env import import_interfaces, import_rclpy

    rclpy = import_rclpy()
    (std_srvs,) = import_interfaces("std_srvs.srv")
    rclpy.init()
    node = rclpy.create_node("pendant")
    try:
        client = node.create_client(std_srvs.Trigger, f"/dashboard_client/{sys.argv[1]}")
        if not client.wait_for_service(timeout_sec=10.0):
            print("no dashboard", file=sys.stderr)
            return 1
        future = client.call_async(std_srvs.Trigger.Request())
        rclpy.spin_until_future_complete(node, future, timeout_sec=10.0)
        answer = future.result()
        print(answer.message if answer is not None else "no answer")
        return 0 if answer is not None and answer.success else 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    raise SystemExit(main())
